#pragma once
// How sure a mean error is: a 95% interval from a block bootstrap over blocks of data time.
//
// Scored about 60 times a second, neighbouring instants say almost the same thing: a robot's
// error at one frame is nearly its error at the next, so the errors are not independent and an
// interval that treated them so would be far too narrow. The data clock is cut into blocks (10 s
// by default), each block's errors are summed, and whole blocks are drawn with replacement, as
// many as there are, a thousand times: the spread of the resampled means is the interval (the
// 2.5th and 97.5th percentiles). Every method and every row (game state, horizon) is resampled
// from the same draws, so a ratio of two methods' means keeps their pairing: the model and a
// baseline were scored on the same robots at the same instants.

#include <compare>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace ssl_formation::evaluation {

struct BootstrapConfig {
  int resamples = 1000;  // 0: no intervals
  double block_s = 10.0;
  // A fixed seed: the same data gives the same intervals, run after run.
  std::uint64_t seed = 20261205;
  double level = 0.95;
  // A row spread over fewer blocks than this gets no interval: its resamples would draw the same
  // few pieces of play again and again, and their spread would say nothing of the next match.
  std::size_t min_blocks = 5;
  bool enabled() const { return resamples > 0; }
};

// A block of data time: which test stream (each has its own clock) and which block_s of it.
struct DataBlock {
  std::size_t stream = 0;
  std::int64_t index = 0;
  friend auto operator<=>(const DataBlock&, const DataBlock&) = default;
};
DataBlock data_block(std::size_t stream, double time_s, double block_s);

// One block's share of a row: how many robots were scored in it and each method's summed error.
struct BlockSums {
  std::uint64_t robots = 0;
  std::vector<double> error_sums;  // by method
};
using BlockedErrors = std::map<DataBlock, BlockSums>;

// Adds `errors` (one per method, of one robot) to `block`'s sums.
void add_to_block(BlockedErrors& blocks, DataBlock block, const std::vector<double>& errors);

struct Interval {
  double low = 0.0;
  double high = 0.0;
};

// The draws: for each resample, how many times each block of the universe was drawn.
class BlockResamples {
 public:
  // `universe`: every block any row was scored in (sorted and without repeats by the caller or
  // not: it is sorted here).
  BlockResamples(std::vector<DataBlock> universe, const BootstrapConfig& config);
  std::size_t resamples() const { return draws_.size(); }
  const std::vector<DataBlock>& universe() const { return universe_; }
  // How many times block `b` (of universe()) was drawn in resample `r`.
  std::uint32_t times(std::size_t r, std::size_t b) const { return draws_[r][b]; }
  double level() const { return level_; }
  std::size_t min_blocks() const { return min_blocks_; }

 private:
  std::vector<DataBlock> universe_;
  std::vector<std::vector<std::uint32_t>> draws_;
  double level_ = 0.95;
  std::size_t min_blocks_ = 5;
};

// A row's intervals: each method's mean error, and each method's mean over the best baseline's.
// Both empty when the row has fewer blocks than the configuration's minimum.
struct RowIntervals {
  std::vector<Interval> mean;   // by method
  std::vector<Interval> ratio;  // by method; empty without a best baseline
  // The first method's (the model's) mean over each of `model_over`'s methods' (bootstrap_row).
  std::vector<Interval> model_ratio;
  std::size_t blocks = 0;  // the blocks the row was scored in
};

// The intervals of one row: each method's mean error, its ratio to method `best_baseline`'s
// (none: no ratios), and the first method's ratio to each method of `model_over` (the model's
// ablations). A resample that drew none of the row's blocks is left out.
RowIntervals bootstrap_row(const BlockedErrors& row, const BlockResamples& draws,
                           std::optional<std::size_t> best_baseline,
                           const std::vector<std::size_t>& model_over = {});

}  // namespace ssl_formation::evaluation
