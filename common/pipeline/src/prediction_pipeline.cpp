#include "ssl_formation/pipeline/prediction_pipeline.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ssl_formation {

namespace {

// The motion model's history keeps what its velocities need; the step and horizons come from
// the table, but velocities only need the window, which is the same for every table.
MotionConfig motion_history_config(const PredictionConfig& config) {
  MotionConfig motion;
  motion.step_s = config.sampler.step_s;
  motion.horizons = 1;
  return motion;
}

}  // namespace

PredictionPipeline::PredictionPipeline(PredictionConfig config, Handler on_prediction)
    : config_(config),
      on_prediction_(std::move(on_prediction)),
      motion_history_(motion_history_config(config)),
      online_calibration_(config.recalibration.value_or(OnlineCalibrationSettings{})),
      sampler_(config.sampler, [this](const FormationSample& sample) { on_sample(sample); }),
      match_(config.opponent ? *config.opponent
                             : fixed_opponent(config.sampler.opponent_color,
                                              config.sampler.opponent_attacks,
                                              config.sampler.infer_attacks)) {
  if (config_.model == ModelKind::motion && config_.sampler.sampling != Sampling::frame) {
    throw std::invalid_argument(
        "the motion model predicts from every frame's velocities: it needs --sampling frame");
  }
  if (config_.recalibration && !config_.recalibration->valid()) {
    throw std::invalid_argument(
        "the recalibration's half-life must be positive seconds, its prior weight, tolerance and "
        "remember interval finite and not negative");
  }
  if (config_.horizon < 1 || config_.horizon > PredictionConfig::max_horizon) {
    throw std::invalid_argument("the horizon must be 1 to " +
                                std::to_string(PredictionConfig::max_horizon) + " formations");
  }
  // The per-sample buffers, allocated together now rather than wherever the first sample
  // leaves them: a daemon woken every 16 ms pays for every cold page its hot path touches.
  constexpr std::size_t usual_robots = 16;
  robot_states_.reserve(usual_robots);
  motion_robots_.reserve(usual_robots);
  prediction_.steps.resize(static_cast<std::size_t>(config_.horizon));
  for (PredictedStep& step : prediction_.steps) step.robots.reserve(usual_robots);
  follow_opponent();
}

RefereeChange PredictionPipeline::add_referee(std::string_view payload, double receive_s) {
  const RefereeChange change = match_.add_referee(payload, receive_s);
  if (change.any()) follow_opponent();
  return change;
}

void PredictionPipeline::start_new_stream() {
  sampler_.start_new_stream();
  motion_history_.clear();
  online_calibration_.clear();
  live_score_.clear();
  last_sample_ = nullptr;
  match_.reset();
  follow_opponent();
}

void PredictionPipeline::follow_opponent() {
  const Opponent& opponent = match_.opponent();
  if (opponent.color != sampler_.config().opponent_color) {
    motion_history_.clear();
    online_calibration_.clear();
    live_score_.clear();  // predictions of the old team's robots would meet the new one's ids
    last_sample_ = nullptr;
  }
  sampler_.set_opponent(opponent.color, opponent.attacks);
}

void PredictionPipeline::set_table(std::shared_ptr<const StoredTable> table) {
  if (table && table->table.grid() != config_.sampler.grid) {
    throw std::invalid_argument("the table's grid " + table->table.grid().to_string() +
                                " differs from the predictor's " +
                                config_.sampler.grid.to_string());
  }
  std::shared_ptr<const MotionModel> model;
  if (table && config_.model == ModelKind::motion) {
    if (!table->motion) {
      throw std::invalid_argument(
          "the table holds only the paper's counts (a version-1 table): it serves --model paper; "
          "train a table with --model motion to use the motion model");
    }
    if (std::abs(table->motion->config().step_s - config_.sampler.step_s) > 1e-9) {
      throw std::invalid_argument("the table's motion model was trained with another step");
    }
    model = std::make_shared<const MotionModel>(*table->motion, config_.sampler.grid,
                                                table->metadata.field);
  }
  motion_model_ = std::move(model);
  motion_cache_.clear();
  table_ = std::move(table);
}

void PredictionPipeline::on_sample(const FormationSample& sample) {
  const bool motion = config_.model == ModelKind::motion;
  if (motion) {
    motion_history_.add(sample.formation);
    if (config_.recalibration) online_calibration_.observe(sample.formation);
  }
  live_score_.observe(sample.formation);
  last_sample_ = &sample;
  // Holds the table for the handler's call even if the handler sets another one: the context
  // points into it.
  const std::shared_ptr<const StoredTable> stored = table_;
  if (!predict_sample(sample)) {
    ++samples_without_table_;
    return;
  }
  if (motion && config_.recalibration) {
    online_calibration_.remember(prediction_, sample.formation.time_s, config_.sampler.step_s,
                                 sample.formation.opponent_attacks);
    online_calibration_.adjust(prediction_);
  }
  live_score_.remember(prediction_, sample.formation, config_.sampler.step_s);
  ++predictions_;
  if (on_prediction_) on_prediction_(PredictedFormation{sample, prediction_, context_});
}

bool PredictionPipeline::rehearse(const Handler& on_rehearsal) {
  const std::shared_ptr<const StoredTable> stored = table_;  // as in on_sample
  if (!last_sample_ || !predict_sample(*last_sample_)) return false;
  if (config_.model == ModelKind::motion && config_.recalibration) {
    online_calibration_.adjust(prediction_);
  }
  if (on_rehearsal) on_rehearsal(PredictedFormation{*last_sample_, prediction_, context_});
  return true;
}

bool PredictionPipeline::predict_sample(const FormationSample& sample) {
  // The callers hold the table for the whole call (nothing here can replace it).
  if (!table_) return false;
  const StoredTable& stored = *table_;
  const MotionModel* motion_model = motion_model_.get();
  PredictionContext& context = context_;
  // The sampler's opponent now (the referee may have changed it since the start).
  context = prediction_context(stored.table, sampler_.config(), sampler_.field());
  // The direction may be inferred (--opponent-attacks auto): the one this sample was taken with.
  context.opponent_attacks = sampler_.attacks().value_or(sampler_.config().opponent_attacks);
  context.model = config_.model;
  context.game_state = match_.game_state();
  if (motion_model) {
    motion_robots_.clear();
    for (const FormationRobot& robot : sample.formation.robots) {
      const MotionHistory::Entry* seen = motion_history_.latest(robot.robot_id);
      // The history has just taken this formation: `seen` is the robot's latest observation,
      // this frame's or (a robot carried over from an earlier frame) the one before.
      const bool moving = seen && seen->has_velocity;
      motion_robots_.push_back({robot.robot_id, robot.position,
                                moving ? seen->kinematics : MotionKinematics{}, moving,
                                moving ? seen->context : 0});
    }
    motion_model->predict(motion_robots_, config_.horizon, sampler_.codec(), sampler_.field(),
                          context.opponent_attacks, prediction_, motion_cache_);
  } else {
    robot_states_.clear();
    for (const FormationRobot& robot : sample.formation.robots) {
      robot_states_.push_back({robot.robot_id, robot.state});
    }
    predict(stored.table, robot_states_, config_.horizon, prediction_);
    const Grid& grid = config_.sampler.grid;
    for (PredictedStep& step : prediction_.steps) {
      for (RobotPrediction& robot : step.robots) {
        robot.normalised_position = grid.centre_of(robot.position, sampler_.field());
        robot.feed_position = normalise(robot.normalised_position, context.opponent_attacks);
      }
    }
  }
  return true;
}

}  // namespace ssl_formation
