#include "ssl_formation/training.hpp"

#include <stdexcept>

namespace ssl_formation {

Training::Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before)
    : table_(std::move(table)),
      sampler_(config,
               [this](const FormationSample& sample) {
                 for (const Transition& t : sample.transitions) table_.add(t.from, t.to);
               }),
      samples_before_(samples_before),
      saved_transitions_(table_.transitions()),
      saved_samples_(samples_before) {
  if (table_.grid() != config.grid) {
    throw std::invalid_argument("the table's grid " + table_.grid().to_string() +
                                " differs from the sampler's " + config.grid.to_string());
  }
}

}  // namespace ssl_formation
