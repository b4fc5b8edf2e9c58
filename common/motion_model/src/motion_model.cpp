#include "ssl_formation/motion_model/motion_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <tuple>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ssl_formation {

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

std::int32_t whole_mm(double value) {
  // Round half away from zero without std::round's call: this runs for every value of every
  // instance trained. Adding copysign(0.5) is adding 0.5 or subtracting it, without a branch on
  // the sign, which half the velocities and displacements would mispredict.
  const double clamped = std::clamp(value, -1.0e9, 1.0e9);
  return static_cast<std::int32_t>(clamped + std::copysign(0.5, clamped));
}

WholePoint whole_mm(Point p) {
#if defined(__SSE2__)
  // Both coordinates in one register: the clamp, the signed half and the truncation are one
  // instruction each for the two (whole_mm(double) is about fourteen per value, two of them
  // jumps), and training converts 14 values per instance learned. The operands are ordered as
  // whole_mm(double) computes: a NaN stays NaN through the clamp and truncates to the same
  // integer.
  static_assert(offsetof(Point, y) == sizeof(double), "x and y are loaded as one pair");
  __m128d v = _mm_loadu_pd(&p.x);
  v = _mm_max_pd(_mm_set1_pd(-1.0e9), v);
  v = _mm_min_pd(_mm_set1_pd(1.0e9), v);
  const __m128d sign = _mm_and_pd(v, _mm_set1_pd(-0.0));
  v = _mm_add_pd(v, _mm_or_pd(sign, _mm_set1_pd(0.5)));
  const __m128i whole = _mm_cvttpd_epi32(v);
  return {_mm_cvtsi128_si32(whole), _mm_cvtsi128_si32(_mm_srli_si128(whole, 4))};
#else
  return {whole_mm(p.x), whole_mm(p.y)};
#endif
}

namespace {
// Fetches every cache line `object` spans into the cache (a hint: nothing waits for it).
template <typename T>
void prefetch_object(const T& object) {
  const char* bytes = reinterpret_cast<const char*>(&object);
  for (std::size_t at = 0; at < sizeof(T); at += 64) __builtin_prefetch(bytes + at);
  __builtin_prefetch(bytes + sizeof(T) - 1);  // an object not aligned to a line spans one more
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

void MotionRowMap::prefetch_row(std::uint32_t number) const { prefetch_object(row(number)); }

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

bool MotionConfig::valid() const {
  return std::isfinite(step_s) && step_s > 0.0 && horizons >= 1 && horizons <= max_horizons &&
         std::isfinite(velocity_window_s) && velocity_window_s > 0.0 &&
         std::isfinite(settle_window_s) && settle_window_s > 0.0 &&
         std::isfinite(long_settle_window_s) && long_settle_window_s > 0.0 &&
         std::isfinite(tolerance_s) && tolerance_s >= 0.0 && std::isfinite(calibration_block_s) &&
         calibration_block_s > 0.0 && calibration_one_in >= 2 && calibration_capacity >= 1;
}

int MotionFeatures::cell(Point p) {
  const int x = clamped_cell((p.x + cells_x * cell_mm / 2.0) / cell_mm, cells_x);
  const int y = clamped_cell((p.y + cells_y * cell_mm / 2.0) / cell_mm, cells_y);
  return x * cells_y + y;
}

int MotionFeatures::team_phase(Point centroid, Point team_velocity) {
  const int place = centroid.x < -team_place_edge_mm ? 0 : centroid.x <= team_place_edge_mm ? 1 : 2;
  const bool moving = team_velocity.x * team_velocity.x + team_velocity.y * team_velocity.y >=
                      speed_limits_mm_s[0] * speed_limits_mm_s[0];
  return place * 2 + (moving ? 1 : 0);
}

int MotionFeatures::velocity_class(Point v) {
  const double speed_squared = v.x * v.x + v.y * v.y;
  int band = 0;
  while (band < static_cast<int>(speed_limits_mm_s.size()) &&
         speed_squared >= speed_limits_mm_s[band] * speed_limits_mm_s[band]) {
    ++band;
  }
  if (band == 0) return 0;
  // Eight sectors of 45 degrees centred on +x, +x+y, +y, ... (counter-clockwise), told apart
  // by comparisons with tan(22.5 degrees) rather than an atan2 per robot and frame.
  static_assert(directions == 8);
  constexpr double tan_22_5 = 0.41421356237309503;
  const double ax = std::abs(v.x), ay = std::abs(v.y);
  int sector = 0;
  if (ay <= tan_22_5 * ax) {
    sector = v.x > 0.0 ? 0 : 4;
  } else if (ax <= tan_22_5 * ay) {
    sector = v.y > 0.0 ? 2 : 6;
  } else {
    sector = v.x > 0.0 ? (v.y > 0.0 ? 1 : 7) : (v.y > 0.0 ? 3 : 5);
  }
  return 1 + (band - 1) * directions + sector;
}

std::uint32_t MotionFeatures::standing_context(double standing_s) {
  std::uint32_t bin = 1;
  for (const double limit : standing_limits_s) {
    if (standing_s < limit) return bin;
    ++bin;
  }
  return bin;
}

std::uint32_t MotionFeatures::game_context(GamePhase phase, double since_command_s) {
  if (phase == GamePhase::running) return running_game;
  if (phase == GamePhase::halt) return halt_game;
  // The other phases in all_game_phases' order after running and halt, three buckets each.
  std::uint32_t index = 0;
  for (const GamePhase p : all_game_phases) {
    if (p == GamePhase::running || p == GamePhase::halt) continue;
    if (p == phase) break;
    ++index;
  }
  std::uint32_t bucket = 0;
  while (bucket < since_command_limits_s.size() &&
         !(since_command_s < since_command_limits_s[bucket])) {
    ++bucket;
  }
  return 2 + index * since_command_buckets + bucket;
}

GamePhase MotionFeatures::phase_of_game_context(std::uint32_t game_context) {
  if (game_context == running_game || game_context >= game_contexts) return GamePhase::running;
  if (game_context == halt_game) return GamePhase::halt;
  std::uint32_t index = (game_context - 2) / since_command_buckets;
  for (const GamePhase p : all_game_phases) {
    if (p == GamePhase::running || p == GamePhase::halt) continue;
    if (index == 0) return p;
    --index;
  }
  return GamePhase::running;
}

int MotionFeatures::zone_of_cell(int cell) {
  // The cell's centre decides (no cell straddles an edge: the edges are multiples of cell_mm).
  const auto band = [](double centre_mm, const auto& edges) {
    int index = 0;
    while (index < static_cast<int>(edges.size()) && centre_mm >= edges[index]) ++index;
    return index;
  };
  const double x = (cell / cells_y + 0.5) * cell_mm - cells_x * cell_mm / 2.0;
  const double y = (cell % cells_y + 0.5) * cell_mm - cells_y * cell_mm / 2.0;
  return band(x, zone_length_edges_mm) * zones_y + band(y, zone_width_edges_mm);
}

namespace {
// Bit fields of a key, low to high: context 24, velocity class 8, cell 12, robot slot 8,
// level 4, horizon 8.
constexpr int context_shift = 0, velocity_shift = 24, cell_shift = 32, slot_shift = 44,
              level_shift = 52, horizon_shift = 56;
std::uint64_t field(MotionKey key, int shift, int bits) {
  return (key >> shift) & ((std::uint64_t{1} << bits) - 1);
}
}  // namespace

MotionKeyParts motion_key_parts(int horizon_index, const MotionInstance& i) {
  MotionKeyParts p;
  p.horizon_index = horizon_index;
  p.level = MotionLevel::robot;
  p.robot_slot = MotionFeatures::robot_slot(i.robot_id);
  p.cell = MotionFeatures::cell({static_cast<double>(i.x), static_cast<double>(i.y)});
  p.velocity_class =
      MotionFeatures::velocity_class({static_cast<double>(i.v_x), static_cast<double>(i.v_y)});
  p.context = i.context;
  return p;
}

MotionKey encode_motion_key(MotionKeyParts p) {
  switch (p.level) {
    case MotionLevel::all:
      p.velocity_class = 0;
      [[fallthrough]];
    case MotionLevel::velocity:
      p.cell = 0;
      // The coarse levels keep the game context alone: in HALT or STOP every robot's motion
      // differs from running play's whatever its place.
      p.context = MotionFeatures::robot_contexts * MotionFeatures::game_context_of(p.context);
      [[fallthrough]];
    case MotionLevel::zone:
      p.robot_slot = 0;
      [[fallthrough]];
    case MotionLevel::robot:
      break;
  }
  return static_cast<MotionKey>(p.horizon_index) << horizon_shift |
         static_cast<MotionKey>(p.level) << level_shift |
         static_cast<MotionKey>(p.robot_slot) << slot_shift |
         static_cast<MotionKey>(p.cell) << cell_shift |
         static_cast<MotionKey>(p.velocity_class) << velocity_shift |
         static_cast<MotionKey>(p.context & 0xffffffu) << context_shift;
}

MotionKeyParts decode_motion_key(MotionKey key) {
  MotionKeyParts p;
  p.horizon_index = static_cast<int>(field(key, horizon_shift, 8));
  p.level = static_cast<MotionLevel>(field(key, level_shift, 4));
  p.robot_slot = static_cast<int>(field(key, slot_shift, 8));
  p.cell = static_cast<int>(field(key, cell_shift, 12));
  p.velocity_class = static_cast<int>(field(key, velocity_shift, 8));
  p.context = static_cast<std::uint32_t>(field(key, context_shift, 24));
  return p;
}

MotionKey coarser_motion_key(MotionKey key) {
  MotionKeyParts p = decode_motion_key(key);
  if (p.level == MotionLevel::robot) p.cell = MotionFeatures::zone_of_cell(p.cell);
  if (p.level != MotionLevel::all)
    p.level = static_cast<MotionLevel>(static_cast<int>(p.level) + 1);
  return encode_motion_key(p);
}

MotionRegressors motion_regressors_of(const MotionKinematics& k, double horizon_s) {
  return {Point{k.velocity.x * horizon_s, k.velocity.y * horizon_s},
          Point{k.velocity_change.x * horizon_s, k.velocity_change.y * horizon_s}, k.to_recent_mean,
          k.to_settled_mean, Point{k.team_velocity.x * horizon_s, k.team_velocity.y * horizon_s}};
}

MotionKinematics MotionInstance::kinematics() const {
  const auto p = [](std::int32_t px, std::int32_t py) {
    return Point{static_cast<double>(px), static_cast<double>(py)};
  };
  return {p(v_x, v_y), p(a_x, a_y), p(g_x, g_y), p(s_x, s_y), p(t_x, t_y)};
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
    const WholePoint whole = whole_mm(Point{px * horizon_s, py * horizon_s});
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

// ---- MotionHistory -----------------------------------------------------------------------------

namespace {
// No robot data for this long: the play moved on.
constexpr double forget_after_gap_s = RobotTracker::forget_after_s;
}  // namespace

MotionHistory::MotionHistory(const MotionConfig& config)
    : config_(config),
      keep_s_(config.horizons * config.step_s +
              std::max(
                  {config.velocity_window_s, config.settle_window_s, config.long_settle_window_s}) +
              2.0 * config.tolerance_s) {}

void MotionHistory::Track::grow() {
  const std::size_t size = std::max<std::size_t>(64, capacity * 2);
  std::vector<Entry> grown(size);
  std::vector<double> grown_times(size);
  std::vector<Running> grown_running(size);
  for (std::uint64_t seq = begin; seq < end; ++seq) {
    grown[seq & (size - 1)] = at(seq);
    grown_times[seq & (size - 1)] = time_at(seq);
    grown_running[seq & (size - 1)] = running_at(seq);
  }
  ring = std::move(grown);
  times = std::move(grown_times);
  running = std::move(grown_running);
  capacity = size;
}

void MotionHistory::Track::clear() {
  begin = end;
  settle_cursor = long_settle_cursor = end;
  tracker.reset();
  horizon_cursor.fill(end);
  still_since_s.reset();
}

void MotionHistory::clear() {
  for (Track& track : tracks_) track.clear();
  last_time_s_.reset();
  learning_gate_.reset();
  learning_instants_ = 0;
}

bool MotionHistory::take_learning_instant(double time_s, double interval_s) {
  if (!learning_gate_.pass(time_s, interval_s)) return false;
  ++learning_instants_;
  return true;
}

inline const MotionHistory::Entry* MotionHistory::nearest(const Track& track, std::uint64_t after,
                                                          double time_s) const {
  // `after` is the first entry at or after time_s: it or the one before it is the nearest.
  const Entry* best = nullptr;
  double best_gap = config_.tolerance_s + 1e-9;
  if (after < track.end && track.time_at(after) - time_s <= best_gap) {
    best = &track.at(after);
    best_gap = track.time_at(after) - time_s;
  }
  if (after > track.begin && time_s - track.time_at(after - 1) <= best_gap) {
    best = &track.at(after - 1);
  }
  return best;
}

void MotionHistory::add(const Formation& formation, std::uint32_t game_context,
                        Point ball_velocity) {
  const double t = formation.time_s;
  if (last_time_s_ && (t <= *last_time_s_ || t - *last_time_s_ > forget_after_gap_s ||
                       formation.opponent_attacks != attacks_)) {
    clear();
  }
  last_time_s_ = t;
  attacks_ = formation.opponent_attacks;
  const double limit = MotionFeatures::speed_limits_mm_s[0];
  // The team's mean velocity, summed as each robot gets its own (in the formation's order).
  Point team{};
  int with_velocity = 0;
  // Every robot's track made first, so that the loops index them without a size check each (a
  // Track's size is no power of two: a vector's size() is a multiplication).
  std::uint32_t highest_id = 0;
  for (const FormationRobot& robot : formation.robots) {
    highest_id = std::max(highest_id, robot.robot_id);
  }
  if (!formation.robots.empty() && highest_id >= tracks_.size()) tracks_.resize(highest_id + 1);
  for (const FormationRobot& robot : formation.robots) {
    Track& track = tracks_[robot.robot_id];
    if (!robot.observed) {
      // No entry: the robot's latest is still its last observation, and counts for the team.
      if (track.end > track.begin && track.at(track.end - 1).has_velocity) {
        const Point velocity = track.at(track.end - 1).kinematics.velocity;
        team.x += velocity.x;
        team.y += velocity.y;
        ++with_velocity;
      }
      continue;
    }
    if (track.end > track.begin) {
      const Track::Running& last = track.running_at(track.end - 1);
      if (MotionFeatures::is_jump(last.position, track.time_at(track.end - 1), robot.position, t)) {
        track.clear();
      }
    }
    while (track.begin < track.end && track.time_at(track.begin) < t - keep_s_) ++track.begin;
    // Cursors: the first entry at or after each window's start.
    const auto advance = [&](std::uint64_t& cursor, double from_s) {
      // Moved in a local: a cursor stored through its reference at each step cost a store per
      // entry passed.
      std::uint64_t at = std::max(cursor, track.begin);
      while (at < track.end && track.time_at(at) < from_s) ++at;
      cursor = at;
    };
    advance(track.settle_cursor, t - config_.settle_window_s);
    advance(track.long_settle_cursor, t - config_.long_settle_window_s);

    // The new entry is written in place, in the ring's next free slot (made first, so that no
    // pointer into the ring moves after this) and counts once it is complete.
    track.make_room();
    const Track::Running* last =
        track.end > track.begin ? &track.running_at(track.end - 1) : nullptr;
    Track::Running& running = track.running_at(track.end);
    running.position = robot.position;
    running.sum = {robot.position.x + (last ? last->sum.x : 0.0),
                   robot.position.y + (last ? last->sum.y : 0.0)};
    // Every field is written below (no `entry = Entry{}`: zeroing the whole slot first was a
    // fifth of this function's time).
    Entry& entry = track.at(track.end);
    entry.time_s = t;
    entry.position = robot.position;
    MotionKinematics& k = entry.kinematics;
    k.team_velocity = {};  // set after the loop if any robot of the formation has a velocity
    track.tracker.observe(t, robot.position);
    // A velocity once the track has gone on for half the velocity window: before that the
    // filter has seen too little of the robot to tell its motion from the vision's noise.
    if (track.tracker.observations() >= 2 &&
        t - track.tracker.first_s() > config_.velocity_window_s / 2.0) {
      k.velocity = track.tracker.velocity();
      entry.has_velocity = true;
      // The change of velocity over one velocity window at the filter's acceleration now.
      const Point acceleration = track.tracker.acceleration();
      k.velocity_change = {acceleration.x * config_.velocity_window_s,
                           acceleration.y * config_.velocity_window_s};
      // From the robot to its mean position since the window's first entry (the new one
      // included), from the running sums. They run unbroken over every kept entry (they restart
      // only when none is kept), so the number of positions summed is that of sequence numbers.
      const auto to_mean_since = [&](std::uint64_t first_seq) {
        if (first_seq >= track.end) return Point{};
        const Track::Running& first = track.running_at(first_seq);
        const double n = static_cast<double>(track.end - first_seq + 1);
        return Point{(running.sum.x - first.sum.x + first.position.x) / n - robot.position.x,
                     (running.sum.y - first.sum.y + first.position.y) / n - robot.position.y};
      };
      k.to_recent_mean = to_mean_since(track.settle_cursor);
      k.to_settled_mean = to_mean_since(track.long_settle_cursor);
      // How long a standing robot has stood: one that has held its place for a while is about
      // to leave it (set plays hold each position for a second or two).
      const bool standing =
          k.velocity.x * k.velocity.x + k.velocity.y * k.velocity.y < limit * limit;
      if (!standing) {
        track.still_since_s.reset();
      } else if (!track.still_since_s) {
        track.still_since_s = t;
      }
      // The standing context for now: the team's phase is added below, once the team's mean
      // velocity is known.
      entry.context = standing ? MotionFeatures::standing_context(t - *track.still_since_s) : 0;
      team.x += k.velocity.x;
      team.y += k.velocity.y;
      ++with_velocity;
    } else {
      entry.has_velocity = false;
      entry.context = 0;
      k.velocity = k.velocity_change = k.to_recent_mean = k.to_settled_mean = {};
    }
    track.time_at(track.end) = t;
    ++track.end;
  }
  // The team's mean velocity and phase go into every new entry, now that each robot has its own.
  if (with_velocity > 0) team = {team.x / with_velocity, team.y / with_velocity};
  const int team_phase = MotionFeatures::team_phase(formation.centroid, team);
  const bool ball_in_flight = MotionFeatures::ball_in_flight(ball_velocity);
  for (const FormationRobot& robot : formation.robots) {
    if (!robot.observed) continue;
    Track& track = tracks_[robot.robot_id];
    Entry& entry = track.at(track.end - 1);
    entry.kinematics.team_velocity = team;
    entry.context =
        MotionFeatures::context(entry.context, team_phase, game_context, ball_in_flight);
  }
}

const MotionHistory::Entry* MotionHistory::latest(std::uint32_t robot_id) const {
  if (robot_id >= tracks_.size()) return nullptr;
  const Track& track = tracks_[robot_id];
  return track.end > track.begin ? &track.at(track.end - 1) : nullptr;
}

const MotionHistory::Entry* MotionHistory::steps_before_latest(std::uint32_t robot_id, int steps) {
  if (robot_id >= tracks_.size() || steps < 1 || steps > config_.horizons) return nullptr;
  Track& track = tracks_[robot_id];
  if (track.end == track.begin) return nullptr;
  // The cursor moves only when asked (learning is 10 times a second, frames come 60): to the
  // first entry before the latest one at or after the latest's time minus the steps, else the
  // latest. The target only grows between two clears, so its earlier place is a lower bound.
  const double time_s = track.time_at(track.end - 1) - steps * config_.step_s;
  std::uint64_t& cursor = track.horizon_cursor[static_cast<std::size_t>(steps - 1)];
  cursor = std::max(cursor, track.begin);
  while (cursor < track.end - 1 && track.time_at(cursor) < time_s) ++cursor;
  return nearest(track, cursor, time_s);
}

void learn_motion(MotionTable& table, MotionHistory& history, const Formation& now,
                  double learn_from_s) {
  const MotionConfig& config = table.config();
  // A robot not seen since the last learning instant (its camera's packets missed it) was
  // learned from there already.
  const std::optional<double> previous_s = history.last_learning_instant_s();
  if (!history.take_learning_instant(now.time_s, config.learn_interval_s)) return;
  const int horizons = (history.learning_instants() - 1) % MotionConfig::later_horizons_every == 0
                           ? config.horizons
                           : 1;
  // Gathered, then counted a batch at a time (MotionTable::add's prefetching), in this order.
  // The buffer outlives the call (per thread: learn_motion never reenters itself), so that 3 KiB
  // are not zeroed at every learning instant; each entry used is written in full first.
  static thread_local std::array<MotionTable::Learned, 48> batch;
  // The entries learned from are 30 to 90 frames back, out of the nearest cache: all of them
  // are found and fetched first, so that their misses overlap.
  static thread_local std::vector<const MotionHistory::Entry*> thens;
  thens.clear();
  for (const FormationRobot& robot : now.robots) {
    const MotionHistory::Entry* latest = history.latest(robot.robot_id);
    const bool learned_already =
        !robot.observed && previous_s && latest && latest->time_s <= *previous_s;
    for (int k = 1; k <= horizons; ++k) {
      const MotionHistory::Entry* then =
          learned_already ? nullptr : history.steps_before_latest(robot.robot_id, k);
      if (then) prefetch_object(*then);
      thens.push_back(then);
    }
  }
  std::size_t pending = 0;
  std::size_t next_then = 0;
  for (const FormationRobot& robot : now.robots) {
    for (int k = 1; k <= horizons; ++k) {
      const MotionHistory::Entry* then = thens[next_then++];
      if (!then || !then->has_velocity || then->time_s >= now.time_s ||
          then->time_s < learn_from_s) {
        continue;
      }
      MotionTable::Learned& learned = batch[pending++];
      learned.horizon_index = k - 1;
      learned.time_s = then->time_s;
      MotionInstance& instance = learned.instance;
      instance.robot_id = robot.robot_id;
      const MotionKinematics& kinematics = then->kinematics;
      const auto set_whole_mm = [](std::int32_t& x, std::int32_t& y, Point p) {
        const WholePoint whole = whole_mm(p);
        x = whole.x;
        y = whole.y;
      };
      set_whole_mm(instance.x, instance.y, then->position);
      set_whole_mm(instance.v_x, instance.v_y, kinematics.velocity);
      set_whole_mm(instance.a_x, instance.a_y, kinematics.velocity_change);
      set_whole_mm(instance.g_x, instance.g_y, kinematics.to_recent_mean);
      set_whole_mm(instance.s_x, instance.s_y, kinematics.to_settled_mean);
      set_whole_mm(instance.t_x, instance.t_y, kinematics.team_velocity);
      set_whole_mm(instance.d_x, instance.d_y,
                   Point{robot.position.x - then->position.x, robot.position.y - then->position.y});
      instance.context = then->context;
      if (pending == batch.size()) {
        table.add(std::span<const MotionTable::Learned>(batch.data(), pending));
        pending = 0;
      }
    }
  }
  table.add(std::span<const MotionTable::Learned>(batch.data(), pending));
}

}  // namespace ssl_formation
