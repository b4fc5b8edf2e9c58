#include "ssl_formation/evaluation/position_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "ssl_formation/pipeline/prediction_pipeline.hpp"

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

// One method's predictions at one instant of a test stream.
struct Instant {
  double time_s = 0.0;
  GamePhase phase = GamePhase::running;
  std::vector<PredictedStep> steps;
};

// What a method predicted over one test stream, and (the model's) the formations it sampled.
struct StreamPredictions {
  std::vector<Instant> instants;
  std::vector<Formation> formations;  // kept for the model only: the truth
};

const RobotPrediction* find_robot(const PredictedStep& step, std::uint32_t robot_id) {
  const auto it = std::find_if(step.robots.begin(), step.robots.end(),
                               [&](const RobotPrediction& r) { return r.robot_id == robot_id; });
  return it == step.robots.end() ? nullptr : &*it;
}

// A method as the evaluation runs it: its sampler and what it learned.
struct Method {
  ModelKind kind;
  PredictionConfig prediction;
  std::unique_ptr<Training> training;
};

// Scores the model's instant `i` of test stream `stream` and every method's prediction at its
// nearest instant, at every horizon, into the rows "all" and the instant's phase.
void score_instant(PositionEvaluation& result, const PositionEvaluationConfig& config,
                   const std::vector<StreamPredictions>& by_method, std::size_t stream,
                   std::size_t i) {
  const StreamPredictions& model = by_method.front();
  const Instant& instant = model.instants[i];
  const Formation& now = model.formations[i];
  // Each baseline's instant nearest the model's.
  std::vector<const Instant*> at(by_method.size(), nullptr);
  at[0] = &instant;
  for (std::size_t m = 1; m < by_method.size(); ++m) {
    const auto j = nearest_index(by_method[m].instants, instant.time_s, config.tolerance_s,
                                 [](const Instant& x) { return x.time_s; });
    if (!j) return;  // scored on the same instants or not at all
    at[m] = &by_method[m].instants[*j];
  }
  const std::array<std::size_t, 2> rows{0, state_row_of(instant.phase)};
  // What a file of predictions does not state is not scored for it (method 0): its cells, its
  // states, and the probabilities that need them.
  const RecordedPredictions* file = config.recorded_predictions.get();
  const bool scores_cells = !file || file->has_cells;
  const bool scores_states = !file || file->has_states;
  const bool scores_robot_probability = !file || (file->has_cells && file->has_probabilities);
  const bool scores_formation_probability =
      !file || (file->has_cells && file->has_formation_probability);
  const double step_s = config.sampler.step_s;
  for (int k = 0; k < config.steps; ++k) {
    const auto h = static_cast<std::size_t>(k);
    const Formation* truth = formation_near(model.formations, instant.time_s + (k + 1) * step_s,
                                            config.tolerance_s);
    if (!truth) continue;
    // The robots every method predicted and the truth holds.
    struct Scored {
      const FormationRobot* now;
      const FormationRobot* actual;
      std::vector<const RobotPrediction*> guesses;
    };
    std::vector<Scored> scored;
    for (const FormationRobot& robot : now.robots) {
      const FormationRobot* actual = truth->find(robot.robot_id);
      if (!actual) continue;
      Scored s{&robot, actual, std::vector<const RobotPrediction*>(at.size(), nullptr)};
      bool everyone = true;
      for (std::size_t m = 0; m < at.size() && everyone; ++m) {
        if (h >= at[m]->steps.size()) {
          everyone = false;
          break;
        }
        s.guesses[m] = find_robot(at[m]->steps[h], robot.robot_id);
        everyone = s.guesses[m] != nullptr;
      }
      if (everyone) scored.push_back(std::move(s));
    }
    if (scored.empty()) continue;
    if (config.on_sample) {
      for (const Scored& s : scored) {
        config.on_sample(ScoredSample{step_s, k + 1, stream, instant.time_s, s.now->robot_id,
                                      instant.phase, s.now->feed_position, s.actual->feed_position,
                                      &s.guesses});
      }
    }
    for (const std::size_t row : rows) {
      HorizonScore& score = result.rows[row][h];
      bool every_cell_right = true;
      for (std::size_t m = 0; m < at.size(); ++m) {
        MethodScore& method = score.methods[m];
        ++method.cells.formations;
        for (const Scored& s : scored) {
          const RobotPrediction& guess = *s.guesses[m];
          const double error = distance(guess.feed_position, s.actual->feed_position);
          method.error.add(error);
          ++method.cells.robots;
          if ((m != 0 || scores_states) && guess.state == s.actual->state) {
            ++method.cells.exact_states;
          }
          const bool right = guess.position == s.actual->cell;
          if ((m != 0 || scores_cells) && right) ++method.cells.exact_cells;
          if (m != 0 || scores_cells) {
            method.cells.cell_distance += static_cast<std::uint64_t>(
                std::abs(guess.position.x - s.actual->cell.x) +
                std::abs(guess.position.y - s.actual->cell.y));
          }
          if (m != 0) continue;
          if (guess.radius90_mm > 0.0) {
            ++score.radii.robots;
            if (error <= guess.radius50_mm) ++score.radii.within50;
            if (error <= guess.radius90_mm) ++score.radii.within90;
          }
          if (scores_robot_probability) score.robot.add(guess.probability, right);
          every_cell_right = every_cell_right && right;
        }
      }
      if (scores_formation_probability) {
        score.formation.add(at[0]->steps[h].formation_probability, every_cell_right);
      }
      if (config.bootstrap.enabled()) {
        std::vector<double> errors(at.size());
        const DataBlock block = data_block(stream, instant.time_s, config.bootstrap.block_s);
        for (const Scored& s : scored) {
          for (std::size_t m = 0; m < at.size(); ++m) {
            errors[m] = distance(s.guesses[m]->feed_position, s.actual->feed_position);
          }
          add_to_block(score.blocks, block, errors);
        }
      }
    }
  }
}

}  // namespace

std::string_view state_row_name(std::size_t row) {
  return row == 0 ? std::string_view("all") : to_string(all_game_phases[row - 1]);
}

std::vector<std::size_t> PositionEvaluation::reported_rows() const {
  if (!test_has_referee) return {0, state_row_of(GamePhase::running)};
  std::vector<std::size_t> all_rows(state_rows);
  for (std::size_t r = 0; r < all_rows.size(); ++r) all_rows[r] = r;
  return all_rows;
}

std::optional<std::size_t> best_baseline(const HorizonScore& score, std::size_t baselines_end) {
  std::optional<std::size_t> best;
  for (std::size_t m = 1; m < std::min(baselines_end, score.methods.size()); ++m) {
    if (score.methods[m].error.count() == 0) continue;
    if (!best || score.methods[m].error.mean() < score.methods[*best].error.mean()) best = m;
  }
  return best;
}

const Formation* formation_near(const std::vector<Formation>& formations, double time_s,
                                double tolerance_s) {
  const auto index = nearest_index(formations, time_s, tolerance_s,
                                   [](const Formation& f) { return f.time_s; });
  return index ? &formations[*index] : nullptr;
}

PositionEvaluation evaluate_positions(const PositionEvaluationConfig& config,
                                      const std::vector<RecordedMatch>& train,
                                      const std::vector<RecordedMatch>& test) {
  PositionEvaluation result;
  result.methods.push_back(config.model);
  result.methods.insert(result.methods.end(), config.baselines.begin(), config.baselines.end());
  result.baselines_end = result.methods.size();
  const RecordedPredictions* recorded = config.recorded_predictions.get();
  if (recorded && test.size() != 1) {
    throw std::invalid_argument("recorded predictions are scored against one test stream");
  }
  result.labels.emplace_back(recorded ? "predictions" : "model");
  result.model_states_cells = !recorded || recorded->has_cells;
  result.model_states_states = !recorded || recorded->has_states;
  for (const ModelKind kind : config.baselines) result.labels.emplace_back(describe(kind).label);
  if (config.pooled_ablation && config.model == ModelKind::motion && !recorded) {
    result.methods.push_back(ModelKind::motion);
    result.labels.emplace_back("pooled model");
  }
  ModelSettings settings;
  settings.grid = config.sampler.grid;
  settings.step_s = config.sampler.step_s;
  settings.horizons = config.steps;
  settings.recalibration = config.recalibration;
  settings.velocity_window_s = config.velocity_window_s;
  settings.tolerance_s = config.tolerance_s;

  // Training: each method through its own Training, with the sampling it needs (the baselines
  // read every frame's velocities even where the model samples every step).
  std::vector<Method> methods;
  for (std::size_t m = 0; m < result.methods.size(); ++m) {
    const ModelKind kind = result.methods[m];
    const bool ablation = m >= result.baselines_end;
    PredictionConfig prediction;
    prediction.sampler = config.sampler;
    if (kind != config.model && sampling_problem(kind, prediction.sampler.sampling)) {
      prediction.sampler.sampling = Sampling::frame;
    }
    prediction.horizon = config.steps;
    prediction.model = kind;
    prediction.recalibration = config.recalibration;
    prediction.opponent = config.rules ? std::optional<OpponentChoice>(config.rules->opponent)
                                       : std::nullopt;
    prediction.tracked_vision = config.tracked_vision;
    TrainingConfig training;
    training.sampler = prediction.sampler;
    training.rules = config.rules;
    training.tracked_vision = config.tracked_vision;
    // The ablation learns the model's table again (the same counts) for forecasters of its own.
    ModelSettings own_settings = settings;
    own_settings.pooled_motion = ablation;
    auto trained = std::make_unique<Training>(training, kind, make_learner(kind, own_settings));
    for (const RecordedMatch& stream : train) {
      trained->start_new_stream();
      stream.replay(*trained);
    }
    methods.push_back({kind, prediction, std::move(trained)});
  }
  const Training& model = *methods.front().training;
  TableMetadata metadata;
  metadata.field = model.sampler().field();
  metadata.step_s = config.sampler.step_s;
  metadata.samples = model.samples();
  result.train_formations = model.samples();
  result.feed_problem = model.feed_problem();
  if (const TransitionTable* transitions = model.learner().transitions()) {
    const MotionTable* motion = model.learner().motion();
    result.table = std::make_shared<const StoredTable>(StoredTable{
        *transitions, metadata, motion ? std::optional<MotionTable>(*motion) : std::nullopt});
    result.transitions = transitions->transitions();
    result.table_memory_bytes = transitions->memory_bytes() + (motion ? motion->memory_bytes() : 0);
  }

  result.rows.assign(state_rows, std::vector<HorizonScore>(static_cast<std::size_t>(config.steps)));
  for (auto& row : result.rows) {
    for (int k = 0; k < config.steps; ++k) {
      row[static_cast<std::size_t>(k)].horizon_s = (k + 1) * config.sampler.step_s;
      row[static_cast<std::size_t>(k)].methods.resize(methods.size());
    }
  }

  // Testing: every method's pipeline over each test stream, then the stream scored.
  std::vector<StreamPredictions> by_method(methods.size());
  std::vector<std::unique_ptr<PredictionPipeline>> pipelines;
  for (std::size_t m = 0; m < methods.size(); ++m) {
    Method& method = methods[m];
    TableMetadata own = metadata;
    own.field = method.training->sampler().field();
    pipelines.push_back(std::make_unique<PredictionPipeline>(
        method.prediction,
        method.training->learner().forecaster(
            own, m == 0 || m >= result.baselines_end ? config.prior_table : nullptr),
        [&by_method, &config, &result, m, recorded](const PredictedFormation& p) {
          if (m == 0 && config.on_model_prediction) config.on_model_prediction(p);
          StreamPredictions& out = by_method[m];
          const double time_s = p.formation().time_s;
          if (m == 0 && recorded) {
            // The file's predictions at this instant, if it made any, in place of the sampling
            // model's.
            const auto at = nearest_index(recorded->instants, time_s, recorded_time_tolerance_s,
                                          [](const RecordedPrediction& r) { return r.time_s; });
            if (at) ++result.recorded_matched;
            out.instants.push_back({time_s, p.context.phase,
                                    at ? recorded->instants[*at].prediction.steps
                                       : std::vector<PredictedStep>{}});
          } else {
            out.instants.push_back({time_s, p.context.phase, p.prediction.steps});
          }
          if (m == 0) out.formations.push_back(p.formation());
        }));
  }
  for (std::size_t t = 0; t < test.size(); ++t) {
    const RecordedMatch& stream = test[t];
    result.test_has_referee = result.test_has_referee || stream.has_referee();
    for (std::size_t m = 0; m < methods.size(); ++m) {
      by_method[m] = StreamPredictions{};
      pipelines[m]->start_new_stream();
      stream.replay(*pipelines[m]);
    }
    result.test_formations += by_method.front().formations.size();
    for (std::size_t i = 0; i < by_method.front().instants.size(); ++i) {
      score_instant(result, config, by_method, t, i);
    }
  }
  if (config.bootstrap.enabled()) {
    // One set of draws for every row and horizon: the blocks any robot was scored in.
    std::vector<DataBlock> universe;
    for (const HorizonScore& score : result.all()) {
      for (const auto& [block, sums] : score.blocks) universe.push_back(block);
    }
    const BlockResamples draws(std::move(universe), config.bootstrap);
    // The model against every other method: RowIntervals::model_ratio[m - 1] is over method m.
    std::vector<std::size_t> others;
    for (std::size_t m = 1; m < result.methods.size(); ++m) others.push_back(m);
    for (auto& row : result.rows) {
      for (HorizonScore& score : row) {
        score.intervals =
            bootstrap_row(score.blocks, draws, result.best_baseline(score), others);
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
