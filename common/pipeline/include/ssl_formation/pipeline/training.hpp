#pragma once
// Training: the match's front end feeding a model's learner. The live trainer, offline training
// from logs, the evaluation and the tests all run exactly this code, fed from sockets, a file, a
// match in memory or a vector.

#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>

#include "ssl_formation/match/match.hpp"
#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/pipeline/match_front_end.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {
inline namespace pipeline {

// How training follows the match: who the opponent is, and which game states it learns in.
struct MatchRules {
  OpponentChoice opponent;
  LearnDuring learn_during = LearnDuring::all;
};

struct TrainingConfig {
  SamplerConfig sampler;
  // None: the opponent is the sampler's, fixed as if given by option (the referee changes
  // neither its colour nor its side), and learning is in running play.
  std::optional<MatchRules> rules;
  bool tracked_vision = false;  // --vision-source tracked (FrontEndConfig)
};

class Training final : public MatchEventSink {
 public:
  // `learner` is a learner of `model` (model_factory.hpp); it may hold earlier counts (a resumed
  // table) from `samples_before` formations. Throws std::invalid_argument when the model cannot
  // run on the sampler's sampling, or a table's grid or step differs from the sampler's.
  Training(TrainingConfig config, ModelKind model, std::unique_ptr<Learner> learner,
           std::uint64_t samples_before = 0);
  // A table model's training: the motion model's with `motion` (which needs frame sampling:
  // velocities come from the frames, and its step must be the sampler's), the paper's without.
  // `table` may hold earlier counts (a resumed table).
  Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before = 0,
           std::optional<MotionTable> motion = std::nullopt,
           std::optional<MatchRules> rules = std::nullopt);
  // The same on `shared`, a front end made with front_end_config(config) that others read too
  // (MatchFrontEnd::join): the evaluation trains every method of one sampling on one. Events go
  // to `shared`, which hands them to all its consumers; it must not be fed after this training
  // is gone.
  Training(TrainingConfig config, ModelKind model, std::unique_ptr<Learner> learner,
           MatchFrontEnd& shared);
  Training(const Training&) = delete;
  Training& operator=(const Training&) = delete;

  // The front end a training of `config` reads.
  static FrontEndConfig front_end_config(const TrainingConfig& config);

  void on_event(const MatchEvent& event) override { front_end_.on_event(event); }
  // A new log file: its first formation follows nothing (no transition across two files), and
  // its referee is heard anew.
  void start_new_stream() override { front_end_.start_new_stream(); }
  // on_event(), returning what a referee message changed. The opponent's colour and side follow
  // the referee as the rules allow; with LearnDuring::running only running play is learned, and
  // nothing spans a new command (which takes effect from the next instant the vision completes).
  RefereeChange handle(const MatchEvent& event) { return front_end_.handle(event); }
  void add(const SSL_WrapperPacket& packet) { front_end_.add(packet); }
  void add(const VisionFrame& frame) { front_end_.add(frame); }
  RefereeChange add_referee(std::string_view payload, double receive_s) {
    return front_end_.add_referee(payload, receive_s);
  }

  // Adds what `other` learned (another log's training, run apart: in another thread), as if this
  // training had learned it too: the tables merge, and its formations add to samples(). Throws
  // std::invalid_argument for another model or other settings.
  void absorb(const Training& other);

  ModelKind model() const { return model_; }
  const Learner& learner() const { return *learner_; }
  // What its table holds so far, for a status line (throws std::logic_error for a model that
  // keeps no table).
  TableSummary table_summary() const;
  // Whether its model keeps a table.
  bool keeps_table() const { return learner_->table_summary().has_value(); }
  // What a table file keeps of this training, with `metadata` (a copy: training may go on).
  // Throws std::logic_error for a model that keeps no table.
  StoredTable stored_table(const TableMetadata& metadata) const;
  // The same with the metadata of this training: the field its sampler uses, its step, and the
  // formations sampled.
  StoredTable stored_table() const;
  // stored_table(metadata) without a copy, for a caller done with this training: it is left
  // without what it learned.
  StoredTable release_table(const TableMetadata& metadata);
  const MatchFrontEnd& front_end() const { return front_end_; }
  const FormationSampler& sampler() const { return front_end_.sampler(); }
  const MatchFollower& match() const { return front_end_.match(); }
  LearnDuring learn_during() const { return learn_during_; }
  // Why the model cannot learn from this feed, with the option that fixes it (none: it can, or
  // the pace is not known yet).
  std::optional<std::string> feed_problem() const;
  // Samples not learned from: outside running play, by the rules.
  std::uint64_t samples_outside_play() const { return samples_outside_play_; }
  // Formations sampled, including those of the resumed table.
  std::uint64_t samples() const { return samples_before_ + sampler().counters().samples; }
  // Counts added since the last call to mark_saved(): lets a daemon skip saving an unchanged table.
  bool changed_since_save() const {
    return learner_->progress() != saved_progress_ || samples() != saved_samples_;
  }
  void mark_saved() {
    saved_progress_ = learner_->progress();
    saved_samples_ = samples();
  }

 private:
  Training(TrainingConfig config, ResumedLearner resumed, std::uint64_t samples_before);
  void on_sample(const MatchMoment& moment);
  MatchFrontEnd::Handlers handlers();

  ModelKind model_;
  std::unique_ptr<Learner> learner_;
  LearnDuring learn_during_;
  std::unique_ptr<MatchFrontEnd> own_front_end_;  // none on a shared front end
  MatchFrontEnd& front_end_;
  std::uint64_t samples_outside_play_ = 0;
  std::uint64_t samples_before_;
  std::uint64_t saved_progress_;
  std::uint64_t saved_samples_;
};

}  // namespace pipeline
}  // namespace ssl_formation
