#pragma once
// Prediction: the sampler feeding the predictor, the twin of Training. The live predictor,
// `ssl-predictor --from-log`, the evaluation, the benchmarks and the tests all run exactly this
// code, fed from a socket, a file or a vector: vision frames in, each sampled formation with its
// prediction out, on the data's own clock.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "ssl_formation/pipeline/live_score.hpp"
#include "ssl_formation/match/match.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/paper_model/predictor.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/files/table_file.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {

struct PredictionConfig {
  SamplerConfig sampler;
  int horizon = 2;  // formations predicted ahead, 1 to max_horizon
  ModelKind model = ModelKind::paper;
  // How the motion model's stated probabilities follow what the play lately did
  // (OnlineCalibration); none: as the table's calibration states them.
  std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{};
  // Who the opponent is, with the referee filling in what the options leave open; none: the
  // sampler's colour and side, fixed as if given by option.
  std::optional<OpponentChoice> opponent = std::nullopt;
  static constexpr int max_horizon = 100;
};

// One sampled formation and what was predicted from it. Valid only during the handler's call:
// the pipeline reuses its buffers for the next one.
struct PredictedFormation {
  const FormationSample& sample;
  const Prediction& prediction;
  const PredictionContext& context;
  const Formation& formation() const { return sample.formation; }
};

class PredictionPipeline {
 public:
  using Handler = std::function<void(const PredictedFormation&)>;

  // Throws std::invalid_argument for a horizon out of range or a bad sampler configuration.
  PredictionPipeline(PredictionConfig config, Handler on_prediction);
  // The sampler's handler points at this object.
  PredictionPipeline(const PredictionPipeline&) = delete;
  PredictionPipeline& operator=(const PredictionPipeline&) = delete;

  // The table predictions come from; until one is set, formations are sampled (so the data
  // clock and the chains run on) and counted, but nothing is predicted. Throws
  // std::invalid_argument for a table of another grid than the sampler's, or without the
  // counts the configured model needs (a version-1 table asked for the motion model).
  void set_table(std::shared_ptr<const StoredTable> table);
  const std::shared_ptr<const StoredTable>& table() const { return table_; }

  void add(const VisionFrame& frame) { sampler_.add(frame); }
  void add(const SSL_WrapperPacket& packet) { sampler_.add(packet); }
  // A referee message (a datagram, or a log's type-3 payload) in its place among the frames,
  // received at `receive_s`: the opponent's colour and side follow it as the options allow, and
  // every prediction says the game state it was made in.
  RefereeChange add_referee(std::string_view payload, double receive_s);
  // A new log file: its first formation follows nothing (no chain across two files), and its
  // referee is heard anew.
  void start_new_stream();

  // Predicts the last sampled formation again, as it was, counting nothing, and hands it to
  // `on_rehearsal` (not to the pipeline's handler). A daemon that waits ~16 ms between frames
  // finds its model's memory and code cold; rehearsing just before the next frame is due brings
  // them back, so the real prediction is quick. Returns false if there is nothing to rehearse
  // (no table, or no formation since the table was set).
  bool rehearse(const Handler& on_rehearsal);

  const PredictionConfig& config() const { return config_; }
  const FormationSampler& sampler() const { return sampler_; }
  const MatchFollower& match() const { return match_; }
  std::uint64_t predictions() const { return predictions_; }
  std::uint64_t samples_without_table() const { return samples_without_table_; }
  // How far the predictions have lately been, against "everyone stays" (LiveScore).
  const LiveScore& live_score() const { return live_score_; }

 private:
  void on_sample(const FormationSample& sample);
  // Fills prediction_ and context_ for `sample` from the current table; false without one.
  bool predict_sample(const FormationSample& sample);
  // Hands the match's opponent to the sampler; another colour also forgets what was followed of
  // the old one (its robots share the ids).
  void follow_opponent();

  PredictionConfig config_;
  Handler on_prediction_;
  std::shared_ptr<const StoredTable> table_;
  std::shared_ptr<const MotionModel> motion_model_;  // built from table_ for the motion model
  MotionModel::Cache motion_cache_;
  MotionHistory motion_history_;
  OnlineCalibration online_calibration_;
  LiveScore live_score_;
  FormationSampler sampler_;
  MatchFollower match_;
  // Reused from sample to sample, so that a steady stream allocates nothing once warmed up.
  std::vector<RobotStateById> robot_states_;
  std::vector<MotionRobot> motion_robots_;
  Prediction prediction_;
  PredictionContext context_;
  // The sampler's last sample (its own buffer, unchanged until the next frame completes one).
  const FormationSample* last_sample_ = nullptr;
  std::uint64_t predictions_ = 0;
  std::uint64_t samples_without_table_ = 0;
};

}  // namespace ssl_formation
