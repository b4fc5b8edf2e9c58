#include "ssl_formation/pipeline/prediction_pipeline.hpp"

#include <stdexcept>
#include <string>
#include <utility>

namespace ssl_formation {
inline namespace pipeline {

namespace {

ModelSettings model_settings(const PredictionConfig& config) {
  ModelSettings settings;
  settings.grid = config.sampler.grid;
  settings.step_s = config.sampler.step_s;
  settings.horizons = config.horizon;
  settings.recalibration = config.recalibration;
  settings.prior_table = config.prior_table;
  return settings;
}

// Checks what can be checked before the forecaster and the sampler are made.
const PredictionConfig& checked(const PredictionConfig& config) {
  if (config.horizon < 1 || config.horizon > PredictionConfig::max_horizon) {
    throw std::invalid_argument("the horizon must be 1 to " +
                                std::to_string(PredictionConfig::max_horizon) + " formations");
  }
  if (const auto problem = sampling_problem(config.model, config.sampler.sampling)) {
    throw std::invalid_argument(*problem);
  }
  return config;
}

}  // namespace

FrontEndConfig PredictionPipeline::front_end_config(const PredictionConfig& config) {
  FrontEndConfig front;
  front.sampler = config.sampler;
  front.opponent = config.opponent;
  front.tracked_vision = config.tracked_vision;
  return front;
}

PredictionPipeline::PredictionPipeline(PredictionConfig config, Handler on_prediction)
    : PredictionPipeline(config, make_forecaster(checked(config).model, model_settings(config)),
                         std::move(on_prediction)) {}

PredictionPipeline::PredictionPipeline(PredictionConfig config,
                                       std::unique_ptr<Forecaster> forecaster,
                                       Handler on_prediction)
    : config_(checked(config)),
      on_prediction_(std::move(on_prediction)),
      forecaster_(std::move(forecaster)),
      own_front_end_(std::make_unique<MatchFrontEnd>(front_end_config(config_), handlers())),
      front_end_(*own_front_end_) {
  reserve_buffers();
}

PredictionPipeline::PredictionPipeline(PredictionConfig config,
                                       std::unique_ptr<Forecaster> forecaster,
                                       Handler on_prediction, MatchFrontEnd& shared)
    : config_(checked(config)),
      on_prediction_(std::move(on_prediction)),
      forecaster_(std::move(forecaster)),
      front_end_(shared) {
  front_end_.join(handlers());
  reserve_buffers();
}

MatchFrontEnd::Handlers PredictionPipeline::handlers() {
  return {[this](const MatchMoment& moment) { on_sample(moment); }, [this] { forget_match(); }};
}

void PredictionPipeline::reserve_buffers() {
  // The per-sample buffers, allocated together now rather than wherever the first sample
  // leaves them: a daemon woken every 16 ms pays for every cold page its hot path touches.
  constexpr std::size_t usual_robots = 16;
  prediction_.steps.resize(static_cast<std::size_t>(config_.horizon));
  for (PredictedStep& step : prediction_.steps) step.robots.reserve(usual_robots);
}

void PredictionPipeline::forget_match() {
  if (forecaster_) forecaster_->forget_match();
  live_score_.clear();  // predictions of the old team's robots would meet the new one's ids
  last_moment_.reset();
}

PreparedTable PredictionPipeline::prepare_table(std::shared_ptr<const StoredTable> table) const {
  if (table && table->table.grid() != config_.sampler.grid) {
    throw std::invalid_argument("the table's grid " + table->table.grid().to_string() +
                                " differs from the predictor's " +
                                config_.sampler.grid.to_string());
  }
  return forecaster_->prepare_table(std::move(table));  // throws for a table it cannot use
}

PreparedTable PredictionPipeline::install_table(PreparedTable prepared) noexcept {
  std::shared_ptr<const StoredTable> previous = std::exchange(table_, prepared.table);
  PreparedTable old = forecaster_->install_table(std::move(prepared));
  // Handed back even when the forecaster kept no copy of it, so that it is freed where the
  // caller chooses.
  if (!old.table) old.table = std::move(previous);
  return old;
}

std::optional<std::string> PredictionPipeline::feed_problem() const {
  return ssl_formation::feed_problem(config_.model, front_end_.recent_frame_gap_s());
}

void PredictionPipeline::on_sample(const MatchMoment& moment) {
  forecaster_->observe(moment);
  live_score_.observe(moment.formation());
  last_moment_.emplace(moment);
  // Holds the table for the handler's call even if the handler sets another one: the context
  // points into it.
  const std::shared_ptr<const StoredTable> stored = table_;
  if (!predict(moment, ForecastUse::predict)) {
    ++samples_without_table_;
    return;
  }
  live_score_.remember(prediction_, moment.formation(), config_.sampler.step_s, moment.phase);
  ++predictions_;
  if (on_prediction_) on_prediction_(PredictedFormation{moment.sample, prediction_, context_});
}

bool PredictionPipeline::rehearse(const Handler& on_rehearsal) {
  const std::shared_ptr<const StoredTable> stored = table_;  // as in on_sample
  if (!last_moment_ || !predict(*last_moment_, ForecastUse::rehearse)) return false;
  if (on_rehearsal) {
    on_rehearsal(PredictedFormation{last_moment_->sample, prediction_, context_});
  }
  return true;
}

bool PredictionPipeline::predict(const MatchMoment& moment, ForecastUse use) {
  if (!forecaster_->ready()) return false;
  PredictionContext& context = context_;
  context.codec = &moment.codec;
  context.field = moment.field;
  // The direction may be inferred (--opponent-attacks auto): the one this sample was taken with.
  context.opponent_attacks = moment.attacks;
  // The sampler's opponent now (the referee may have changed it since the start).
  context.opponent_color = sampler().config().opponent_color;
  context.step_s = config_.sampler.step_s;
  context.table_transitions = table_ ? table_->table.transitions() : 0;
  context.model = config_.model;
  context.game_state = moment.game_state;
  context.phase = moment.phase;
  forecaster_->forecast(moment, config_.horizon, prediction_, use);
  return true;
}

}  // namespace pipeline
}  // namespace ssl_formation
