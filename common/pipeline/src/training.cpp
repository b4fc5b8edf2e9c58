#include "ssl_formation/pipeline/training.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace ssl_formation {

Training::Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before,
                   std::optional<MotionTable> motion, std::optional<MatchRules> rules)
    : table_(std::move(table)),
      motion_(std::move(motion)),
      motion_history_(motion_ ? motion_->config() : MotionConfig{}),
      sampler_(config, [this](const FormationSample& sample) { on_sample(sample); }),
      match_(rules ? rules->opponent
                   : fixed_opponent(config.opponent_color, config.opponent_attacks,
                                    config.infer_attacks)),
      learn_during_(rules ? rules->learn_during : LearnDuring::running),
      samples_before_(samples_before),
      saved_transitions_(table_.transitions()),
      saved_samples_(samples_before),
      saved_motion_instances_(motion_instances()) {
  if (motion_ && config.sampling != Sampling::frame) {
    throw std::invalid_argument(
        "the motion model learns from every frame: it needs --sampling frame");
  }
  if (motion_ && std::abs(motion_->config().step_s - config.step_s) > 1e-9) {
    throw std::invalid_argument("the motion table's step differs from the sampler's");
  }
  if (table_.grid() != config.grid) {
    throw std::invalid_argument("the table's grid " + table_.grid().to_string() +
                                " differs from the sampler's " + config.grid.to_string());
  }
  follow_opponent();
}

RefereeChange Training::add_referee(std::string_view payload, double receive_s) {
  const RefereeChange change = match_.add_referee(payload, receive_s);
  if (!change.any()) return change;
  follow_opponent();
  if (change.command && learn_during_ == LearnDuring::running) {
    sampler_.start_new_segment();
    segment_start_s_ = std::numeric_limits<double>::infinity();
  }
  return change;
}

void Training::start_new_stream() {
  sampler_.start_new_stream();
  motion_history_.clear();
  match_.reset();
  follow_opponent();
  segment_start_s_ = -std::numeric_limits<double>::infinity();
}

void Training::absorb(const Training& other) {
  if (motion_.has_value() != other.motion_.has_value()) {
    throw std::invalid_argument("a training of the other model cannot be added");
  }
  if (motion_ && !(motion_->config() == other.motion_->config())) {
    throw std::invalid_argument("a training with other motion model settings cannot be added");
  }
  table_.merge(other.table_);  // checks the grid
  if (motion_) motion_->merge(*other.motion_);
  samples_before_ += other.samples();
}

void Training::follow_opponent() {
  const Opponent& opponent = match_.opponent();
  // The motion history keys robots by id, which the other team's robots share.
  if (opponent.color != sampler_.config().opponent_color) motion_history_.clear();
  sampler_.set_opponent(opponent.color, opponent.attacks);
}

void Training::on_sample(const FormationSample& sample) {
  if (segment_start_s_ == std::numeric_limits<double>::infinity()) {
    segment_start_s_ = sample.formation.time_s;
  }
  const bool learning = match_.learning(learn_during_);
  if (learning) {
    for (const Transition& t : sample.transitions) table_.add(t.from, t.to);
  } else {
    ++samples_outside_play_;
  }
  if (motion_) {
    // Followed in every state, so that velocities are known when play starts again.
    motion_history_.add(sample.formation);
    if (learning) learn_motion(*motion_, motion_history_, sample.formation, segment_start_s_);
  }
}

}  // namespace ssl_formation
