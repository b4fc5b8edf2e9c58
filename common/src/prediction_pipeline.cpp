#include "ssl_formation/prediction_pipeline.hpp"

#include <stdexcept>
#include <string>

namespace ssl_formation {

PredictionPipeline::PredictionPipeline(PredictionConfig config, Handler on_prediction)
    : config_(config),
      on_prediction_(std::move(on_prediction)),
      sampler_(config.sampler, [this](const FormationSample& sample) { on_sample(sample); }) {
  if (config_.horizon < 1 || config_.horizon > PredictionConfig::max_horizon) {
    throw std::invalid_argument("the horizon must be 1 to " +
                                std::to_string(PredictionConfig::max_horizon) + " formations");
  }
  // The per-sample buffers, allocated together now rather than wherever the first sample
  // leaves them: a daemon woken every 16 ms pays for every cold page its hot path touches.
  constexpr std::size_t usual_robots = 16;
  robot_states_.reserve(usual_robots);
  prediction_.steps.resize(static_cast<std::size_t>(config_.horizon));
  for (PredictedStep& step : prediction_.steps) step.robots.reserve(usual_robots);
}

void PredictionPipeline::set_table(std::shared_ptr<const StoredTable> table) {
  if (table && table->table.grid() != config_.sampler.grid) {
    throw std::invalid_argument("the table's grid " + table->table.grid().to_string() +
                                " differs from the predictor's " +
                                config_.sampler.grid.to_string());
  }
  table_ = std::move(table);
}

void PredictionPipeline::on_sample(const FormationSample& sample) {
  if (!table_) {
    ++samples_without_table_;
    return;
  }
  // Holds the table for this call even if the handler sets another one.
  const std::shared_ptr<const StoredTable> stored = table_;
  robot_states_.clear();
  for (const FormationRobot& robot : sample.formation.robots) {
    robot_states_.push_back({robot.robot_id, robot.state});
  }
  predict(stored->table, robot_states_, config_.horizon, prediction_);
  PredictionContext context = prediction_context(stored->table, config_.sampler, sampler_.field());
  // The direction may be inferred (--opponent-attacks auto): the one this sample was taken with.
  context.opponent_attacks = sampler_.attacks().value_or(config_.sampler.opponent_attacks);
  ++predictions_;
  if (on_prediction_) on_prediction_(PredictedFormation{sample, prediction_, context});
}

}  // namespace ssl_formation
