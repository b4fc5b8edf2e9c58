#pragma once
// Prediction: the match's front end feeding a model's forecaster, the twin of Training. The live
// predictor, `ssl-predictor --from-log`, the evaluation, the benchmarks and the tests all run
// exactly this code, fed from sockets, a file, a match in memory or a vector: the match's events
// in, each sampled formation with its prediction out, on the data's own clock.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "ssl_formation/match/match.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/pipeline/live_score.hpp"
#include "ssl_formation/pipeline/match_front_end.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {
inline namespace pipeline {

struct PredictionConfig {
  SamplerConfig sampler = sampler_config_for(default_model);
  int horizon = 2;  // formations predicted ahead, 1 to max_horizon
  ModelKind model = default_model;
  // How the motion model's stated probabilities follow what the play lately did
  // (OnlineCalibration); none: as the table's calibration states them.
  std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{};
  // Who the opponent is, with the referee filling in what the options leave open; none: the
  // sampler's colour and side, fixed as if given by option.
  std::optional<OpponentChoice> opponent = std::nullopt;
  bool tracked_vision = false;  // --vision-source tracked (FrontEndConfig)
  // The motion model's prior (ModelSettings::prior_table): --prior-table.
  std::shared_ptr<const MotionTable> prior_table = nullptr;
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

class PredictionPipeline final : public MatchEventSink {
 public:
  using Handler = std::function<void(const PredictedFormation&)>;

  // Throws std::invalid_argument for a horizon out of range, a model that cannot run on the
  // sampler's sampling, or a bad sampler or recalibration configuration.
  PredictionPipeline(PredictionConfig config, Handler on_prediction);
  // The same with a forecaster of config.model made already (one a Learner made of what it
  // learned, in the evaluation), which carries its own settings (config.recalibration is the
  // learner's to give it).
  PredictionPipeline(PredictionConfig config, std::unique_ptr<Forecaster> forecaster,
                     Handler on_prediction);
  // The same on `shared`, a front end made with front_end_config(config) that others read too
  // (MatchFrontEnd::join): the evaluation predicts with every method of one sampling on one.
  // Events go to `shared`, which hands them to all its consumers; it must not be fed after this
  // pipeline is gone.
  PredictionPipeline(PredictionConfig config, std::unique_ptr<Forecaster> forecaster,
                     Handler on_prediction, MatchFrontEnd& shared);
  PredictionPipeline(const PredictionPipeline&) = delete;
  PredictionPipeline& operator=(const PredictionPipeline&) = delete;

  // The front end a pipeline of `config` reads.
  static FrontEndConfig front_end_config(const PredictionConfig& config);

  // The table predictions come from. A model that needs one samples formations until it has one
  // (so the data clock and the chains run on) and counts them, but predicts nothing. Throws
  // std::invalid_argument for a table of another grid than the sampler's, or one the model
  // cannot use (a version-1 table for the motion model), keeping the table it had.
  void set_table(std::shared_ptr<const StoredTable> table) {
    install_table(prepare_table(std::move(table)));
  }
  // set_table in two steps (Forecaster::prepare_table): a daemon prepares a new table on a thread
  // of its own, which is safe while this pipeline predicts (prepare_table reads only what is
  // fixed at construction), and installs it between two frames, cheaply. install_table returns
  // the table it replaces, for the caller to free off the prediction's path.
  PreparedTable prepare_table(std::shared_ptr<const StoredTable> table) const;
  PreparedTable install_table(PreparedTable prepared) noexcept;
  const std::shared_ptr<const StoredTable>& table() const { return table_; }
  // Whether the model needs a table to predict.
  bool needs_table() const { return describe(config_.model).keeps_table; }

  void on_event(const MatchEvent& event) override { front_end_.on_event(event); }
  // A new log file: its first formation follows nothing (no chain across two files), and its
  // referee is heard anew.
  void start_new_stream() override { front_end_.start_new_stream(); }
  // on_event(), returning what a referee message changed: the opponent's colour and side follow
  // it as the options allow, and every prediction says the game state it was made in.
  RefereeChange handle(const MatchEvent& event) { return front_end_.handle(event); }
  void add(const VisionFrame& frame) { front_end_.add(frame); }
  void add(const SSL_WrapperPacket& packet) { front_end_.add(packet); }
  RefereeChange add_referee(std::string_view payload, double receive_s) {
    return front_end_.add_referee(payload, receive_s);
  }

  // Predicts the last sampled formation again, as it was, counting nothing, and hands it to
  // `on_rehearsal` (not to the pipeline's handler). A daemon that waits ~16 ms between frames
  // finds its model's memory and code cold; rehearsing just before the next frame is due brings
  // them back, so the real prediction is quick. Returns false if there is nothing to rehearse
  // (no table, or no formation since the table was set).
  bool rehearse(const Handler& on_rehearsal);

  const PredictionConfig& config() const { return config_; }
  const MatchFrontEnd& front_end() const { return front_end_; }
  const FormationSampler& sampler() const { return front_end_.sampler(); }
  const MatchFollower& match() const { return front_end_.match(); }
  std::uint64_t predictions() const { return predictions_; }
  std::uint64_t samples_without_table() const { return samples_without_table_; }
  // How far the predictions have lately been, against "everyone stays" (LiveScore).
  const LiveScore& live_score() const { return live_score_; }
  // Why the model cannot predict from this feed, with the option that fixes it (none: it can,
  // or the pace is not known yet).
  std::optional<std::string> feed_problem() const;

 private:
  void on_sample(const MatchMoment& moment);
  // What was followed of the match no longer holds (a new stream, another opponent's colour).
  void forget_match();
  // Fills prediction_ and context_ for `moment` from the forecaster; false when it cannot yet.
  bool predict(const MatchMoment& moment, ForecastUse use);
  MatchFrontEnd::Handlers handlers();
  void reserve_buffers();

  PredictionConfig config_;
  Handler on_prediction_;
  std::unique_ptr<Forecaster> forecaster_;
  std::shared_ptr<const StoredTable> table_;
  LiveScore live_score_;
  std::unique_ptr<MatchFrontEnd> own_front_end_;  // none on a shared front end
  MatchFrontEnd& front_end_;
  Prediction prediction_;  // reused from sample to sample
  PredictionContext context_;
  // The last sample, as the front end handed it (the sampler's own buffer, unchanged until the
  // next frame completes one), for rehearse().
  std::optional<MatchMoment> last_moment_;
  std::uint64_t predictions_ = 0;
  std::uint64_t samples_without_table_ = 0;
};

}  // namespace pipeline
}  // namespace ssl_formation
