#pragma once
// The daemons' time, given to them rather than read inside them: the process's clocks in the
// programs, a clock a test moves by hand when it drives a daemon in-process.

#include <cstdint>

namespace ssl_formation::app {

class Clock {
 public:
  virtual ~Clock() = default;
  // Seconds on a clock that never goes back: what timers, ages and live receive times use.
  virtual double steady_s() const = 0;
  // The wall clock in milliseconds since the Unix epoch: only to date things for people.
  virtual std::int64_t unix_ms() const = 0;
};

// The process's steady and wall clocks.
class SystemClock final : public Clock {
 public:
  double steady_s() const override;
  std::int64_t unix_ms() const override;
};

// A clock that moves only when told: for tests.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(double steady_s = 1000.0, std::int64_t unix_ms = 1'700'000'000'000)
      : steady_s_(steady_s), unix_ms_(unix_ms) {}
  double steady_s() const override { return steady_s_; }
  std::int64_t unix_ms() const override { return unix_ms_; }
  void advance(double seconds) {
    steady_s_ += seconds;
    unix_ms_ += static_cast<std::int64_t>(seconds * 1000.0);
  }

 private:
  double steady_s_;
  std::int64_t unix_ms_;
};

}  // namespace ssl_formation::app
