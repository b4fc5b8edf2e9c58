#include "ssl_formation/model_api/transition_table.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace ssl_formation {
inline namespace model_api {

namespace {

struct SparseRow {
  std::vector<std::pair<StateIndex, TransitionTable::Count>> entries;  // sorted by target
  std::uint64_t total = 0;
};

}  // namespace

// Exactly one of the two layouts is in use.
struct TransitionTable::Storage {
  bool dense = true;
  std::uint64_t states = 0;
  // Dense: states*states counts and a total per FROM row. The counts are not row-major: they
  // are grouped in blocks by (FROM centroid, TO centroid), and within a block the candidates that
  // best_successor() weighs (same previous cell, every position) sit side by side. One prediction
  // step looks up every robot in one block (all share the centroid and the predicted centroid):
  // a few kilobytes on one or two pages, instead of one page per robot. That is what a
  // prediction costs when the predictor wakes with cold caches and TLB every 16 ms.
  std::vector<Count> counts;
  std::uint64_t cells = 0;
  // The one formula of the layout: the offset of the candidates (to_centroid, every position,
  // previous) of the row whose centroid and (position, previous) within it are given.
  std::uint64_t candidates(std::uint64_t from_centroid, std::uint64_t from_in_block,
                           std::uint64_t to_centroid, std::uint64_t previous) const {
    const std::uint64_t block = from_centroid * cells + to_centroid;
    return ((block * cells * cells + from_in_block) * cells + previous) * cells;
  }
  // Offset of the candidates (to_centroid, every position, previous) of row `from`.
  std::uint64_t candidates(StateIndex from, std::uint64_t to_centroid,
                           std::uint64_t previous) const {
    const std::uint64_t block_rows = cells * cells;  // (position, previous) of one centroid
    return candidates(from / block_rows, from % block_rows, to_centroid, previous);
  }
  // offset(from, to), from the centroids the caller has already divided out (`from_centroid` =
  // from / cells^2 and so on): add() runs for every transition, and 64-bit divisions were most
  // of it.
  std::uint64_t offset(StateIndex from_centroid, StateIndex from_in_block, StateIndex to_centroid,
                       StateIndex to_in_block) const {
    const auto cells32 = static_cast<StateIndex>(cells);
    const StateIndex position = to_in_block / cells32;
    const StateIndex previous = to_in_block - position * cells32;
    return candidates(from_centroid, from_in_block, to_centroid, previous) + position;
  }
  std::uint64_t offset(StateIndex from, StateIndex to) const {
    const auto block_rows = static_cast<StateIndex>(cells * cells);
    return offset(from / block_rows, from % block_rows, to / block_rows, to % block_rows);
  }
  Count& at(StateIndex from, StateIndex to) { return counts[offset(from, to)]; }
  Count at(StateIndex from, StateIndex to) const { return counts[offset(from, to)]; }
  std::vector<std::uint64_t> row_totals;
  // Sparse: only the rows and entries seen.
  std::unordered_map<StateIndex, SparseRow> rows;
  std::size_t sparse_entries = 0;
};

TransitionTable::TransitionTable(Grid grid, TableStorage storage)
    : codec_(grid), storage_(std::make_unique<Storage>()) {
  const std::uint64_t states = codec_.state_count();
  const std::uint64_t cells = codec_.cell_count();
  storage_->states = states;
  storage_->cells = cells;
  storage_->dense = (storage == TableStorage::dense && states * states <= dense_entry_hard_limit) ||
                    (storage == TableStorage::automatic && states * states <= dense_entry_limit);
  if (storage_->dense) {
    storage_->counts.assign(states * states, 0);
    storage_->row_totals.assign(states, 0);
  }
  centroid_counts_.assign(cells * cells, 0);
  centroid_totals_.assign(cells, 0);
}

TransitionTable::~TransitionTable() = default;
TransitionTable::TransitionTable(TransitionTable&&) noexcept = default;
TransitionTable& TransitionTable::operator=(TransitionTable&&) noexcept = default;
TransitionTable::TransitionTable(const TransitionTable& other)
    : codec_(other.codec_),
      storage_(std::make_unique<Storage>(*other.storage_)),
      centroid_counts_(other.centroid_counts_),
      centroid_totals_(other.centroid_totals_),
      transitions_(other.transitions_) {}
TransitionTable& TransitionTable::operator=(const TransitionTable& other) {
  if (this != &other) *this = TransitionTable(other);
  return *this;
}

bool TransitionTable::is_dense() const { return storage_->dense; }

TransitionTable::Count TransitionTable::add(StateIndex from, StateIndex to, Count n) {
  if (from >= storage_->states || to >= storage_->states) {
    throw std::out_of_range("state index out of range for grid " + grid().to_string());
  }
  const StateIndex block_rows = codec_.cell_count() * codec_.cell_count();
  const StateIndex from_centroid = from / block_rows;
  const StateIndex to_centroid = to / block_rows;
  Count* cell = nullptr;
  std::uint64_t* row_total = nullptr;
  if (storage_->dense) {
    cell = &storage_->counts[storage_->offset(from_centroid, from - from_centroid * block_rows,
                                              to_centroid, to - to_centroid * block_rows)];
    row_total = &storage_->row_totals[from];
  } else {
    if (n == 0) return 0;
    SparseRow& row = storage_->rows[from];
    auto it = std::lower_bound(row.entries.begin(), row.entries.end(), to,
                               [](const auto& entry, StateIndex key) { return entry.first < key; });
    if (it == row.entries.end() || it->first != to) {
      it = row.entries.insert(it, {to, 0});
      ++storage_->sparse_entries;
    }
    cell = &it->second;
    row_total = &row.total;
  }
  const Count added = std::min<Count>(n, max_count - *cell);
  *cell += added;
  *row_total += added;
  centroid_counts_[from_centroid * codec_.cell_count() + to_centroid] += added;
  centroid_totals_[from_centroid] += added;
  transitions_ += added;
  return added;
}

TransitionTable::Count TransitionTable::count(StateIndex from, StateIndex to) const {
  if (from >= storage_->states || to >= storage_->states) return 0;
  if (storage_->dense) return storage_->at(from, to);
  const auto row = storage_->rows.find(from);
  if (row == storage_->rows.end()) return 0;
  const auto& entries = row->second.entries;
  const auto it =
      std::lower_bound(entries.begin(), entries.end(), to,
                       [](const auto& entry, StateIndex key) { return entry.first < key; });
  return it != entries.end() && it->first == to ? it->second : 0;
}

std::uint64_t TransitionTable::row_total(StateIndex from) const {
  if (from >= storage_->states) return 0;
  if (storage_->dense) return storage_->row_totals[from];
  const auto row = storage_->rows.find(from);
  return row == storage_->rows.end() ? 0 : row->second.total;
}

std::size_t TransitionTable::nonzero_entries() const {
  if (!storage_->dense) return storage_->sparse_entries;
  return static_cast<std::size_t>(
      std::count_if(storage_->counts.begin(), storage_->counts.end(), [](Count c) { return c; }));
}

std::size_t TransitionTable::rows_seen() const {
  if (!storage_->dense) return storage_->rows.size();
  return static_cast<std::size_t>(std::count_if(
      storage_->row_totals.begin(), storage_->row_totals.end(), [](std::uint64_t t) { return t; }));
}

std::size_t TransitionTable::memory_bytes() const {
  std::size_t bytes =
      sizeof(*this) + sizeof(Storage) +
      (centroid_counts_.capacity() + centroid_totals_.capacity()) * sizeof(std::uint64_t);
  if (storage_->dense) {
    bytes += storage_->counts.capacity() * sizeof(Count) +
             storage_->row_totals.capacity() * sizeof(std::uint64_t);
  } else {
    // Hash buckets, one node per row (key, row header, allocator overhead) and the entries.
    bytes += storage_->rows.bucket_count() * sizeof(void*);
    for (const auto& [from, row] : storage_->rows) {
      bytes += sizeof(from) + sizeof(row) + 2 * sizeof(void*) +
               row.entries.capacity() * sizeof(row.entries[0]);
    }
  }
  return bytes;
}

TransitionTable::BestSuccessor TransitionTable::best_successor(StateIndex from,
                                                               StateIndex to_centroid,
                                                               StateIndex previous) const {
  BestSuccessor best;
  const StateIndex cells = codec_.cell_count();
  if (storage_->dense) {
    // Candidates are (to_centroid, p', previous) for every cell p': one per cell, in index order,
    // and contiguous (see Storage).
    const Count* candidates = &storage_->counts[storage_->candidates(from, to_centroid, previous)];
    for (StateIndex position = 0; position < cells; ++position) {
      const Count c = candidates[position];
      best.candidates_total += c;
      if (c > best.best_count) {
        best.best_count = c;
        best.state = codec_.compose(to_centroid, position, previous);
      }
    }
    return best;
  }
  const auto row = storage_->rows.find(from);
  if (row == storage_->rows.end()) return best;
  const auto& entries = row->second.entries;
  const StateIndex block_begin = to_centroid * cells * cells;
  const StateIndex block_end = block_begin + cells * cells;
  auto it = std::lower_bound(entries.begin(), entries.end(), block_begin,
                             [](const auto& entry, StateIndex key) { return entry.first < key; });
  for (; it != entries.end() && it->first < block_end; ++it) {
    if (codec_.previous_id(it->first) != previous) continue;
    best.candidates_total += it->second;
    if (it->second > best.best_count) {
      best.best_count = it->second;
      best.state = it->first;
    }
  }
  return best;
}

void TransitionTable::for_each_nonzero(
    const std::function<void(StateIndex, StateIndex, Count)>& visit) const {
  if (storage_->dense) {
    const std::uint64_t states = storage_->states;
    const std::uint64_t cells = storage_->cells;
    for (std::uint64_t from = 0; from < states; ++from) {
      if (storage_->row_totals[from] == 0) continue;
      // TO states in index order, each read from where the layout keeps it.
      StateIndex to = 0;
      for (std::uint64_t centroid = 0; centroid < cells; ++centroid) {
        for (std::uint64_t position = 0; position < cells; ++position) {
          for (std::uint64_t previous = 0; previous < cells; ++previous, ++to) {
            const Count c = storage_->counts[storage_->candidates(static_cast<StateIndex>(from),
                                                                  centroid, previous) +
                                             position];
            if (c != 0) visit(static_cast<StateIndex>(from), to, c);
          }
        }
      }
    }
    return;
  }
  std::vector<StateIndex> froms;
  froms.reserve(storage_->rows.size());
  for (const auto& [from, row] : storage_->rows) froms.push_back(from);
  std::sort(froms.begin(), froms.end());
  for (const StateIndex from : froms) {
    for (const auto& [to, c] : storage_->rows.at(from).entries) {
      if (c != 0) visit(from, to, c);
    }
  }
}

void TransitionTable::merge(const TransitionTable& other) {
  if (other.grid() != grid()) {
    throw std::invalid_argument("cannot merge a " + other.grid().to_string() + " table into a " +
                                grid().to_string() + " table: the grids differ");
  }
  other.for_each_nonzero([this](StateIndex from, StateIndex to, Count c) { add(from, to, c); });
}

}  // namespace model_api
}  // namespace ssl_formation
