#include "ssl_formation/models/model_factory.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "baselines.hpp"
#include "ssl_formation/motion_model/motion_learning.hpp"
#include "ssl_formation/paper_model/paper_learning.hpp"

namespace ssl_formation {
inline namespace models {

namespace {

// The data-clock gap between frames above which a model that reads velocities sees none: its
// tracker needs frames within a few hundredths of a second (MotionConfig::velocity_window_s).
constexpr double max_frame_gap_for_velocities_s = 0.25;

const std::array<ModelDescription, all_model_kinds.size()> descriptions{{
    // name, label, states positions, keeps a table, its motion rows, learns, every frame, step,
    // takes a prior table, has a pooled ablation
    {"paper", "paper", false, true, false, true, false, 2.0, false, false},
    {"motion", "model", true, true, true, true, true, 0.5, true, true},
    {"persistence", "persistence", true, false, false, false, true, 0.5, false, false},
    {"constant-velocity", "constant velocity", true, false, false, false, true, 0.5, false, false},
    {"damped-constant-velocity", "damped constant velocity", true, false, false, true, true, 0.5,
     false, false},
    {"constant-acceleration", "constant acceleration", true, false, false, false, true, 0.5, false,
     false},
    {"damped-constant-acceleration", "damped constant acceleration", true, false, false, true, true,
     0.5, false, false},
}};

}  // namespace

const ModelDescription& describe(ModelKind kind) {
  return descriptions[static_cast<std::size_t>(kind)];
}

std::string_view to_string(ModelKind kind) { return describe(kind).name; }

std::optional<ModelKind> parse_model(std::string_view name) {
  for (const ModelKind kind : all_model_kinds) {
    if (describe(kind).name == name) return kind;
  }
  return std::nullopt;
}

std::string model_names() {
  std::string names;
  for (const ModelKind kind : all_model_kinds) {
    if (!names.empty()) names += ", ";
    names += describe(kind).name;
  }
  return names;
}

SamplerConfig sampler_config_for(ModelKind kind) {
  SamplerConfig config;
  config.step_s = describe(kind).default_step_s;
  config.sampling = describe(kind).needs_every_frame ? Sampling::frame : Sampling::step;
  return config;
}

std::optional<std::string> sampling_problem(ModelKind kind, Sampling sampling) {
  if (!describe(kind).needs_every_frame || sampling == Sampling::frame) return std::nullopt;
  return "--model " + std::string(describe(kind).name) +
         " reads every frame's velocities: it needs --sampling frame (or auto); --model paper "
         "samples a formation every --step";
}

std::optional<std::string> feed_problem(ModelKind kind, double frame_gap_s) {
  if (!describe(kind).needs_every_frame || frame_gap_s <= max_frame_gap_for_velocities_s) {
    return std::nullopt;
  }
  char gap[32];
  std::snprintf(gap, sizeof gap, "%.2g", frame_gap_s);
  return "the vision frames come " + std::string(gap) +
         " s apart on the data clock (t_capture), but --model " + std::string(describe(kind).name) +
         " needs frames a few hundredths of a second apart to see how the robots move, as "
         "SSL-Vision and grSim send them (and ssl-producer --simulation match): it learns and "
         "predicts nothing from this feed. For a feed of one formation every few seconds (the "
         "paper's, ssl-producer --simulation paper) use --model paper";
}

MotionConfig ModelSettings::motion_config() const {
  MotionConfig config;
  config.step_s = step_s;
  config.horizons = horizons;
  return config;
}

namespace {

models::Extrapolation extrapolation_of(ModelKind kind) {
  switch (kind) {
    case ModelKind::constant_velocity:
    case ModelKind::damped_constant_velocity:
      return models::Extrapolation::velocity;
    case ModelKind::constant_acceleration:
    case ModelKind::damped_constant_acceleration:
      return models::Extrapolation::acceleration;
    default:
      return models::Extrapolation::stay;
  }
}

}  // namespace

std::unique_ptr<Learner> make_learner(ModelKind kind, const ModelSettings& settings) {
  switch (kind) {
    case ModelKind::paper:
      return std::make_unique<PaperLearner>(TransitionTable(settings.grid));
    case ModelKind::motion: {
      const MotionConfig config = settings.motion_config();
      if (!config.valid())
        throw std::invalid_argument("invalid step or horizon for the motion model");
      return std::make_unique<MotionLearner>(TransitionTable(settings.grid), MotionTable(config),
                                             settings.recalibration, settings.pooled_motion,
                                             settings.motion_rows_in_memory);
    }
    case ModelKind::persistence:
    case ModelKind::constant_velocity:
    case ModelKind::damped_constant_velocity:
    case ModelKind::constant_acceleration:
    case ModelKind::damped_constant_acceleration:
      return std::make_unique<models::BaselineLearner>(kind, extrapolation_of(kind),
                                                       describe(kind).learns, settings);
  }
  throw std::invalid_argument("unknown model");
}

ModelKind model_of_table(const StoredTable& table) {
  return table.motion ? ModelKind::motion : ModelKind::paper;
}

ResumedLearner resume_learner(StoredTable stored) {
  const ModelKind kind = model_of_table(stored);
  if (kind == ModelKind::motion) {
    // The learner goes on from its own copy: a loaded section is shared by whoever read it.
    MotionTable motion = *stored.motion;
    stored.motion.reset();
    return {kind, std::make_unique<MotionLearner>(std::move(stored.table), std::move(motion))};
  }
  return {kind, std::make_unique<PaperLearner>(std::move(stored.table))};
}

ResumedLearner empty_table_learner(const Grid& grid, const std::optional<MotionConfig>& motion) {
  return resume_learner(
      StoredTable{TransitionTable(grid), TableMetadata{},
                  motion ? std::make_shared<const MotionTable>(*motion) : nullptr});
}

MotionForecastSettings motion_forecast_settings(const ModelSettings& settings) {
  MotionForecastSettings motion;
  motion.grid = settings.grid;
  motion.step_s = settings.step_s;
  motion.recalibration = settings.recalibration;
  motion.prior_table = settings.prior_table;
  motion.prior_field = settings.prior_field;
  motion.pooled = settings.pooled_motion;
  return motion;
}

std::unique_ptr<Forecaster> make_forecaster(ModelKind kind, const ModelSettings& settings) {
  switch (kind) {
    case ModelKind::paper:
      return std::make_unique<PaperForecaster>();
    case ModelKind::motion:
      return std::make_unique<MotionForecaster>(motion_forecast_settings(settings));
    case ModelKind::persistence:
    case ModelKind::constant_velocity:
    case ModelKind::damped_constant_velocity:
    case ModelKind::constant_acceleration:
    case ModelKind::damped_constant_acceleration:
      // Before any fit the damped ones extrapolate undamped.
      return std::make_unique<models::BaselineForecaster>(extrapolation_of(kind), settings);
  }
  throw std::invalid_argument("unknown model");
}

}  // namespace models
}  // namespace ssl_formation
