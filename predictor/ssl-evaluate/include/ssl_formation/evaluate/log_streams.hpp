#pragma once
// Logs as the evaluation's streams (evaluation::EventStream): read from the file each time they
// are replayed, so that nothing of a log stays in memory however long it is. A part of a log in
// time is what RecordedMatch::split gives of it, without holding the log.

#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "ssl_formation/evaluation/position_evaluation.hpp"

namespace ssl_formation::evaluate {

// The events of a log whose count of vision events before them lies in [first, end): a split
// after n vision events has the head {0, n} and the tail {n, no end}.
struct VisionRange {
  std::uint64_t first = 0;
  std::uint64_t end = std::numeric_limits<std::uint64_t>::max();
};

class LogFile {
 public:
  // Throws std::runtime_error naming the file if it cannot be opened as a log.
  explicit LogFile(const std::string& path);
  // Its vision events (up to where it stops being readable), read once and remembered.
  std::uint64_t vision_events() const;
  // Its events in `range`, read from the file at each replay. A file that stops being readable
  // gives what came before, with a warning (once per file); with nothing before, the replay
  // throws std::runtime_error.
  evaluation::EventStream stream(VisionRange range = {}) const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace ssl_formation::evaluate
