#include "baselines.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace models {

// ---- BaselineTracks -------------------------------------------------------------------------

BaselineTracks::BaselineTracks(double velocity_window_s, double keep_s)
    : velocity_window_s_(velocity_window_s), keep_s_(keep_s) {}

void BaselineTracks::clear() {
  tracks_.clear();
  last_time_s_.reset();
}

void BaselineTracks::add(const Formation& formation) {
  const double t = formation.time_s;
  // Records kept in time order and on one side: a clock going back or a change of ends starts
  // over (the positions before and after do not compare).
  if (last_time_s_ && (t <= *last_time_s_ || formation.opponent_attacks != attacks_)) clear();
  last_time_s_ = t;
  attacks_ = formation.opponent_attacks;
  for (const FormationRobot& robot : formation.robots) {
    if (robot.robot_id >= tracks_.size()) tracks_.resize(robot.robot_id + 1);
    Track& track = tracks_[robot.robot_id];
    RobotTracker& tracker = track.tracker;
    if (robot.observed) {
      // A robot carried over from an earlier frame (not observed) tells the tracker nothing.
      if (tracker.observations() > 0 &&
          MotionFeatures::is_jump(track.last_observed, tracker.last_s(), robot.position, t)) {
        tracker.reset();
      }
      tracker.observe(t, robot.position);
      track.last_observed = robot.position;
    }
    Seen seen;
    seen.time_s = t;
    seen.position = robot.position;
    // A velocity once the track has gone on for half the velocity window, as the motion
    // model's: before that the filter has seen too little of the robot.
    if (tracker.observations() >= 2 && t - tracker.first_s() > velocity_window_s_ / 2.0) {
      seen.has_kinematics = true;
      seen.velocity = tracker.velocity();
      seen.acceleration = tracker.acceleration();
    }
    track.seen.push_back(seen);
    while (!track.seen.empty() && track.seen.front().time_s < t - keep_s_) track.seen.pop_front();
    track.latest_s = t;
  }
}

const BaselineTracks::Seen* BaselineTracks::latest(std::uint32_t robot_id) const {
  if (robot_id >= tracks_.size() || !last_time_s_) return nullptr;
  const Track& track = tracks_[robot_id];
  if (track.seen.empty() || track.latest_s != *last_time_s_) return nullptr;
  return &track.seen.back();
}

const BaselineTracks::Seen* BaselineTracks::nearest(std::uint32_t robot_id, double time_s,
                                                    double tolerance_s) const {
  if (robot_id >= tracks_.size()) return nullptr;
  const std::deque<Seen>& seen = tracks_[robot_id].seen;
  const auto after = std::lower_bound(seen.begin(), seen.end(), time_s,
                                      [](const Seen& s, double t) { return s.time_s < t; });
  const Seen* best = nullptr;
  double best_gap = tolerance_s;
  const auto consider = [&](auto it) {
    const double gap = std::abs(it->time_s - time_s);
    if (gap <= best_gap) {
      best_gap = gap;
      best = &*it;
    }
  };
  if (after != seen.begin()) consider(after - 1);  // the earlier wins a tie
  if (after != seen.end()) consider(after);
  return best;
}

// ---- BaselineForecaster ---------------------------------------------------------------------

BaselineForecaster::BaselineForecaster(Extrapolation extrapolation, const ModelSettings& settings,
                                       std::vector<StepFactors> factors)
    : extrapolation_(extrapolation),
      settings_(settings),
      factors_(std::move(factors)),
      tracks_(settings.velocity_window_s, 0.0) {
  if (!(settings_.step_s > 0.0) || !std::isfinite(settings_.step_s)) {
    throw std::invalid_argument("the step must be a positive number of seconds");
  }
}

StepFactors BaselineForecaster::factors(int step) const {
  if (factors_.empty()) return {};
  return factors_[std::min(static_cast<std::size_t>(step), factors_.size() - 1)];
}

void BaselineForecaster::forecast(const MatchMoment& moment, int steps, Prediction& out,
                                  ForecastUse) {
  const Formation& now = moment.formation();
  const Grid& grid = moment.codec.grid();
  out.steps.resize(static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) {
    PredictedStep& step = out.steps[static_cast<std::size_t>(k)];
    step.robots.clear();
    const double h = static_cast<double>(k + 1) * settings_.step_s;
    const StepFactors f = factors(k);
    Point sum{};
    for (const FormationRobot& robot : now.robots) {
      const BaselineTracks::Seen* seen = tracks_.latest(robot.robot_id);
      const bool moving = seen && seen->has_kinematics;
      const Point v = moving ? seen->velocity : Point{};
      const Point a = moving ? seen->acceleration : Point{};
      Point to = robot.position;
      if (extrapolation_ != Extrapolation::stay) {
        to.x += f.velocity * v.x * h;
        to.y += f.velocity * v.y * h;
      }
      if (extrapolation_ == Extrapolation::acceleration) {
        to.x += f.acceleration * 0.5 * a.x * h * h;
        to.y += f.acceleration * 0.5 * a.y * h * h;
      }
      RobotPrediction& predicted = step.robots.emplace_back();
      predicted.robot_id = robot.robot_id;
      predicted.normalised_position = to;
      predicted.feed_position = normalise(to, moment.attacks);
      predicted.position = grid.cell_of(to, moment.field);
      predicted.previous = robot.cell;
      sum.x += to.x;
      sum.y += to.y;
    }
    // The predicted state: the cell of the mean of the predicted positions, the predicted cell,
    // the robot's cell now. A baseline states no probability.
    const double n = std::max<double>(1.0, static_cast<double>(step.robots.size()));
    step.centroid = grid.cell_of(Point{sum.x / n, sum.y / n}, moment.field);
    for (RobotPrediction& predicted : step.robots) {
      predicted.state =
          moment.codec.encode(RobotState{step.centroid, predicted.position, predicted.previous});
    }
    step.centroid_probability = 0.0;
    step.centroid_unseen = false;
    step.formation_probability = 0.0;
    step.confidence = 0.0;
  }
}

// ---- BaselineLearner ------------------------------------------------------------------------

BaselineLearner::BaselineLearner(ModelKind kind, Extrapolation extrapolation, bool damped,
                                 const ModelSettings& settings)
    : kind_(kind),
      extrapolation_(extrapolation),
      damped_(damped),
      settings_(settings),
      tracks_(settings.velocity_window_s,
              damped ? settings.step_s * settings.horizons + settings.tolerance_s : 0.0),
      sums_(static_cast<std::size_t>(std::max(settings.horizons, 1))) {
  if (!(settings_.step_s > 0.0) || !std::isfinite(settings_.step_s)) {
    throw std::invalid_argument("the step must be a positive number of seconds");
  }
  if (settings_.horizons < 1 || settings_.horizons > MotionConfig::max_horizons) {
    throw std::invalid_argument("the horizons must be 1 to " +
                                std::to_string(MotionConfig::max_horizons));
  }
}

void BaselineLearner::learn(const MatchMoment& moment) {
  if (!damped_) return;
  const Formation& now = moment.formation();
  const double t = now.time_s;
  for (const FormationRobot& robot : now.robots) {
    for (std::size_t k = 0; k < sums_.size(); ++k) {
      const double h = static_cast<double>(k + 1) * settings_.step_s;
      const BaselineTracks::Seen* then =
          tracks_.nearest(robot.robot_id, t - h, settings_.tolerance_s);
      if (!then || !then->has_kinematics || then->time_s < moment.learn_from_s) continue;
      // A jump in between (a ghost now) is no displacement to fit to.
      if (MotionFeatures::is_jump(then->position, then->time_s, robot.position, t)) continue;
      const Point d{robot.position.x - then->position.x, robot.position.y - then->position.y};
      const Point v{then->velocity.x * h, then->velocity.y * h};
      const Point a{then->acceleration.x * 0.5 * h * h, then->acceleration.y * 0.5 * h * h};
      Sums& s = sums_[k];
      s.vv += v.x * v.x + v.y * v.y;
      s.va += v.x * a.x + v.y * a.y;
      s.aa += a.x * a.x + a.y * a.y;
      s.dv += d.x * v.x + d.y * v.y;
      s.da += d.x * a.x + d.y * a.y;
      ++fitted_;
    }
  }
}

void BaselineLearner::absorb(const Learner& other) {
  const auto* baseline = dynamic_cast<const BaselineLearner*>(&other);
  if (!baseline || baseline->kind_ != kind_ || baseline->sums_.size() != sums_.size() ||
      baseline->settings_.step_s != settings_.step_s ||
      baseline->settings_.velocity_window_s != settings_.velocity_window_s ||
      baseline->settings_.tolerance_s != settings_.tolerance_s) {
    throw std::invalid_argument("a training of another model or other settings cannot be added");
  }
  for (std::size_t k = 0; k < sums_.size(); ++k) {
    const Sums& o = baseline->sums_[k];
    Sums& s = sums_[k];
    s.vv += o.vv;
    s.va += o.va;
    s.aa += o.aa;
    s.dv += o.dv;
    s.da += o.da;
  }
  fitted_ += baseline->fitted_;
}

std::vector<StepFactors> BaselineLearner::factors() const {
  std::vector<StepFactors> factors(sums_.size());
  if (!damped_) return factors;
  for (std::size_t k = 0; k < sums_.size(); ++k) {
    const Sums& s = sums_[k];
    StepFactors& f = factors[k];
    // Velocity alone: k = (d . v) / (v . v); plain constant velocity when nothing moved.
    f.velocity = s.vv > 0.0 ? s.dv / s.vv : 1.0;
    f.acceleration = 0.0;
    if (extrapolation_ != Extrapolation::acceleration) continue;
    // Both terms: the 2 x 2 normal equations, unless they are too close to singular (an
    // acceleration always along the velocity), where the velocity's factor alone stands.
    const double det = s.vv * s.aa - s.va * s.va;
    if (s.vv > 0.0 && s.aa > 0.0 && det > 1e-9 * s.vv * s.aa) {
      f.velocity = (s.dv * s.aa - s.da * s.va) / det;
      f.acceleration = (s.da * s.vv - s.dv * s.va) / det;
    } else if (s.vv <= 0.0) {
      f = StepFactors{};
    }
  }
  return factors;
}

std::unique_ptr<Forecaster> BaselineLearner::forecaster(const TableMetadata&) const {
  return std::make_unique<BaselineForecaster>(extrapolation_, settings_, factors());
}

}  // namespace models
}  // namespace ssl_formation
