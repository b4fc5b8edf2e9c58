#include "ssl_formation/training.hpp"

#include <cmath>
#include <stdexcept>

namespace ssl_formation {

Training::Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before,
                   std::optional<MotionTable> motion)
    : table_(std::move(table)),
      motion_(std::move(motion)),
      motion_history_(motion_ ? motion_->config() : MotionConfig{}),
      sampler_(config, [this](const FormationSample& sample) { on_sample(sample); }),
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
}

void Training::on_sample(const FormationSample& sample) {
  for (const Transition& t : sample.transitions) table_.add(t.from, t.to);
  if (motion_) {
    motion_history_.add(sample.formation);
    learn_motion(*motion_, motion_history_, sample.formation);
  }
}

}  // namespace ssl_formation
