#pragma once
// Training: the sampler feeding the transition table. The live trainer, offline training from
// logs and the tests all run exactly this code, fed from a socket, a file or a vector.

#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>

#include "ssl_formation/match/match.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/paper_model/transition_table.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {

// How training follows the match: who the opponent is, and which game states it learns in.
struct MatchRules {
  OpponentChoice opponent;
  LearnDuring learn_during = LearnDuring::running;
};

class Training {
 public:
  // `table` may hold earlier counts (a resumed table); its grid must be the sampler's.
  // Throws std::invalid_argument if the grids differ.
  // With `motion` (which needs frame sampling: velocities come from the frames), the motion
  // model's rows are counted too, from the same samples. Throws std::invalid_argument for a
  // motion table with step sampling or another step than the sampler's.
  // Without `rules`, the opponent is the sampler's, fixed as if given by option (the referee
  // changes neither its colour nor its side), and learning is in running play.
  Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before = 0,
           std::optional<MotionTable> motion = std::nullopt,
           std::optional<MatchRules> rules = std::nullopt);
  // The sampler's handler points at this object's table.
  Training(const Training&) = delete;
  Training& operator=(const Training&) = delete;

  void add(const SSL_WrapperPacket& packet) { sampler_.add(packet); }
  void add(const VisionFrame& frame) { sampler_.add(frame); }
  // A referee message (a datagram, or a log's type-3 payload) in its place among the frames,
  // received at `receive_s`. The opponent's colour and side follow it as the rules allow; with
  // LearnDuring::running only running play is counted, and no transition spans a new command.
  // (A command takes effect from the next instant the vision completes: a frame held for a
  // camera still to report when it came counts under the new one.)
  RefereeChange add_referee(std::string_view payload, double receive_s);
  // A new log file: its first formation follows nothing (no transition across two files), and
  // its referee is heard anew.
  void start_new_stream();
  // Adds what `other` counted (another log's training, run apart: in another thread), as if this
  // training had counted it too: the tables merge, and its formations add to samples(). Throws
  // std::invalid_argument for tables of another grid, model or motion settings.
  void absorb(const Training& other);

  const TransitionTable& table() const { return table_; }
  const std::optional<MotionTable>& motion() const { return motion_; }
  const FormationSampler& sampler() const { return sampler_; }
  const MatchFollower& match() const { return match_; }
  LearnDuring learn_during() const { return learn_during_; }
  // Samples not learned from: outside running play, by the rules.
  std::uint64_t samples_outside_play() const { return samples_outside_play_; }
  // Formations sampled, including those of the resumed table.
  std::uint64_t samples() const { return samples_before_ + sampler_.counters().samples; }
  // Counts added since the last call to mark_saved(): lets a daemon skip saving an unchanged table.
  bool changed_since_save() const {
    return table_.transitions() != saved_transitions_ || samples() != saved_samples_ ||
           motion_instances() != saved_motion_instances_;
  }
  void mark_saved() {
    saved_transitions_ = table_.transitions();
    saved_samples_ = samples();
    saved_motion_instances_ = motion_instances();
  }

 private:
  void on_sample(const FormationSample& sample);
  // Hands the match's opponent to the sampler; another colour also forgets the motion history.
  void follow_opponent();
  std::uint64_t motion_instances() const {
    return motion_ ? motion_->instances() + motion_->held_out() : 0;
  }

  TransitionTable table_;
  std::optional<MotionTable> motion_;
  MotionHistory motion_history_;
  FormationSampler sampler_;
  MatchFollower match_;
  LearnDuring learn_during_;
  // The current command's first sample time (learning learns nothing from before it); +infinity
  // from a new command until its first sample.
  double segment_start_s_ = -std::numeric_limits<double>::infinity();
  std::uint64_t samples_outside_play_ = 0;
  std::uint64_t samples_before_;
  std::uint64_t saved_transitions_;
  std::uint64_t saved_samples_;
  std::uint64_t saved_motion_instances_;
};

}  // namespace ssl_formation
