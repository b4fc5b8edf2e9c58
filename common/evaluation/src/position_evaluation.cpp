#include "ssl_formation/evaluation/position_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::evaluation {

namespace {

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Index of the entry of `items` (sorted by time) nearest `time_s`, if within `tolerance_s`.
template <typename Items, typename TimeOf>
std::optional<std::size_t> nearest_index(const Items& items, double time_s, double tolerance_s,
                                         TimeOf time_of) {
  if (items.empty()) return std::nullopt;
  const auto after = std::lower_bound(
      items.begin(), items.end(), time_s,
      [&](const auto& item, double t) { return time_of(item) < t; });
  std::optional<std::size_t> best;
  double best_gap = tolerance_s;
  const auto consider = [&](auto it) {
    const double gap = std::abs(time_of(*it) - time_s);
    if (gap <= best_gap) {
      best_gap = gap;
      best = static_cast<std::size_t>(it - items.begin());
    }
  };
  if (after != items.begin()) consider(after - 1);  // the earlier wins a tie
  if (after != items.end()) consider(after);
  return best;
}

}  // namespace

void RobotTracks::add(const Formation& formation) {
  const double t = formation.time_s;
  for (const FormationRobot& robot : formation.robots) {
    if (robot.robot_id >= by_id_.size()) {
      by_id_.resize(robot.robot_id + 1);
      followed_.resize(robot.robot_id + 1);
    }
    Followed& followed = followed_[robot.robot_id];
    RobotTracker& tracker = followed.tracker;
    if (robot.observed) {
      // A robot carried over from an earlier frame (not observed) tells the tracker nothing. A
      // jump starts a new track here as in MotionHistory (time going back and long gaps the
      // tracker handles itself).
      if (tracker.observations() > 0 &&
          MotionFeatures::is_jump(followed.last_position, tracker.last_s(), robot.feed_position,
                                  t)) {
        tracker.reset();
      }
      tracker.observe(t, robot.feed_position);
      followed.last_position = robot.feed_position;
    }
    Seen seen{t, robot.feed_position, {}, std::nullopt};
    if (tracker.observations() >= 2) {
      seen.velocity = tracker.velocity();
      seen.tracked_since_s = tracker.first_s();
    }
    by_id_[robot.robot_id].push_back(seen);
  }
}

std::optional<RobotTracks::Seen> RobotTracks::nearest(std::uint32_t robot_id, double time_s,
                                                      double tolerance_s) const {
  if (robot_id >= by_id_.size()) return std::nullopt;
  const std::vector<Seen>& track = by_id_[robot_id];
  const auto index =
      nearest_index(track, time_s, tolerance_s, [](const Seen& s) { return s.time_s; });
  if (!index) return std::nullopt;
  return track[*index];
}

std::optional<Point> RobotTracks::velocity(std::uint32_t robot_id, double time_s, double window_s,
                                           double tolerance_s) const {
  const auto now = nearest(robot_id, time_s, tolerance_s);
  if (!now || !now->tracked_since_s || !(now->time_s - *now->tracked_since_s > window_s / 2.0)) {
    return std::nullopt;
  }
  return now->velocity;
}

double ErrorStats::mean() const {
  if (errors_.empty()) return 0.0;
  return std::accumulate(errors_.begin(), errors_.end(), 0.0) /
         static_cast<double>(errors_.size());
}

double ErrorStats::percentile(double p) const {
  if (errors_.empty()) return 0.0;
  std::sort(errors_.begin(), errors_.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(errors_.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(rank));
  const std::size_t above = std::min(below + 1, errors_.size() - 1);
  const double fraction = rank - static_cast<double>(below);
  return errors_[below] + fraction * (errors_[above] - errors_[below]);
}

void DampingFit::add(Point displacement, Point extrapolated) {
  dot_ += displacement.x * extrapolated.x + displacement.y * extrapolated.y;
  norm_ += extrapolated.x * extrapolated.x + extrapolated.y * extrapolated.y;
}

double DampingFit::factor() const { return norm_ > 0.0 ? dot_ / norm_ : 1.0; }

std::string_view to_string(PositionMethod method) {
  switch (method) {
    case PositionMethod::model:
      return "model";
    case PositionMethod::persistence:
      return "persistence";
    case PositionMethod::constant_velocity:
      return "constant velocity";
    case PositionMethod::damped_constant_velocity:
      return "damped constant velocity";
  }
  return "?";
}

const Formation* formation_near(const std::vector<Formation>& formations, double time_s,
                                double tolerance_s) {
  const auto index = nearest_index(formations, time_s, tolerance_s,
                                   [](const Formation& f) { return f.time_s; });
  return index ? &formations[*index] : nullptr;
}

void score_instant(HorizonScore& score, const PositionSetup& setup, const RobotTracks& tracks,
                   const Formation& now, const PredictedStep& model, const Formation& truth,
                   double damping) {
  const Grid& grid = setup.codec->grid();
  const AttackDirection attacks = now.opponent_attacks;
  const auto cell_of_feed = [&](Point feed) {
    return grid.cell_of(normalise(feed, attacks), setup.field);
  };
  // Each method's predicted feed position per robot of `now`, on the robots the truth holds.
  struct Guess {
    const FormationRobot* robot;
    const FormationRobot* truth;
    const RobotPrediction* model;
    std::array<Point, 4> position;
  };
  std::vector<Guess> guesses;
  for (const FormationRobot& robot : now.robots) {
    const FormationRobot* actual = truth.find(robot.robot_id);
    if (!actual) continue;
    const auto model_robot =
        std::find_if(model.robots.begin(), model.robots.end(),
                     [&](const RobotPrediction& r) { return r.robot_id == robot.robot_id; });
    if (model_robot == model.robots.end()) continue;
    Guess guess{&robot, actual, &*model_robot, {}};
    // The model's position in feed coordinates (for the paper's model, its cell's centre).
    guess.position[0] = model_robot->feed_position;
    guess.position[1] = robot.feed_position;
    const std::optional<Point> v =
        tracks.velocity(robot.robot_id, now.time_s, setup.velocity_window_s, setup.tolerance_s);
    const Point step = v ? Point{v->x * score.horizon_s, v->y * score.horizon_s} : Point{};
    guess.position[2] = {robot.feed_position.x + step.x, robot.feed_position.y + step.y};
    guess.position[3] = {robot.feed_position.x + damping * step.x,
                         robot.feed_position.y + damping * step.y};
    guesses.push_back(guess);
  }
  if (guesses.empty()) return;

  bool every_cell_right = true;
  for (std::size_t m = 0; m < all_position_methods.size(); ++m) {
    // The baselines' predicted centroid: the cell of the mean of their predicted positions.
    Point sum{};
    for (const Guess& g : guesses) {
      const Point p = normalise(g.position[m], attacks);
      sum.x += p.x;
      sum.y += p.y;
    }
    const double n = static_cast<double>(guesses.size());
    const Cell centroid = grid.cell_of(Point{sum.x / n, sum.y / n}, setup.field);
    Accuracy& accuracy = score.cells[m];
    ++accuracy.formations;
    for (const Guess& g : guesses) {
      const double error = distance(g.position[m], g.truth->feed_position);
      score.error[m].add(error);
      if (m == 0 && g.model->radius90_mm > 0.0) {
        ++score.radii.robots;
        if (error <= g.model->radius50_mm) ++score.radii.within50;
        if (error <= g.model->radius90_mm) ++score.radii.within90;
      }
      const Cell predicted_cell =
          m == 0 ? g.model->position : cell_of_feed(g.position[m]);
      const StateIndex predicted_state =
          m == 0 ? g.model->state
                 : setup.codec->encode(RobotState{centroid, predicted_cell, g.robot->cell});
      const Cell actual_cell = g.truth->cell;
      ++accuracy.robots;
      if (predicted_state == g.truth->state) ++accuracy.exact_states;
      if (predicted_cell == actual_cell) ++accuracy.exact_cells;
      accuracy.cell_distance += static_cast<std::uint64_t>(std::abs(predicted_cell.x - actual_cell.x) +
                                                           std::abs(predicted_cell.y - actual_cell.y));
      if (m == 0) {
        const bool right = predicted_cell == actual_cell;
        score.robot.add(g.model->probability, right);
        every_cell_right = every_cell_right && right;
      }
    }
  }
  score.formation.add(model.formation_probability, every_cell_right);
}

void fit_damping(DampingFit& fit, const PositionSetup& setup, const RobotTracks& tracks,
                 const std::vector<Formation>& formations, double horizon_s) {
  for (const Formation& now : formations) {
    const Formation* later = formation_near(formations, now.time_s + horizon_s, setup.tolerance_s);
    if (!later) continue;
    for (const FormationRobot& robot : now.robots) {
      const FormationRobot* after = later->find(robot.robot_id);
      if (!after) continue;
      const std::optional<Point> v =
          tracks.velocity(robot.robot_id, now.time_s, setup.velocity_window_s, setup.tolerance_s);
      // A jump before `later` (a ghost there) is no displacement to fit the damping to.
      if (!v || MotionFeatures::is_jump(robot.feed_position, now.time_s, after->feed_position,
                                        later->time_s)) {
        continue;
      }
      fit.add({after->feed_position.x - robot.feed_position.x,
               after->feed_position.y - robot.feed_position.y},
              {v->x * horizon_s, v->y * horizon_s});
    }
  }
}

namespace {

// Every position the stream shows of each robot, frame by frame, whatever the model's sampling:
// the baselines' velocities come from the robots' own observed positions.
RobotTracks observed_tracks(const SamplerConfig& model, const std::vector<SSL_WrapperPacket>& stream) {
  SamplerConfig every_frame = model;
  every_frame.sampling = Sampling::frame;
  RobotTracks tracks;
  FormationSampler sampler(every_frame,
                           [&](const FormationSample& sample) { tracks.add(sample.formation); });
  for (const SSL_WrapperPacket& packet : stream) sampler.add(packet);
  return tracks;
}

}  // namespace

PositionEvaluation evaluate_positions(const PositionEvaluationConfig& config,
                                      const std::vector<std::vector<SSL_WrapperPacket>>& train,
                                      const std::vector<std::vector<SSL_WrapperPacket>>& test) {
  PositionEvaluation result;
  const double step_s = config.sampler.step_s;
  const auto horizon_s = [&](int k) { return static_cast<double>(k) * step_s; };
  PositionSetup setup;
  setup.velocity_window_s = config.velocity_window_s;
  setup.tolerance_s = config.tolerance_s;

  // Training: the table, and the training streams' own formations for the damping fit.
  std::optional<MotionTable> motion;
  if (config.model == ModelKind::motion) {
    MotionConfig motion_config;
    motion_config.step_s = step_s;
    motion_config.horizons = config.steps;
    motion.emplace(motion_config);
  }
  Training training(config.sampler, TransitionTable(config.sampler.grid), 0, std::move(motion));
  std::vector<DampingFit> fits(static_cast<std::size_t>(config.steps));
  for (const auto& stream : train) {
    training.start_new_stream();
    for (const SSL_WrapperPacket& packet : stream) training.add(packet);
    std::vector<Formation> formations;
    FormationSampler sampler(config.sampler, [&](const FormationSample& sample) {
      formations.push_back(sample.formation);
    });
    for (const SSL_WrapperPacket& packet : stream) sampler.add(packet);
    const RobotTracks tracks = observed_tracks(config.sampler, stream);
    for (int k = 1; k <= config.steps; ++k) {
      fit_damping(fits[static_cast<std::size_t>(k - 1)], setup, tracks, formations, horizon_s(k));
    }
  }
  for (const DampingFit& fit : fits) result.damping.push_back(fit.factor());
  result.train_formations = training.samples();
  result.transitions = training.table().transitions();
  result.table_memory_bytes = training.table().memory_bytes();
  TableMetadata metadata;
  metadata.field = training.sampler().field();
  metadata.step_s = step_s;
  metadata.samples = training.samples();
  const auto table = std::make_shared<const StoredTable>(
      StoredTable{training.table(), metadata, training.motion()});
  if (training.motion()) result.table_memory_bytes += training.motion()->memory_bytes();
  setup.codec = &table->table.codec();
  result.table = table;

  for (int k = 1; k <= config.steps; ++k) {
    result.horizons.emplace_back();
    result.horizons.back().horizon_s = horizon_s(k);
  }
  PredictionConfig prediction;
  prediction.sampler = config.sampler;
  prediction.horizon = config.steps;
  prediction.model = config.model;
  prediction.recalibration = config.recalibration;
  for (const auto& stream : test) {
    std::vector<Formation> formations;
    std::vector<std::vector<PredictedStep>> predicted;
    PredictionPipeline pipeline(prediction, [&](const PredictedFormation& p) {
      formations.push_back(p.formation());
      predicted.push_back(p.prediction.steps);
    });
    pipeline.set_table(table);
    for (const SSL_WrapperPacket& packet : stream) pipeline.add(packet);
    const RobotTracks tracks = observed_tracks(config.sampler, stream);
    setup.field = pipeline.sampler().field();
    result.test_formations += formations.size();
    for (std::size_t i = 0; i < formations.size(); ++i) {
      for (int k = 1; k <= config.steps; ++k) {
        const auto h = static_cast<std::size_t>(k - 1);
        const Formation* truth =
            formation_near(formations, formations[i].time_s + horizon_s(k), config.tolerance_s);
        if (!truth || h >= predicted[i].size()) continue;
        score_instant(result.horizons[h], setup, tracks, formations[i], predicted[i][h], *truth,
                      result.damping[h]);
      }
    }
  }
  return result;
}

double expected_calibration_error(const Calibration& calibration) {
  if (calibration.n == 0) return 0.0;
  double sum = 0.0;
  for (std::size_t b = 0; b < calibration.bin_count.size(); ++b) {
    const std::uint64_t count = calibration.bin_count[b];
    if (count == 0) continue;
    const double observed = static_cast<double>(calibration.bin_hits[b]) / static_cast<double>(count);
    const double confidence = calibration.bin_confidence[b] / static_cast<double>(count);
    sum += static_cast<double>(count) * std::abs(observed - confidence);
  }
  return sum / static_cast<double>(calibration.n);
}

}  // namespace ssl_formation::evaluation
