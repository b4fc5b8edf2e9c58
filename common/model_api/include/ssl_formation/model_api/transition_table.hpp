#pragma once
// The transition count table of the paper (§3.3): S x S counts, FROM state by row and TO state
// by column, with the row totals and the centroid-block matrix C[t][c] (§5.1) kept up to date on
// every count, so a prediction never re-sums a block.
//
// Small grids store the counts densely (S*S entries, the paper's "vector matrix"); large grids
// store only the transitions seen, in sorted rows, so a 12x9 table (S = 1,259,712) costs memory
// in proportion to what it has learned, not S^2.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/state.hpp"

namespace ssl_formation {
inline namespace model_api {

enum class TableStorage { automatic, dense, sparse };

class TransitionTable {
 public:
  using Count = std::uint32_t;
  static constexpr Count max_count = std::numeric_limits<Count>::max();
  // Above this many entries (16 MiB of counts) `automatic` storage chooses sparse.
  static constexpr std::uint64_t dense_entry_limit = std::uint64_t{1} << 22;
  // Above this (1 GiB of counts) even an explicit `dense` request gets sparse storage: a 16x16
  // grid would need a petabyte. Both layouts answer every query identically.
  static constexpr std::uint64_t dense_entry_hard_limit = std::uint64_t{1} << 28;

  explicit TransitionTable(Grid grid, TableStorage storage = TableStorage::automatic);
  ~TransitionTable();
  TransitionTable(TransitionTable&&) noexcept;
  TransitionTable& operator=(TransitionTable&&) noexcept;
  TransitionTable(const TransitionTable&);
  TransitionTable& operator=(const TransitionTable&);

  const Grid& grid() const { return codec_.grid(); }
  const StateCodec& codec() const { return codec_; }
  bool is_dense() const;

  // Adds n to count(from, to). Counts saturate at max_count instead of wrapping; the returned
  // value is what was really added, and the totals grow by exactly that.
  Count add(StateIndex from, StateIndex to, Count n = 1);

  Count count(StateIndex from, StateIndex to) const;
  std::uint64_t row_total(StateIndex from) const;
  // Sum of the block of rows with centroid `from_centroid` and columns with centroid
  // `to_centroid` (cell ids).
  std::uint64_t centroid_count(StateIndex from_centroid, StateIndex to_centroid) const {
    return centroid_counts_[from_centroid * codec_.cell_count() + to_centroid];
  }
  std::uint64_t centroid_total(StateIndex from_centroid) const {
    return centroid_totals_[from_centroid];
  }

  std::uint64_t transitions() const { return transitions_; }  // sum of all counts
  std::size_t nonzero_entries() const;
  std::size_t rows_seen() const;  // FROM states with at least one count
  std::size_t memory_bytes() const;

  // The most counted TO state among those with centroid `to_centroid` and previous cell
  // `previous` (cell ids) in row `from`: the velocity-consistent candidates.
  // Ties go to the lowest index. best_count == 0 means no candidate was ever counted.
  struct BestSuccessor {
    StateIndex state = 0;
    Count best_count = 0;
    std::uint64_t candidates_total = 0;
  };
  BestSuccessor best_successor(StateIndex from, StateIndex to_centroid, StateIndex previous) const;

  // Every nonzero count in increasing (from, to) order.
  void for_each_nonzero(const std::function<void(StateIndex, StateIndex, Count)>& visit) const;

  // Adds every count of `other`. Throws std::invalid_argument if the grids differ.
  void merge(const TransitionTable& other);

 private:
  struct Storage;
  StateCodec codec_;
  std::unique_ptr<Storage> storage_;
  std::vector<std::uint64_t> centroid_counts_;  // C x C
  std::vector<std::uint64_t> centroid_totals_;  // C
  std::uint64_t transitions_ = 0;
};

}  // namespace model_api
}  // namespace ssl_formation
