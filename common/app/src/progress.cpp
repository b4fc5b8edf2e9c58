#include "ssl_formation/app/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace ssl_formation::app {

ProgressBar::ProgressBar(std::string label, std::uint64_t total_bytes)
    : label_(std::move(label)),
      total_(std::max<std::uint64_t>(total_bytes, 1)),
      terminal_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

void ProgressBar::update(std::uint64_t done_bytes, std::uint64_t items) {
  const auto now = std::chrono::steady_clock::now();
  if (terminal_) {
    if (now - last_draw_ < std::chrono::milliseconds(200)) return;
  } else {
    const int decile = static_cast<int>(10 * done_bytes / total_);
    if (decile == last_decile_) return;
    last_decile_ = decile;
  }
  last_draw_ = now;
  draw(done_bytes, items, false);
}

void ProgressBar::finish(std::uint64_t items) { draw(total_, items, true); }

void ProgressBar::draw(std::uint64_t done_bytes, std::uint64_t items, bool final) {
  const double fraction =
      std::min(1.0, static_cast<double>(done_bytes) / static_cast<double>(total_));
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(items) / elapsed : 0.0;
  const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
  constexpr int width = 30;
  const int filled = static_cast<int>(fraction * width);
  char bar[width + 1];
  for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
  bar[width] = '\0';
  std::fprintf(stderr, "%s%s [%s] %5.1f%%  %.0f frames/s  %s %.1f s%s", terminal_ ? "\r" : "",
               label_.c_str(), bar, 100.0 * fraction, rate, final ? "took" : "ETA",
               final ? elapsed : eta, terminal_ && !final ? "" : "\n");
  std::fflush(stderr);
}

}  // namespace ssl_formation::app
