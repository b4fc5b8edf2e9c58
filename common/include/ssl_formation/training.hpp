#pragma once
// Training: the sampler feeding the transition table. The live trainer, offline training from
// logs and the tests all run exactly this code, fed from a socket, a file or a vector.

#include <cstdint>
#include <optional>

#include "ssl_formation/motion_model.hpp"
#include "ssl_formation/sampler.hpp"
#include "ssl_formation/transition_table.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {

class Training {
 public:
  // `table` may hold earlier counts (a resumed table); its grid must be the sampler's.
  // Throws std::invalid_argument if the grids differ.
  // With `motion` (which needs frame sampling: velocities come from the frames), the motion
  // model's rows are counted too, from the same samples. Throws std::invalid_argument for a
  // motion table with step sampling or another step than the sampler's.
  Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before = 0,
           std::optional<MotionTable> motion = std::nullopt);
  // The sampler's handler points at this object's table.
  Training(const Training&) = delete;
  Training& operator=(const Training&) = delete;

  void add(const SSL_WrapperPacket& packet) { sampler_.add(packet); }
  void add(const VisionFrame& frame) { sampler_.add(frame); }
  // A new log file: its first formation follows nothing (no transition across two files).
  void start_new_stream() {
    sampler_.start_new_stream();
    motion_history_.clear();
  }

  const TransitionTable& table() const { return table_; }
  const std::optional<MotionTable>& motion() const { return motion_; }
  const FormationSampler& sampler() const { return sampler_; }
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
  std::uint64_t motion_instances() const {
    return motion_ ? motion_->instances() + motion_->held_out() : 0;
  }

  TransitionTable table_;
  std::optional<MotionTable> motion_;
  MotionHistory motion_history_;
  FormationSampler sampler_;
  std::uint64_t samples_before_;
  std::uint64_t saved_transitions_;
  std::uint64_t saved_samples_;
  std::uint64_t saved_motion_instances_;
};

}  // namespace ssl_formation
