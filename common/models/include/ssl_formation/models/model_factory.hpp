#pragma once
// The models by name, behind --model in every program: what each needs and states, and the
// learner and forecaster of each. The only place that tells the models apart.
//
//   paper                         the paper's Markov model on cells (docs/models.md), from a table
//   motion                        positions in mm with calibrated radii, from a table (the default)
//   persistence                   every robot stays where it is
//   constant-velocity             every robot goes on at its tracker's velocity
//   damped-constant-velocity      the same, scaled by a factor per step fitted on training data
//   constant-acceleration         the tracker's velocity and acceleration, kept
//   damped-constant-acceleration  both scaled by factors per step fitted on training data
//
// The baselines take their velocity and acceleration from the robot tracker the motion model
// uses (vision/robot_tracker.hpp), so the model is compared with what a team's own tracker would
// extrapolate.

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/motion_model/motion_learning.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation {
inline namespace models {

enum class ModelKind {
  paper,
  motion,
  persistence,
  constant_velocity,
  damped_constant_velocity,
  constant_acceleration,
  damped_constant_acceleration,
};
inline constexpr std::array<ModelKind, 7> all_model_kinds{ModelKind::paper,
                                                          ModelKind::motion,
                                                          ModelKind::persistence,
                                                          ModelKind::constant_velocity,
                                                          ModelKind::damped_constant_velocity,
                                                          ModelKind::constant_acceleration,
                                                          ModelKind::damped_constant_acceleration};
// The baselines every evaluation compares a model with, in the order its tables show them.
inline constexpr std::array<ModelKind, 5> baseline_kinds{
    ModelKind::persistence, ModelKind::constant_velocity, ModelKind::damped_constant_velocity,
    ModelKind::constant_acceleration, ModelKind::damped_constant_acceleration};

// The model every program runs unless told otherwise (--model), and the library's too.
inline constexpr ModelKind default_model = ModelKind::motion;

// What a model is, for the programs to ask instead of naming models.
struct ModelDescription {
  std::string_view name;   // --model's value: "damped-constant-velocity"
  std::string_view label;  // in reports: "damped constant velocity"
  // Its positions are its own, in millimetres (the paper's model states cells, whose centres
  // stand for its positions).
  bool states_positions = true;
  bool keeps_table = false;        // learns into a table file, which ssl-trainer writes
  bool keeps_motion_rows = false;  // its table holds the motion model's rows (version 3)
  bool learns = false;  // learns anything at all (a table, or the damped baselines' factors)
  // Samples a formation at every frame: it reads the robots' velocities, which need frames a few
  // hundredths of a second apart. False: it also takes a formation every --step.
  bool needs_every_frame = true;
  double default_step_s = 0.5;  // --step auto
  // Predicts under every team's table (--prior-table, ModelSettings::prior_table).
  bool takes_prior_table = false;
  // Has an ablation that pools its rows (ModelSettings::pooled_motion), which ssl-evaluate
  // reports beside it.
  bool has_pooled_ablation = false;
};

const ModelDescription& describe(ModelKind kind);
std::string_view to_string(ModelKind kind);  // describe(kind).name
std::optional<ModelKind> parse_model(std::string_view name);
std::string model_names();  // "paper, motion, persistence, ..." for messages and --help

// A sampler set up as `kind` needs it: its default step, and frame sampling where it reads
// velocities (the paper's model samples every step, as the paper did). Everything else is
// SamplerConfig's default.
SamplerConfig sampler_config_for(ModelKind kind);

// Why `kind` cannot run on `sampling` (none: it can): the one check of a model against the
// sampling, made by the options, Training and PredictionPipeline alike.
std::optional<std::string> sampling_problem(ModelKind kind, Sampling sampling);

// Why `kind` cannot learn from a feed whose detection frames come `frame_gap_s` apart on the
// data clock, with the option that fixes it (none: it can).
std::optional<std::string> feed_problem(ModelKind kind, double frame_gap_s);

// How the models learn and forecast.
struct ModelSettings {
  Grid grid{3, 2};
  double step_s = 0.5;
  // Steps learned (the motion model's table, the damped baselines' factors): k x step_s ahead
  // for k = 1..horizons.
  int horizons = 3;
  // The motion model's recalibration while it predicts (none: as the table states).
  std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{};
  // The baselines: a robot has a velocity once its track has run half this long (as the motion
  // model's, MotionConfig::velocity_window_s).
  double velocity_window_s = 0.1;
  // The damped baselines: how far from t + horizon a position may be to stand for it.
  double tolerance_s = 0.05;
  // The motion model's prior: every team's table (`ssl-trainer --opponent-team all`, merged),
  // under the opponent's own rows (MotionModel). None: damped constant velocity is the prior.
  std::shared_ptr<const MotionTable> prior_table = nullptr;
  // The field the prior's probabilities are calibrated for until a table brings its own.
  FieldSize prior_field{9000.0, 6000.0};
  // The motion model as an ablation: one fit for every robot and state instead of its keyed
  // rows (MotionModelSettings::pooled; ssl-evaluate's "pooled model").
  bool pooled_motion = false;
  // The motion model's learner prunes the table it holds as a saved table is pruned (the rows
  // that add nothing folded into their parents, motion_table_pruning.hpp), and further to half
  // this many rows, once it holds more than this: what training holds in memory stops growing
  // with the data, as the file does. 2^17 rows take about 40 MB; the file of a 4 MB budget
  // keeps fewer. 0: never (the table holds every row).
  std::size_t motion_rows_in_memory = default_motion_rows_in_memory;
  // The motion model's table settings for these (its step and horizons from above).
  MotionConfig motion_config() const;
};

// A learner of `kind` with nothing learned yet. Throws std::invalid_argument for settings the
// model cannot learn with (an invalid step or horizon).
std::unique_ptr<Learner> make_learner(ModelKind kind, const ModelSettings& settings);
// The model a table serves: the motion model's with its motion section, the paper's without.
ModelKind model_of_table(const StoredTable& table);
// A learner that goes on from a table (of model_of_table). Its kind, for the caller to check
// against --model.
struct ResumedLearner {
  ModelKind kind;
  std::unique_ptr<Learner> learner;
};
ResumedLearner resume_learner(StoredTable stored);
// A learner with nothing learned yet for a table of `grid`: the motion model's with `motion`'s
// settings, the paper's without (what a trainer starts a table from).
ResumedLearner empty_table_learner(const Grid& grid, const std::optional<MotionConfig>& motion);

// A forecaster of `kind`, without a table yet. Throws std::invalid_argument for settings it
// cannot forecast with.
std::unique_ptr<Forecaster> make_forecaster(ModelKind kind, const ModelSettings& settings);

}  // namespace models
}  // namespace ssl_formation
