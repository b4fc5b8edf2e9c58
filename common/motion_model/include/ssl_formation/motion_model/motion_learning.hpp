#pragma once
// The motion model behind the model interface (model_api/model.hpp): it learns the paper's counts
// at every frame and, beside them, how each robot moves (MotionTable); it forecasts with the
// MotionModel built of a table, under the game's rules (game_rules.hpp), a kick-off's memory
// (set_play_memory.hpp) and braking advice (braking_advice.hpp), recalibrating its radii as it
// goes (online_calibration.hpp). Made by the factory (models/model_factory.hpp), which is the
// only code that names it.

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/motion_model/set_play_memory.hpp"

namespace ssl_formation {
inline namespace motion_model {

// The rows a learner holds before it prunes (MotionLearner): 2^16 rows take about 20 MB.
inline constexpr std::size_t default_motion_rows_in_memory = std::size_t{1} << 16;

// How a motion forecaster predicts.
struct MotionForecastSettings {
  Grid grid{3, 2};
  double step_s = 0.5;
  // The recalibration while it predicts (none: as the table states).
  std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{};
  // Every team's table, under the opponent's own rows (none: damped constant velocity is the
  // prior), and the field its probabilities are calibrated for until a table brings its own.
  std::shared_ptr<const MotionTable> prior_table = nullptr;
  FieldSize prior_field{9000.0, 6000.0};
  // One fit for every robot and state instead of the keyed rows (the pooled ablation).
  bool pooled = false;
};

class MotionLearner : public Learner {
 public:
  // `recalibration`: what the forecasters it makes recalibrate with.
  // `pooled`: its forecasters are the pooled ablation.
  // `rows_in_memory`: it prunes its table to half this many rows once it holds more (0: never).
  MotionLearner(
      TransitionTable table, MotionTable motion,
      std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{},
      bool pooled = false, std::size_t rows_in_memory = default_motion_rows_in_memory);
  void observe(const MatchMoment& moment) override;
  void learn(const MatchMoment& moment) override;
  void forget_match() override;
  void absorb(const Learner& other) override;
  std::uint64_t progress() const override {
    return table_.transitions() + motion_.instances() + motion_.held_out();
  }
  std::optional<StoredTable> stored(const TableMetadata& metadata) const override;
  std::optional<StoredTable> release_table(const TableMetadata& metadata) override;
  std::optional<TableSummary> table_summary() const override;
  std::unique_ptr<Forecaster> forecaster(const TableMetadata& metadata) const override;
  std::unique_ptr<Forecaster> forecaster(
      const TableMetadata& metadata, std::shared_ptr<const MotionTable> prior_table) const override;

 private:
  // Prunes the motion table once it holds more rows than rows_in_memory_.
  void bound_memory();

  TransitionTable table_;
  MotionTable motion_;
  std::size_t rows_in_memory_;
  MotionHistory history_;
  SetPlayRecorder set_plays_;
  std::optional<OnlineCalibrationSettings> recalibration_;
  bool pooled_ = false;
};

class MotionForecaster : public Forecaster {
 public:
  explicit MotionForecaster(const MotionForecastSettings& settings);
  // Builds the table's MotionModel (under the prior), which is what a table costs.
  PreparedTable prepare_table(std::shared_ptr<const StoredTable> table) const override;
  PreparedTable install_table(PreparedTable prepared) noexcept override;
  bool ready() const override { return model_ != nullptr; }
  void observe(const MatchMoment& moment) override;
  void forecast(const MatchMoment& moment, int steps, Prediction& out, ForecastUse use) override;
  void forget_match() override;

 private:
  MotionModelSettings model_settings() const {
    MotionModelSettings settings;
    settings.pooled = settings_.pooled;
    return settings;
  }
  // What the forecaster keeps of a table: the model built of its rows, and its kick-offs. Not
  // the rows: a season's table is tens of megabytes that no forecast reads again.
  struct BuiltTable {
    std::shared_ptr<const MotionModel> model;
    SetPlayMemory set_plays;
  };
  MotionForecastSettings settings_;
  std::shared_ptr<const BuiltTable> built_;
  // Every team's model (settings.prior_table), built for the first table's field; serves alone
  // until the opponent has a table. Like settings_, set once in the constructor: prepare_table
  // reads both from another thread.
  std::shared_ptr<const MotionModel> prior_model_;
  std::shared_ptr<const MotionModel> model_;  // built_'s (under the prior), or the prior
  MotionModel::Cache cache_;
  MotionHistory history_;
  OnlineCalibration calibration_;
  std::vector<MotionRobot> robots_;  // reused from sample to sample
  SetPlayAdvice set_play_advice_;    // reused from set play to set play
};

}  // namespace motion_model
}  // namespace ssl_formation
