#pragma once
// Predictions judged as the field judges them: the distance in millimetres between where a
// method said a robot would be `horizon_s` seconds later and where it was, and the calibration
// of every probability the model states, by the phase of the game the prediction was made in.
//
// Every method (the model and the baselines, models/model_factory.hpp) learns on the training
// streams and predicts the test streams through the very Training and PredictionPipeline the
// daemons run, each with the sampling it needs, following the referee as the daemons do. Every
// method is scored on the same robots at the same instants: the model's instants, a baseline's
// prediction taken at its own instant nearest (the same instant when both sample every frame).

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ssl_formation/evaluation/block_bootstrap.hpp"
#include "ssl_formation/evaluation/error_stats.hpp"
#include "ssl_formation/evaluation/evaluation.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/match/match_event.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/pipeline/prediction_csv.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"

namespace ssl_formation::evaluation {

// How often the truth fell within the model's stated radii.
struct RadiusCoverage {
  std::uint64_t robots = 0;  // scored robots with radii stated
  std::uint64_t within50 = 0;
  std::uint64_t within90 = 0;
  double share50() const { return robots ? double(within50) / double(robots) : 0.0; }
  double share90() const { return robots ? double(within90) / double(robots) : 0.0; }
};

// The rows every table is broken into: every instant, then each phase of the game.
inline constexpr std::size_t state_rows = 1 + all_game_phases.size();
std::string_view state_row_name(std::size_t row);  // "all", then to_string(GamePhase)
inline std::size_t state_row_of(GamePhase phase) { return 1 + static_cast<std::size_t>(phase); }

// One method's score at one horizon.
struct MethodScore {
  ErrorStats error;
  Accuracy cells;  // predicted state, cell and cell distance against the truth
};

// Every method's score at one horizon in seconds, in one row.
struct HorizonScore {
  double horizon_s = 0.0;
  std::vector<MethodScore> methods;  // as PositionEvaluation::methods: the model first
  Calibration robot;                 // the model's per-robot probability that its cell is right
  Calibration formation;             // the model's probability that every cell is right
  RadiusCoverage radii;              // the model's 50% and 90% radii
  // Each block of data time's summed errors (with PositionEvaluationConfig::bootstrap), and the
  // intervals drawn from them: of the means, of their ratios to the best baseline, and of the
  // model's mean over every other method's (intervals.model_ratio[m - 1] for method m).
  BlockedErrors blocks;
  RowIntervals intervals;
};

// One robot scored at one horizon: where it was, where it was `steps` steps of `step_s` later, and
// where each method had said it would be (the model first, then the baselines, as
// PositionEvaluation::methods), in the feed's coordinates (mm). The pointed-to values live only
// for the call that passes them.
struct ScoredSample {
  double step_s = 0.0;
  int steps = 0;
  std::size_t stream = 0;  // which test stream, from 0: each has its own clock
  double time_s = 0.0;     // of the instant the predictions were made at
  std::uint32_t robot_id = 0;
  GamePhase phase = GamePhase::running;
  Point position;  // at time_s
  Point truth;     // steps x step_s later
  const std::vector<const RobotPrediction*>* forecasts = nullptr;
};

// How far a recorded prediction's time may be from a frame's to be that frame's: a file written
// with every digit matches exactly, one rounded to the millisecond still does (frames come 16 ms
// apart at 60 Hz).
inline constexpr double recorded_time_tolerance_s = 0.001;

// The baseline of lowest mean error in `score`: of methods 1 to `baselines_end` - 1 (the first
// is the model), if any was scored.
std::optional<std::size_t> best_baseline(const HorizonScore& score, std::size_t baselines_end);

struct PositionEvaluationConfig {
  SamplerConfig sampler = sampler_config_for(default_model);  // the model's
  ModelKind model = default_model;
  std::vector<ModelKind> baselines{baseline_kinds.begin(), baseline_kinds.end()};
  // With the motion model, also its pooled ablation ("pooled model", MotionModelSettings::
  // pooled): the model's regressors fitted once for every robot and state, scored after the
  // baselines. What the model wins over it is what its keyed rows add.
  bool pooled_ablation = true;
  int steps = 1;  // horizons 1..steps, step k being k x step_s ahead
  double velocity_window_s = 0.1;
  // How far from t + horizon the truth may be sampled, and from t a baseline's instant.
  double tolerance_s = 0.05;
  // The motion model's recalibration while it predicts the test streams (PredictionConfig).
  std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{};
  // How the methods follow the referee, as the daemons' --opponent-* and --learn-during do;
  // none: the sampler's opponent, fixed, learning in every state.
  std::optional<MatchRules> rules;
  bool tracked_vision = false;  // --vision-source tracked
  // The model's prior: every team's table (ssl-evaluate --prior-table), under the rows it
  // learns from the training streams.
  std::shared_ptr<const MotionTable> prior_table = nullptr;
  // The table the model predicts from is the one the programs would save: within this budget,
  // its rows that add nothing folded (ssl-evaluate --max-table-mb, table_budget.hpp).
  TableBudget table_budget;
  // Sees every prediction the model makes on the test streams, as the daemon would have sent it
  // (and ssl-predictor --from-log written it): for tools and tests that want them as they are.
  std::function<void(const PredictedFormation&)> on_model_prediction;
  // Sees every robot as it is scored, at every horizon (ssl-evaluate --write-samples): what the
  // tables average, one robot at a time, for whoever wants to cut them another way.
  std::function<void(const ScoredSample&)> on_sample;
  // The intervals of every mean error and ratio (ssl-evaluate --bootstrap): resamples 0 for none.
  BootstrapConfig bootstrap;
  // Predictions made elsewhere (ssl-evaluate score: ssl-predictor --from-log's CSV, or a team's
  // own) scored in the model's place, labelled "predictions": at each instant of the single test
  // stream the file predicted, its robots are scored against where they were and beside the
  // baselines. `model` then only samples the instants (persistence does, learning nothing), and
  // the sampler's step and `steps` must be the file's.
  std::shared_ptr<const RecordedPredictions> recorded_predictions;
};

struct PositionEvaluation {
  std::vector<ModelKind> methods;   // the model, then the baselines, then the ablations
  std::vector<std::string> labels;  // by method: "model", a baseline's label, "pooled model"
  // Methods 1 to baselines_end - 1 are the baselines; from it on, the model's ablations (no
  // row's best baseline is one of them).
  std::size_t baselines_end = 0;
  // Whether the first method states cells and states (a file of predictions may not): without
  // them its cell and state figures are not scored, and reports leave them out.
  bool model_states_cells = true;
  bool model_states_states = true;
  // With recorded predictions: how many of the file's instants were frames of the test stream.
  std::uint64_t recorded_matched = 0;
  std::optional<std::size_t> best_baseline(const HorizonScore& score) const {
    return evaluation::best_baseline(score, baselines_end);
  }
  // rows[row][step - 1], row as state_row_of / 0 for every instant.
  std::vector<std::vector<HorizonScore>> rows;
  std::uint64_t train_formations = 0;
  std::uint64_t transitions = 0;
  std::size_t table_memory_bytes = 0;
  std::uint64_t test_formations = 0;
  // Whether the test streams carried referee messages: without them every instant is running
  // play, and only the rows "all" and "running" mean anything.
  bool test_has_referee = false;
  std::shared_ptr<const StoredTable> table;  // what the model was trained to
  // Why the model could not learn from the training streams (frames seconds apart), if so.
  std::optional<std::string> feed_problem;

  const std::vector<HorizonScore>& all() const { return rows.front(); }
  // The rows a report shows: every row when the test streams had a referee, else "all" and
  // "running" (every instant is running play as far as anyone can tell).
  std::vector<std::size_t> reported_rows() const;
};

// A match's events as the evaluation reads them: each call hands them to `sink` from the start
// (no start_new_stream: the evaluation says where a stream begins). A log is read as it goes, so
// nothing of it stays in memory; a match in memory is replayed (replay_of).
using EventStream = std::function<void(MatchEventSink& sink)>;
// `match` must outlive the stream.
EventStream replay_of(const RecordedMatch& match);

// Trains every method of every configuration on the training streams (each its own stream:
// nothing spans two), then predicts every test stream and scores every method at every horizon,
// by phase of the game. Each stream is read once for all the configurations, and the methods of
// a configuration that sample alike read one front end: a message is parsed once per sampling,
// not once per method. Predictions are scored as soon as the truth of their last horizon has
// been seen, so what is kept does not grow with a stream's length. Throws std::invalid_argument
// for a configuration a method cannot run with.
std::vector<PositionEvaluation> evaluate_positions(
    const std::vector<PositionEvaluationConfig>& configs, const std::vector<EventStream>& train,
    const std::vector<EventStream>& test);
// One configuration on matches in memory.
PositionEvaluation evaluate_positions(const PositionEvaluationConfig& config,
                                      const std::vector<RecordedMatch>& train,
                                      const std::vector<RecordedMatch>& test);

// The formation of `formations` (in time order) sampled nearest `time_s`, within `tolerance_s`.
const Formation* formation_near(const std::vector<Formation>& formations, double time_s,
                                double tolerance_s);

// Expected calibration error over the 10 equal-width bins: sum over bins of
// (bin count / n) x |observed frequency - mean confidence|.
double expected_calibration_error(const Calibration& calibration);

}  // namespace ssl_formation::evaluation
