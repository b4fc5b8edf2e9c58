#pragma once
// A progress bar on stderr for long offline runs: bytes done of a total, rate and ETA. On a
// terminal it redraws one line; otherwise (a log file, CI) it prints a line every 10%.

#include <chrono>
#include <cstdint>
#include <string>

namespace ssl_formation::app {

class ProgressBar {
 public:
  // `label` names the work ("training from match.log.gz"); `total_bytes` is what 100% means.
  ProgressBar(std::string label, std::uint64_t total_bytes);
  // `items` is what the rate counts (frames). Redraws at most 5 times a second; it reads the
  // clock, so call it every few thousand frames, not for every one.
  void update(std::uint64_t done_bytes, std::uint64_t items);
  void finish(std::uint64_t items);

 private:
  void draw(std::uint64_t done_bytes, std::uint64_t items, bool final);

  std::string label_;
  std::uint64_t total_;
  bool terminal_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_decile_ = -1;
};

}  // namespace ssl_formation::app
