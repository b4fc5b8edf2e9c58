#pragma once
// Errors in millimetres: the count and the mean exactly (summed in the order added), the median
// and any percentile (linear between order statistics, as numpy's default) from a histogram whose
// size does not grow with the errors added, so that an hour's log costs what ten minutes' do.
// Its bins are 1/128 mm wide up to 32 mm and 1/2048 to 1/4096 of their value beyond (0.25 mm at
// 1 m), up to about 1 km; each keeps its count, the sum of its errors and its smallest and largest
// error, so that up to three errors in a bin are known to within a float's rounding, and only the
// middle ones of a bin of more are taken as spread evenly around their mean, between the bin's
// smallest and largest (within the bin's width). On a short log that puts the printed figures
// (0.1 mm) where sorting every error put them.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ssl_formation::evaluation {

class ErrorStats {
 public:
  void add(double error_mm) {
    ++count_;
    sum_ += error_mm;
    pending_[pending_count_++] = error_mm;
    if (pending_count_ == pending_.size()) bin_pending();
  }
  std::size_t count() const { return static_cast<std::size_t>(count_); }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : 0.0; }
  double percentile(double p) const;  // p in [0, 100]; 0 without errors
  double median() const { return percentile(50.0); }

 private:
  struct Bin {
    std::uint32_t count = 0;
    float offset_sum = 0.0F;  // of each error's distance from the bin's low edge
    // The smallest and the largest error, in 1/65535 of the bin's width above its low edge.
    std::uint16_t lowest = 0xFFFF;
    std::uint16_t highest = 0;
  };
  // Puts the errors added since into their bins.
  void bin_pending() const;
  // The k-th smallest error (from 0), as the histogram knows it.
  double order_statistic(std::uint64_t k) const;

  std::uint64_t count_ = 0;
  double sum_ = 0.0;
  // Errors are binned a few dozen at a time: a bin is a cache miss, and misses that do not wait
  // for one another overlap.
  mutable std::array<double, 32> pending_{};
  mutable std::size_t pending_count_ = 0;
  // Bins come in pages made on first use: most of the range stays empty.
  mutable std::vector<std::vector<Bin>> pages_;
  mutable std::vector<std::uint64_t> page_counts_;
};

}  // namespace ssl_formation::evaluation
