#pragma once
// The two models that learn into a table file: the paper's (transition counts on cells) and the
// motion model (the paper's counts at every frame, plus how each robot moves). Made by the
// factory only.

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "ssl_formation/files/table_file.hpp"
#include "ssl_formation/models/model.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/motion_model/set_play_memory.hpp"
#include "ssl_formation/paper_model/predictor.hpp"

namespace ssl_formation::models {

class PaperLearner : public Learner {
 public:
  explicit PaperLearner(TransitionTable table) : table_(std::move(table)) {}
  void observe(const MatchMoment&) override {}
  void learn(const MatchMoment& moment) override;
  void forget_match() override {}
  void absorb(const Learner& other) override;
  std::uint64_t progress() const override { return table_.transitions(); }
  const TransitionTable* transitions() const override { return &table_; }
  std::unique_ptr<Forecaster> forecaster(const TableMetadata& metadata) const override;

 private:
  TransitionTable table_;
};

class MotionLearner : public Learner {
 public:
  // `recalibration`: what the forecasters it makes recalibrate with.
  // `pooled`: its forecasters are the pooled ablation (ModelSettings::pooled_motion).
  // `rows_in_memory`: ModelSettings::motion_rows_in_memory.
  MotionLearner(
      TransitionTable table, MotionTable motion,
      std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{},
      bool pooled = false, std::size_t rows_in_memory = ModelSettings{}.motion_rows_in_memory);
  void observe(const MatchMoment& moment) override;
  void learn(const MatchMoment& moment) override;
  void forget_match() override;
  void absorb(const Learner& other) override;
  std::uint64_t progress() const override {
    return table_.transitions() + motion_.instances() + motion_.held_out();
  }
  const TransitionTable* transitions() const override { return &table_; }
  const MotionTable* motion() const override { return &motion_; }
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

class MotionForecaster : public Forecaster {
 public:
  explicit MotionForecaster(const ModelSettings& settings);
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
    settings.pooled = settings_.pooled_motion;
    return settings;
  }
  // What the forecaster keeps of a table: the model built of its rows, and its kick-offs. Not
  // the rows: a season's table is tens of megabytes that no forecast reads again.
  struct BuiltTable {
    std::shared_ptr<const MotionModel> model;
    SetPlayMemory set_plays;
  };
  ModelSettings settings_;
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

}  // namespace ssl_formation::models
