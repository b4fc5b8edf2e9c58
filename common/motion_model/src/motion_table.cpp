// The motion table: its rows in an open-addressing map (MotionRowMap), and the instances
// counted into them and held out for the calibration.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "prefetch.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "whole_mm.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ssl_formation {
inline namespace motion_model {

namespace {

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser: a fixed, well-spread hash
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t instance_hash(int horizon_index, double time_s, const MotionInstance& i) {
  // The time to the millisecond and the instance itself: the same instance from the same
  // stream always ranks the same, whichever table it is trained into.
  std::uint64_t h = mix(static_cast<std::uint64_t>(std::llround(time_s * 1000.0)));
  h = mix(h ^ (static_cast<std::uint64_t>(horizon_index) << 40) ^ i.robot_id);
  h = mix(h ^ (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i.x)) << 32 |
               static_cast<std::uint32_t>(i.y)));
  h = mix(h ^ (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i.d_x)) << 32 |
               static_cast<std::uint32_t>(i.d_y)));
  return h;
}

// The calibration sample's order: the lowest hashes are kept, ties broken by every value of the
// instance so that the kept set never depends on the order instances arrived in.
bool ranks_before(const HeldOutInstance& a, const HeldOutInstance& b) {
  if (a.hash != b.hash) return a.hash < b.hash;  // nearly always: no tuples to build
  const auto key = [](const HeldOutInstance& h) {
    const MotionInstance& i = h.instance;
    return std::tuple(h.hash, i.robot_id, i.x, i.y, i.d_x, i.d_y, i.v_x, i.v_y, i.a_x, i.a_y, i.g_x,
                      i.g_y, i.s_x, i.s_y, i.t_x, i.t_y, i.context);
  };
  return key(a) < key(b);
}

}  // namespace

MotionRow& MotionRowMap::operator[](MotionKey key) {
  if (2 * (row_keys_.size() + 1) > slots_.size()) grow();
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = motion_key_slot(key, mask);; i = (i + 1) & mask) {
    Slot& slot = slots_[i];
    if (slot.key == key) return row(slot.row);
    if (slot.key == empty_key) {
      slot.key = key;
      slot.row = static_cast<std::uint32_t>(row_keys_.size());
      row_keys_.push_back(key);
      if (blocks_.empty() || blocks_.back().size() == rows_per_block) blocks_.emplace_back();
      // Also a copied map's last block, which the copy made only as large as its rows.
      blocks_.back().reserve(rows_per_block);
      return blocks_.back().emplace_back();
    }
  }
}

const MotionRow* MotionRowMap::find(MotionKey key) const {
  const std::uint32_t number = row_number(key);
  return number == no_row ? nullptr : &row(number);
}

std::uint32_t MotionRowMap::row_number(MotionKey key) const {
  if (slots_.empty()) return no_row;
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = motion_key_slot(key, mask);; i = (i + 1) & mask) {
    const Slot& slot = slots_[i];
    if (slot.key == key) return slot.row;
    if (slot.key == empty_key) return no_row;
  }
}

void MotionRowMap::prefetch_slot(MotionKey key) const {
  if (slots_.empty()) return;
  __builtin_prefetch(&slots_[motion_key_slot(key, slots_.size() - 1)]);
}

void MotionRowMap::prefetch_row(std::uint32_t number) const {
  detail::prefetch_object(row(number));
}

std::size_t MotionRowMap::memory_bytes() const {
  std::size_t bytes = slots_.capacity() * sizeof(Slot) + row_keys_.capacity() * sizeof(MotionKey);
  for (const Block& block : blocks_) bytes += block.capacity() * sizeof(MotionRow);
  return bytes;
}

void MotionRowMap::grow() {
  std::vector<Slot, ProbedAllocator<Slot>> slots(std::max<std::size_t>(64, slots_.size() * 2));
  const std::size_t mask = slots.size() - 1;
  for (std::size_t row = 0; row < row_keys_.size(); ++row) {
    std::size_t i = motion_key_slot(row_keys_[row], mask);
    while (slots[i].key != empty_key) i = (i + 1) & mask;
    slots[i] = Slot{row_keys_[row], static_cast<std::uint32_t>(row)};
  }
  slots_ = std::move(slots);
}

bool operator==(const MotionRowMap& a, const MotionRowMap& b) {
  if (a.size() != b.size()) return false;
  bool equal = true;
  a.for_each([&](MotionKey key, const MotionRow& row) {
    const MotionRow* other = b.find(key);
    equal = equal && other && *other == row;
  });
  return equal;
}

void MotionRow::add(const std::array<std::int64_t, 2>& d,
                    const std::array<std::array<std::int64_t, 2>, r>& x) {
  const auto dot = [](const std::array<std::int64_t, 2>& a, const std::array<std::int64_t, 2>& b) {
    return a[0] * b[0] + a[1] * b[1];
  };
  std::size_t at = 0;
  sums[at++] += 1;
  sums[at++] += d[0];
  sums[at++] += d[1];
  for (int i = 0; i < r; ++i) {
    sums[at++] += x[i][0];
    sums[at++] += x[i][1];
  }
  sums[at++] += dot(d, d);
  for (int i = 0; i < r; ++i) sums[at++] += dot(d, x[i]);
  for (int i = 0; i < r; ++i) {
    for (int j = i; j < r; ++j) sums[at++] += dot(x[i], x[j]);
  }
}

void MotionRow::add(const MotionRow& o) {
  for (std::size_t i = 0; i < size; ++i) sums[i] += o.sums[i];
}

MotionRow MotionRow::without_regressor(int i) const {
  MotionRow out = *this;
  out.sums[static_cast<std::size_t>(3 + 2 * i)] = 0;
  out.sums[static_cast<std::size_t>(3 + 2 * i + 1)] = 0;
  out.sums[static_cast<std::size_t>(4 + 2 * r + i)] = 0;
  for (int j = 0; j < r; ++j) out.sums[static_cast<std::size_t>(4 + 3 * r + pair_index(i, j))] = 0;
  return out;
}

MotionTable::MotionTable(MotionConfig config) : config_(config) {
  if (!config_.valid()) throw std::invalid_argument("invalid motion model configuration");
  held_out_.resize(static_cast<std::size_t>(config_.horizons));
}

bool MotionTable::is_held_out(double time_s) const {
  const auto block = static_cast<std::int64_t>(std::floor(time_s / config_.calibration_block_s));
  return mix(static_cast<std::uint64_t>(block)) % config_.calibration_one_in == 0;
}

void MotionTable::add(int horizon_index, double time_s, const MotionInstance& i) {
  if (is_held_out(time_s)) {
    add_held_out(horizon_index, HeldOutInstance{instance_hash(horizon_index, time_s, i), i});
    return;
  }
  count(horizon_index, rows_[encode_motion_key(motion_key_parts(horizon_index, i))], i);
}

void MotionTable::add(std::span<const Learned> learned) {
  // A chunk at a time: every counted instance's key and index slot, then their rows, then the
  // counts, so that the cache misses of a chunk's rows overlap rather than queue.
  constexpr std::size_t chunk = 32;
  std::array<MotionKey, chunk> keys{};
  std::array<std::uint32_t, chunk> rows{};  // row numbers, no_row for a row still to make
  std::array<bool, chunk> held{};
  for (std::size_t start = 0; start < learned.size(); start += chunk) {
    const std::size_t n = std::min(chunk, learned.size() - start);
    const Learned* batch = learned.data() + start;
    // The instances of one horizon mostly share their start time, hence their block.
    double block_time_s = std::numeric_limits<double>::quiet_NaN();
    bool block_held = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (batch[i].time_s != block_time_s) {
        block_time_s = batch[i].time_s;
        block_held = is_held_out(block_time_s);
      }
      held[i] = block_held;
      if (held[i]) continue;
      keys[i] = encode_motion_key(motion_key_parts(batch[i].horizon_index, batch[i].instance));
      rows_.prefetch_slot(keys[i]);
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (held[i]) continue;
      rows[i] = rows_.row_number(keys[i]);
      if (rows[i] != MotionRowMap::no_row) rows_.prefetch_row(rows[i]);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Learned& l = batch[i];
      if (held[i]) {
        add_held_out(
            l.horizon_index,
            HeldOutInstance{instance_hash(l.horizon_index, l.time_s, l.instance), l.instance});
      } else if (rows[i] != MotionRowMap::no_row) {
        count(l.horizon_index, rows_.row(rows[i]), l.instance);  // row numbers never change
      } else {
        count(l.horizon_index, rows_[keys[i]], l.instance);
      }
    }
  }
}

void MotionTable::count(int horizon_index, MotionRow& row, const MotionInstance& i) {
  const double horizon_s = (horizon_index + 1) * config_.step_s;
  // motion_regressors_of(i.kinematics(), horizon_s) in whole millimetres. The settle-window
  // regressors are whole millimetres already: whole_mm of a whole number is that number clamped
  // to +-1e9, so only the two scaled by the horizon need rounding.
  static_assert(motion_regressors == 5);
  const auto whole = [](std::int32_t mm) -> std::int64_t {
    return std::clamp(mm, std::int32_t{-1000000000}, std::int32_t{1000000000});
  };
  const auto scaled = [horizon_s](std::int32_t px, std::int32_t py) -> std::array<std::int64_t, 2> {
    const WholePoint whole = detail::whole_mm_of(Point{px * horizon_s, py * horizon_s});
    return {whole.x, whole.y};
  };
  const std::array<std::array<std::int64_t, 2>, motion_regressors> x{{
      scaled(i.v_x, i.v_y),
      scaled(i.a_x, i.a_y),
      {whole(i.g_x), whole(i.g_y)},
      {whole(i.s_x), whole(i.s_y)},
      scaled(i.t_x, i.t_y),
  }};
  ++instances_;
  row.add({i.d_x, i.d_y}, x);
}

void MotionTable::add_row(MotionKey key, const MotionRow& row) {
  rows_[key].add(row);
  instances_ += static_cast<std::uint64_t>(row.n());
}

void MotionTable::add_held_out(int horizon_index, const HeldOutInstance& held_out) {
  ++held_out_seen_;
  HeldOutSample& sample = held_out_[static_cast<std::size_t>(horizon_index)];
  // Ranking no lower than the bar, it cannot be among the lowest `capacity`: the bar and
  // `capacity` - 1 instances ranked below it are. (An equal one may be left out: it is the
  // bar's twin, and the multiset kept is the same.)
  if (sample.bar && !ranks_before(held_out, *sample.bar)) return;
  sample.candidates.push_back(held_out);
  const std::size_t capacity = config_.calibration_capacity;
  if (sample.candidates.size() < 2 * capacity) return;
  const auto cut = sample.candidates.begin() + static_cast<std::ptrdiff_t>(capacity - 1);
  std::nth_element(sample.candidates.begin(), cut, sample.candidates.end(), ranks_before);
  sample.bar = *cut;
  sample.candidates.resize(capacity);
}

void MotionTable::merge(const MotionTable& other) {
  if (!(other.config_ == config_)) {
    throw std::invalid_argument("the motion tables were trained with different settings");
  }
  other.rows_.for_each([&](MotionKey key, const MotionRow& row) { rows_[key].add(row); });
  instances_ += other.instances_;
  const std::uint64_t seen = held_out_seen_ + other.held_out_seen_;
  for (std::size_t h = 0; h < held_out_.size(); ++h) {
    for (const HeldOutInstance& i : other.held_out_[h].candidates) {
      add_held_out(static_cast<int>(h), i);
    }
  }
  held_out_seen_ = seen;
  set_plays_.merge(other.set_plays_);
}

std::size_t MotionTable::memory_bytes() const {
  std::size_t bytes = rows_.memory_bytes() + set_plays_.memory_bytes();
  for (const HeldOutSample& sample : held_out_) {
    bytes += sample.candidates.capacity() * sizeof(HeldOutInstance);
  }
  return bytes;
}

std::vector<std::pair<MotionKey, MotionRow>> MotionTable::sorted_rows() const {
  std::vector<std::pair<MotionKey, MotionRow>> rows;
  rows.reserve(rows_.size());
  rows_.for_each([&](MotionKey key, const MotionRow& row) { rows.emplace_back(key, row); });
  std::sort(rows.begin(), rows.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return rows;
}

std::vector<HeldOutInstance> MotionTable::calibration(int horizon_index) const {
  std::vector<HeldOutInstance> sample =
      held_out_[static_cast<std::size_t>(horizon_index)].candidates;
  const std::size_t capacity = config_.calibration_capacity;
  if (sample.size() > capacity) {
    std::nth_element(sample.begin(), sample.begin() + static_cast<std::ptrdiff_t>(capacity),
                     sample.end(), ranks_before);
    sample.resize(capacity);
  }
  std::sort(sample.begin(), sample.end(), ranks_before);
  return sample;
}

bool operator==(const MotionTable& a, const MotionTable& b) {
  if (!(a.config_ == b.config_) || a.instances_ != b.instances_ ||
      a.held_out_seen_ != b.held_out_seen_ || a.rows_ != b.rows_ || a.set_plays_ != b.set_plays_) {
    return false;
  }
  for (int h = 0; h < a.config_.horizons; ++h) {
    if (a.calibration(h) != b.calibration(h)) return false;
  }
  return true;
}

}  // namespace motion_model
}  // namespace ssl_formation
