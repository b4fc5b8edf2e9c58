#include "ssl_formation/paper_model/paper_learning.hpp"

#include <stdexcept>

namespace ssl_formation {
inline namespace paper_model {

void PaperLearner::learn(const MatchMoment& moment) {
  for (const Transition& t : moment.sample.transitions) table_.add(t.from, t.to);
}

void PaperLearner::absorb(const Learner& other) {
  const auto* paper = dynamic_cast<const PaperLearner*>(&other);
  if (!paper) throw std::invalid_argument("a training of another model cannot be added");
  table_.merge(paper->table_);  // checks the grid
}

std::optional<StoredTable> PaperLearner::stored(const TableMetadata& metadata) const {
  return StoredTable{table_, metadata};
}

std::optional<TableSummary> PaperLearner::table_summary() const {
  return TableSummary{table_.grid(), table_.transitions(), table_.rows_seen(),
                      table_.memory_bytes(), std::nullopt};
}

std::unique_ptr<Forecaster> PaperLearner::forecaster(const TableMetadata& metadata) const {
  auto forecaster = std::make_unique<PaperForecaster>();
  forecaster->set_table(std::make_shared<const StoredTable>(StoredTable{table_, metadata}));
  return forecaster;
}

void PaperForecaster::forecast(const MatchMoment& moment, int steps, Prediction& out, ForecastUse) {
  robot_states_.clear();
  for (const FormationRobot& robot : moment.formation().robots) {
    robot_states_.push_back({robot.robot_id, robot.state});
  }
  predict(table_->table, robot_states_, steps, out);
  // The paper's model states cells: their centres stand for its positions.
  const Grid& grid = moment.codec.grid();
  for (PredictedStep& step : out.steps) {
    for (RobotPrediction& robot : step.robots) {
      robot.normalised_position = grid.centre_of(robot.position, moment.field);
      robot.feed_position = normalise(robot.normalised_position, moment.attacks);
    }
  }
}

}  // namespace paper_model
}  // namespace ssl_formation
