#include "ssl_formation/app/clock.hpp"

#include <chrono>

namespace ssl_formation::app {

double SystemClock::steady_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::int64_t SystemClock::unix_ms() const {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace ssl_formation::app
