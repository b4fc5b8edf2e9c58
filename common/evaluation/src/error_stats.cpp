#include "ssl_formation/evaluation/error_stats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <optional>

namespace ssl_formation::evaluation {

namespace {

// The bins, in units of 1/128 mm: `linear` bins of one unit, then octaves of `per_octave` bins,
// each octave's twice as wide as the one below; the last bin also holds whatever lies beyond.
constexpr double units_per_mm = 128.0;
constexpr std::uint64_t linear = 4096;
constexpr std::uint64_t per_octave = linear / 2;
constexpr int linear_bits = std::bit_width(linear) - 1;
constexpr int octaves = 15;  // up to 32 mm x 2^15, about 1 km
constexpr std::size_t bins = linear + per_octave * octaves;
constexpr std::size_t page_bins = 256;
constexpr std::size_t pages = (bins + page_bins - 1) / page_bins;

struct Edges {
  double low = 0.0;
  double width = 0.0;
};

Edges edges_of(std::size_t bin) {
  if (bin < linear) return {static_cast<double>(bin) / units_per_mm, 1.0 / units_per_mm};
  const std::uint64_t above = bin - linear;
  const auto shift = static_cast<int>(above / per_octave) + 1;
  const std::uint64_t first = (above % per_octave + per_octave) << shift;
  return {static_cast<double>(first) / units_per_mm,
          static_cast<double>(std::uint64_t{1} << shift) / units_per_mm};
}

}  // namespace

void ErrorStats::bin_pending() const {
  if (pages_.empty()) {
    pages_.resize(pages);
    page_counts_.assign(pages, 0);
  }
  for (std::size_t i = 0; i < pending_count_; ++i) {
    const double error_mm = pending_[i];
    // The bin, and where in it the error lies: what lies outside the range (a negative error, which
    // no distance gives, one beyond the last bin, or not a number) goes to the first or last bin
    // and adds nothing to the estimate of where in its bin it lies.
    const double units = error_mm * units_per_mm;
    std::size_t bin = bins - 1;
    std::optional<double> offset_units;
    double width_units = 0.0;
    if (units < 0.0) {
      bin = 0;
    } else if (units < static_cast<double>(linear)) {
      bin = static_cast<std::size_t>(units);
      offset_units = units - static_cast<double>(bin);
      width_units = 1.0;
    } else if (units < static_cast<double>(linear << octaves)) {
      const auto q = static_cast<std::uint64_t>(units);
      const int shift = std::bit_width(q) - linear_bits;  // 1 for [linear, 2 x linear)
      bin = static_cast<std::size_t>(linear + per_octave * static_cast<std::uint64_t>(shift - 1) +
                                     (q >> shift) - per_octave);
      offset_units = units - static_cast<double>((q >> shift) << shift);
      width_units = static_cast<double>(std::uint64_t{1} << shift);
    }
    std::vector<Bin>& page = pages_[bin / page_bins];
    if (page.empty()) page.resize(page_bins);
    Bin& b = page[bin % page_bins];
    ++b.count;
    if (offset_units) {
      b.offset_sum += static_cast<float>(*offset_units / units_per_mm);
      const auto fraction =
          static_cast<std::uint16_t>(std::lround(*offset_units / width_units * 65535.0));
      b.lowest = std::min(b.lowest, fraction);
      b.highest = std::max(b.highest, fraction);
    }
    ++page_counts_[bin / page_bins];
  }
  pending_count_ = 0;
}

double ErrorStats::order_statistic(std::uint64_t k) const {
  std::uint64_t before = 0;
  std::size_t p = 0;
  while (before + page_counts_[p] <= k) before += page_counts_[p++];
  const std::vector<Bin>& page = pages_[p];
  std::size_t i = 0;
  while (before + page[i].count <= k) before += page[i++].count;
  const Bin& bin = page[i];
  const Edges e = edges_of(p * page_bins + i);
  const double sum = static_cast<double>(bin.offset_sum);
  const std::uint64_t n = bin.count;
  if (n == 1) return e.low + sum;
  const double lowest = static_cast<double>(bin.lowest) / 65535.0 * e.width;
  const double highest = static_cast<double>(bin.highest) / 65535.0 * e.width;
  const std::uint64_t j = k - before;  // of the bin's errors, from its smallest
  if (j == 0 || n == 2) return e.low + (j == 0 ? lowest : sum - lowest);
  if (j == n - 1) return e.low + highest;
  // The errors between the smallest and the largest: evenly spaced around their mean, as far
  // apart as the smallest and largest allow.
  const double middle = static_cast<double>(n - 2);
  const double mean = std::clamp((sum - lowest - highest) / middle, lowest, highest);
  const double room = std::min(mean - lowest, highest - mean);
  const double spacing =
      n == 3 ? 0.0 : std::min((highest - lowest) / (middle + 1.0), 2.0 * room / (middle - 1.0));
  return e.low + mean + (static_cast<double>(j - 1) - (middle - 1.0) / 2.0) * spacing;
}

double ErrorStats::percentile(double p) const {
  if (count_ == 0) return 0.0;
  bin_pending();
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(count_ - 1);
  const auto below = static_cast<std::uint64_t>(std::floor(rank));
  const std::uint64_t above = std::min(below + 1, count_ - 1);
  const double fraction = rank - static_cast<double>(below);
  const double low = order_statistic(below);
  const double high = above == below ? low : order_statistic(above);
  return low + fraction * (high - low);
}

}  // namespace ssl_formation::evaluation
