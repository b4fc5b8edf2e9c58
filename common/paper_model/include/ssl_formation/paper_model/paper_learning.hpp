#pragma once
// The paper's model behind the model interface (model_api/model.hpp): it learns the transition
// counts on cells and forecasts from them with the paper's predictor. Made by the factory
// (models/model_factory.hpp), which is the only code that names it.

#include <memory>
#include <optional>
#include <vector>

#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/paper_model/predictor.hpp"

namespace ssl_formation {
inline namespace paper_model {

class PaperLearner : public Learner {
 public:
  explicit PaperLearner(TransitionTable table) : table_(std::move(table)) {}
  void observe(const MatchMoment&) override {}
  void learn(const MatchMoment& moment) override;
  void forget_match() override {}
  void absorb(const Learner& other) override;
  std::uint64_t progress() const override { return table_.transitions(); }
  std::optional<StoredTable> stored(const TableMetadata& metadata) const override;
  std::optional<TableSummary> table_summary() const override;
  std::unique_ptr<Forecaster> forecaster(const TableMetadata& metadata) const override;

 private:
  TransitionTable table_;
};

class PaperForecaster : public Forecaster {
 public:
  PreparedTable install_table(PreparedTable prepared) noexcept override {
    PreparedTable old{std::move(table_), nullptr};
    table_ = std::move(prepared.table);
    return old;
  }
  bool ready() const override { return table_ != nullptr; }
  void observe(const MatchMoment&) override {}
  void forecast(const MatchMoment& moment, int steps, Prediction& out, ForecastUse use) override;
  void forget_match() override {}

 private:
  std::shared_ptr<const StoredTable> table_;
  std::vector<RobotStateById> robot_states_;  // reused from sample to sample
};

}  // namespace paper_model
}  // namespace ssl_formation
