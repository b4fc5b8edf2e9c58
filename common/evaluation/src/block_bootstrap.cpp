#include "ssl_formation/evaluation/block_bootstrap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>

namespace ssl_formation::evaluation {

namespace {

// The value at quantile q of `values` (sorted here), linear between order statistics as
// ErrorStats::percentile.
double quantile(std::vector<double>& values, double q) {
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(rank));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (rank - static_cast<double>(below)) * (values[above] - values[below]);
}

// None when no resample counted (every one drew none of the row's blocks, or a zero
// denominator): an interval of zeros would look like a real one.
std::optional<Interval> interval_of(std::vector<double>& values, double level) {
  if (values.empty()) return std::nullopt;
  const double tail = (1.0 - level) / 2.0;
  return Interval{quantile(values, tail), quantile(values, 1.0 - tail)};
}

}  // namespace

DataBlock data_block(std::size_t stream, double time_s, double block_s) {
  return {stream, static_cast<std::int64_t>(std::floor(time_s / block_s))};
}

void add_to_block(BlockedErrors& blocks, DataBlock block, const std::vector<double>& errors) {
  BlockSums& sums = blocks[block];
  if (sums.error_sums.empty()) sums.error_sums.assign(errors.size(), 0.0);
  if (sums.error_sums.size() != errors.size()) {
    throw std::invalid_argument("a block's errors come from as many methods as its first robot's");
  }
  ++sums.robots;
  for (std::size_t m = 0; m < errors.size(); ++m) sums.error_sums[m] += errors[m];
}

BlockResamples::BlockResamples(std::vector<DataBlock> universe, const BootstrapConfig& config)
    : universe_(std::move(universe)), level_(config.level), min_blocks_(config.min_blocks) {
  if (!(config.block_s > 0.0) || config.resamples < 0 || !(config.level > 0.0) ||
      !(config.level < 1.0)) {
    throw std::invalid_argument(
        "a block bootstrap needs blocks of positive seconds, no negative count of resamples and "
        "a level between 0 and 1");
  }
  std::sort(universe_.begin(), universe_.end());
  universe_.erase(std::unique(universe_.begin(), universe_.end()), universe_.end());
  if (universe_.empty()) return;
  // mt19937_64 and a draw by rejection then modulo, without bias: uniform_int_distribution's
  // algorithm is the library's, and the intervals should not move between standard libraries.
  std::mt19937_64 random(config.seed);
  const std::uint64_t n = universe_.size();
  const std::uint64_t limit =
      std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
  draws_.assign(static_cast<std::size_t>(config.resamples), std::vector<std::uint32_t>(n, 0));
  for (auto& draw : draws_) {
    for (std::uint64_t i = 0; i < n; ++i) {
      std::uint64_t x = random();
      while (x >= limit) x = random();
      ++draw[x % n];
    }
  }
}

RowIntervals bootstrap_row(const BlockedErrors& row, const BlockResamples& draws,
                           std::optional<std::size_t> best_baseline,
                           const std::vector<std::size_t>& model_over) {
  RowIntervals out;
  out.blocks = row.size();
  if (row.empty() || row.size() < draws.min_blocks() || draws.resamples() == 0) return out;
  const std::size_t methods = row.begin()->second.error_sums.size();
  if ((best_baseline && *best_baseline >= methods) ||
      std::any_of(model_over.begin(), model_over.end(),
                  [&](std::size_t m) { return m >= methods; })) {
    throw std::invalid_argument("a ratio's method is not one of the row's methods");
  }
  // The row's blocks' places in the universe.
  std::vector<std::pair<std::size_t, const BlockSums*>> blocks;
  const auto& universe = draws.universe();
  for (const auto& [block, sums] : row) {
    const auto it = std::lower_bound(universe.begin(), universe.end(), block);
    if (it == universe.end() || *it != block) {
      throw std::invalid_argument("a row's block is not among the blocks the resamples drew from");
    }
    blocks.emplace_back(static_cast<std::size_t>(it - universe.begin()), &sums);
  }
  std::vector<std::vector<double>> means(methods);
  std::vector<std::vector<double>> ratios(best_baseline ? methods : 0);
  std::vector<std::vector<double>> model_ratios(model_over.size());
  std::vector<double> sums(methods);
  for (std::size_t r = 0; r < draws.resamples(); ++r) {
    std::uint64_t robots = 0;
    std::fill(sums.begin(), sums.end(), 0.0);
    for (const auto& [b, block] : blocks) {
      const std::uint32_t times = draws.times(r, b);
      if (times == 0) continue;
      robots += times * block->robots;
      for (std::size_t m = 0; m < methods; ++m) sums[m] += times * block->error_sums[m];
    }
    if (robots == 0) continue;
    for (std::size_t j = 0; j < model_over.size(); ++j) {
      if (sums[model_over[j]] > 0.0) model_ratios[j].push_back(sums[0] / sums[model_over[j]]);
    }
    for (std::size_t m = 0; m < methods; ++m) {
      means[m].push_back(sums[m] / static_cast<double>(robots));
      if (best_baseline && sums[*best_baseline] > 0.0) {
        ratios[m].push_back(sums[m] / sums[*best_baseline]);
      }
    }
  }
  // Each set whole or not at all: a reader takes an interval for every method or none.
  const auto all_of = [&](std::vector<std::vector<double>>& sets) {
    std::vector<Interval> intervals;
    for (auto& values : sets) {
      const std::optional<Interval> interval = interval_of(values, draws.level());
      if (!interval) return std::vector<Interval>{};
      intervals.push_back(*interval);
    }
    return intervals;
  };
  out.mean = all_of(means);
  if (out.mean.empty()) return out;
  out.ratio = all_of(ratios);
  out.model_ratio = all_of(model_ratios);
  return out;
}

}  // namespace ssl_formation::evaluation
