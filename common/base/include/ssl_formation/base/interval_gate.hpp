#pragma once
// Lets instants of the data clock through at most once per interval: training's learning
// instants and the recalibration's remembering and refreshing. Frames 16 ms apart say almost the
// same thing, so each of these works at a pace of its own rather than at every frame.

#include <optional>

namespace ssl_formation {
inline namespace base {

class IntervalGate {
 public:
  // Instants a whole interval apart on the data clock may differ by a rounding less.
  static constexpr double slack_s = 1e-6;

  // True, and `time_s` becomes the last instant let through, for the first instant, one before
  // the last (the clock went back) or one at least `interval_s` after it.
  bool pass(double time_s, double interval_s) {
    if (last_s_ && time_s >= *last_s_ && time_s - *last_s_ < interval_s - slack_s) return false;
    last_s_ = time_s;
    return true;
  }
  std::optional<double> last_s() const { return last_s_; }
  void reset() { last_s_.reset(); }

 private:
  std::optional<double> last_s_;
};

}  // namespace base
}  // namespace ssl_formation
