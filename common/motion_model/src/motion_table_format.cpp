#include "ssl_formation/motion_model/motion_table_format.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace ssl_formation {
inline namespace motion_model {
namespace detail {

namespace {

constexpr std::uint64_t motion_row_size = 8 + 8 * MotionRow::size;
// hash, robot_id, the values, context
constexpr std::uint64_t held_out_size = 8 + 4 + 4 * motion_instance_values.size() + 4;
constexpr std::uint64_t motion_horizons_offset = 8;                    // in the configuration
constexpr std::uint64_t motion_rows_offset = motion_config_size + 16;  // the row count
// offset_ms, since_command_ms, stage, seen, then x and y per robot slot
constexpr std::uint64_t set_play_snapshot_size = 4 * 4 + 8 * SetPlaySnapshot::robot_slots;

void write_set_plays(FileWriter& writer, const SetPlayMemory& memory) {
  writer.write_u32(static_cast<std::uint32_t>(memory.episodes().size()));
  for (const SetPlayEpisode& episode : memory.episodes()) {
    writer.write_u32(static_cast<std::uint32_t>(episode.snapshots.size()));
    for (const SetPlaySnapshot& s : episode.snapshots) {
      writer.write_u32(static_cast<std::uint32_t>(s.offset_ms));
      writer.write_u32(static_cast<std::uint32_t>(s.since_command_ms));
      writer.write_u32(static_cast<std::uint32_t>(s.stage));
      writer.write_u32(s.seen);
      for (const auto& p : s.position) {
        writer.write_u32(static_cast<std::uint32_t>(p[0]));
        writer.write_u32(static_cast<std::uint32_t>(p[1]));
      }
    }
  }
}

SetPlaySnapshot decode_set_play_snapshot(const std::uint8_t* in) {
  SetPlaySnapshot s;
  s.offset_ms = static_cast<std::int32_t>(get_u32(&in[0]));
  s.since_command_ms = static_cast<std::int32_t>(get_u32(&in[4]));
  s.stage = static_cast<SetPlayStage>(get_u32(&in[8]));
  s.seen = get_u32(&in[12]);
  for (std::size_t i = 0; i < s.position.size(); ++i) {
    s.position[i][0] = static_cast<std::int32_t>(get_u32(&in[16 + 8 * i]));
    s.position[i][1] = static_cast<std::int32_t>(get_u32(&in[20 + 8 * i]));
  }
  return s;
}

void write_motion_config(FileWriter& writer, const MotionConfig& config) {
  writer.write_f64(config.step_s);
  writer.write_u32(static_cast<std::uint32_t>(config.horizons));
  writer.write_f64(config.velocity_window_s);
  writer.write_f64(config.tolerance_s);
  writer.write_f64(config.calibration_block_s);
  writer.write_u32(config.calibration_one_in);
  writer.write_u32(config.calibration_capacity);
  writer.write_f64(config.settle_window_s);
  writer.write_f64(config.long_settle_window_s);
  writer.write_f64(config.learn_interval_s);
}

// The configuration at `in`; `horizons` as stored, config.horizons clamped to one past the
// largest valid value so that a huge count stays invalid without overflowing an int.
MotionConfig decode_motion_config(const std::uint8_t* in, std::uint32_t& horizons) {
  MotionConfig config;
  config.step_s = get_f64(&in[0]);
  horizons = get_u32(&in[8]);
  config.horizons = static_cast<int>(std::min<std::uint32_t>(
      horizons, static_cast<std::uint32_t>(MotionConfig::max_horizons) + 1));
  config.velocity_window_s = get_f64(&in[12]);
  config.tolerance_s = get_f64(&in[20]);
  config.calibration_block_s = get_f64(&in[28]);
  config.calibration_one_in = get_u32(&in[36]);
  config.calibration_capacity = get_u32(&in[40]);
  config.settle_window_s = get_f64(&in[44]);
  config.long_settle_window_s = get_f64(&in[52]);
  config.learn_interval_s = get_f64(&in[60]);
  return config;
}

// MotionConfig::valid(), and what it leaves to the model but a file must not hold.
bool valid_motion_config(const MotionConfig& config) {
  return config.valid() && std::isfinite(config.learn_interval_s) && config.learn_interval_s >= 0.0;
}

MotionRow decode_motion_row(const std::uint8_t* in) {
  MotionRow row;
  for (std::size_t i = 0; i < MotionRow::size; ++i) {
    row.sums[i] = static_cast<std::int64_t>(get_u64(&in[8 * i]));
  }
  return row;
}

// The compact form: the hash as it is (it is random), the rest as varints.
void encode_held_out(std::vector<std::uint8_t>& out, const HeldOutInstance& held) {
  std::uint8_t hash[8];
  put_u64(hash, held.hash);
  out.insert(out.end(), hash, hash + 8);
  append_varint(out, held.instance.robot_id);
  for (const auto value : motion_instance_values) append_varint(out, zigzag(held.instance.*value));
  append_varint(out, held.instance.context);
}

// Decodes a compact instance at `pos`; false if the bytes run out or a value does not fit.
bool decode_compact_held_out(const std::uint8_t*& pos, const std::uint8_t* end,
                             HeldOutInstance& held) {
  if (end - pos < 8) return false;
  held.hash = get_u64(pos);
  pos += 8;
  std::uint64_t value = 0;
  if (!read_varint(pos, end, value) || value > UINT32_MAX) return false;
  held.instance.robot_id = static_cast<std::uint32_t>(value);
  for (const auto field : motion_instance_values) {
    if (!read_varint(pos, end, value)) return false;
    const std::int64_t signed_value = unzigzag(value);
    if (signed_value < INT32_MIN || signed_value > INT32_MAX) return false;
    held.instance.*field = static_cast<std::int32_t>(signed_value);
  }
  if (!read_varint(pos, end, value) || value > UINT32_MAX) return false;
  held.instance.context = static_cast<std::uint32_t>(value);
  return true;
}

HeldOutInstance decode_held_out(const std::uint8_t* in) {
  HeldOutInstance held;
  held.hash = get_u64(&in[0]);
  held.instance.robot_id = get_u32(&in[8]);
  for (std::size_t i = 0; i < motion_instance_values.size(); ++i) {
    held.instance.*motion_instance_values[i] = static_cast<std::int32_t>(get_u32(&in[12 + 4 * i]));
  }
  held.instance.context = get_u32(&in[12 + 4 * motion_instance_values.size()]);
  return held;
}

// What a stored row must satisfy (the same check keeps save_table from writing a row that
// load_table would reject); a reason if it does not.
std::optional<std::string> motion_row_problem(MotionKey key, const MotionRow& row,
                                              const MotionConfig& config) {
  const MotionKeyParts parts = decode_motion_key(key);
  // A row of any level: a pruned table keeps at a coarser key what it folded into it.
  if (static_cast<int>(parts.level) >= motion_levels || encode_motion_key(parts) != key) {
    return std::string("not a motion key");
  }
  if (parts.horizon_index >= config.horizons) return std::string("horizon out of range");
  if (parts.robot_slot >= MotionFeatures::robot_slots || parts.cell >= MotionFeatures::cell_count ||
      parts.velocity_class >= MotionFeatures::velocity_classes ||
      parts.context >= MotionFeatures::context_count) {
    return std::string("feature out of range");
  }
  if (row.n() < 1) return "count " + std::to_string(row.n());
  if (row.dd() < 0) return std::string("negative sum of squares");
  for (int i = 0; i < MotionRow::r; ++i) {
    if (row.xx(i, i) < 0) return std::string("negative sum of squares");
  }
  return std::nullopt;
}

}  // namespace

Result<EncodedMotion> encode_motion_section(const MotionTable& motion, double step_s) {
  const MotionConfig& config = motion.config();
  if (!valid_motion_config(config)) return fail("invalid motion model configuration");
  if (config.step_s != step_s) return fail("the motion model's step differs from the table's");
  EncodedMotion encoded;
  std::uint64_t sum = 0;
  MotionKey previous = 0;
  for (const auto& [key, row] : motion.sorted_rows()) {
    if (const auto problem = motion_row_problem(key, row, config)) {
      return fail("invalid motion row: " + *problem);
    }
    sum += static_cast<std::uint64_t>(row.n());
    // Sorted keys, each as its distance from the one before: neighbours share their high bits.
    append_varint(encoded.row_bytes, key - previous);
    previous = key;
    for (const std::int64_t value : row.sums) append_varint(encoded.row_bytes, zigzag(value));
    ++encoded.rows;
  }
  if (sum != motion.instances()) {
    return fail("the motion rows do not add up to the motion table's instances");
  }
  for (int h = 0; h < config.horizons; ++h) {
    const std::vector<HeldOutInstance> sample = motion.calibration(h);
    append_varint(encoded.calibration_bytes, sample.size());
    for (const HeldOutInstance& held : sample) encode_held_out(encoded.calibration_bytes, held);
  }
  return encoded;
}

std::uint64_t motion_section_size(const MotionTable& motion, const EncodedMotion& encoded) {
  std::uint64_t set_plays = 4;
  for (const SetPlayEpisode& episode : motion.set_plays().episodes()) {
    set_plays += 4 + episode.snapshots.size() * set_play_snapshot_size;
  }
  return motion_fixed_size + 8 + encoded.row_bytes.size() + 8 + encoded.calibration_bytes.size() +
         set_plays;
}

void write_motion_section(FileWriter& writer, const MotionTable& motion,
                          const EncodedMotion& encoded) {
  write_motion_config(writer, motion.config());
  writer.write_u64(motion.instances());
  writer.write_u64(motion.held_out());
  writer.write_u64(encoded.rows);
  writer.write_u64(encoded.row_bytes.size());
  writer.write(encoded.row_bytes.data(), encoded.row_bytes.size());
  writer.write_u64(encoded.calibration_bytes.size());
  writer.write(encoded.calibration_bytes.data(), encoded.calibration_bytes.size());
  write_set_plays(writer, motion.set_plays());
}

MotionExtent motion_extent(int fd, std::uint64_t begin, std::uint64_t limit, MotionLayout layout) {
  MotionExtent extent;
  std::array<std::uint8_t, motion_fixed_size> fixed{};
  {
    ChunkReader reader(fd, begin, begin + motion_fixed_size);
    if ((extent.read_error = reader.read(fixed.data(), fixed.size())) != 0) return extent;
  }
  const std::uint32_t horizons = get_u32(&fixed[motion_horizons_offset]);
  if (horizons < 1 || horizons > static_cast<std::uint32_t>(MotionConfig::max_horizons)) {
    return extent;
  }
  std::uint64_t pos = begin + motion_fixed_size;
  const auto past = [&](std::uint64_t needed) {
    extent.past_end = true;
    extent.at_least = pos + needed;
    return extent;
  };
  // A u32 or u64 size at `pos`, which must lie before `limit`.
  const auto read_size = [&](std::size_t width, std::uint64_t& value) {
    std::uint8_t bytes[8];
    ChunkReader reader(fd, pos, pos + width);
    extent.read_error = reader.read(bytes, width);
    value = width == 4 ? get_u32(bytes) : get_u64(bytes);
    pos += width;
    return extent.read_error == 0;
  };
  if (layout == MotionLayout::compact) {
    // The rows' block and the calibration's, each after its length in bytes.
    for (int block = 0; block < 2; ++block) {
      if (limit - pos < 8) return past(8);
      std::uint64_t bytes = 0;
      if (!read_size(8, bytes)) return extent;
      if (bytes > limit - pos) return past(std::min(bytes, UINT64_MAX / 2));
      pos += bytes;
    }
  } else {
    const std::uint64_t rows = get_u64(&fixed[motion_rows_offset]);
    if (rows > (limit - pos) / motion_row_size) {
      // at_least saturates rather than overflows for an absurd row count.
      return past(rows > (UINT64_MAX / 2) / motion_row_size ? UINT64_MAX / 2
                                                            : rows * motion_row_size);
    }
    pos += rows * motion_row_size;
    for (std::uint32_t h = 0; h < horizons; ++h) {
      if (limit - pos < 4) return past(4);
      std::uint64_t count = 0;
      if (!read_size(4, count)) return extent;
      if (count > (limit - pos) / held_out_size) return past(count * held_out_size);
      pos += count * held_out_size;
    }
  }
  if (layout != MotionLayout::fixed) {
    if (limit - pos < 4) return past(4);
    std::uint64_t episodes = 0;
    if (!read_size(4, episodes)) return extent;
    // More than a memory keeps: the sizes cannot be followed; the content check says why.
    if (episodes > SetPlayMemory::max_episodes) return extent;
    for (std::uint64_t e = 0; e < episodes; ++e) {
      if (limit - pos < 4) return past(4);
      std::uint64_t count = 0;
      if (!read_size(4, count)) return extent;
      if (count > (limit - pos) / set_play_snapshot_size) {
        return past(count * set_play_snapshot_size);
      }
      pos += count * set_play_snapshot_size;
    }
  }
  extent.end = pos;
  extent.known = true;
  return extent;
}

namespace {

// The checks of every row, whichever its layout, as the rows are read in file order.
class RowChecker {
 public:
  RowChecker(MotionTable& table, std::uint64_t instances) : table_(table), instances_(instances) {}

  std::optional<std::string> add(std::uint64_t i, MotionKey key, const MotionRow& row) {
    const std::string where = "motion row " + std::to_string(i);
    if (previous_key_ && key <= *previous_key_) return where + ": rows out of order";
    previous_key_ = key;
    if (const auto problem = motion_row_problem(key, row, table_.config())) {
      return where + ": " + *problem;
    }
    if (static_cast<std::uint64_t>(row.n()) > instances_ - sum_) {
      return "the motion rows hold more than the " + std::to_string(instances_) +
             " instances the section says";
    }
    sum_ += static_cast<std::uint64_t>(row.n());
    table_.add_row(key, row);
    return std::nullopt;
  }
  std::optional<std::string> finish() const {
    if (sum_ == instances_) return std::nullopt;
    return "the motion rows hold " + std::to_string(sum_) + " instances, the section says " +
           std::to_string(instances_);
  }

 private:
  MotionTable& table_;
  std::uint64_t instances_;
  std::uint64_t sum_ = 0;
  std::optional<MotionKey> previous_key_;
};

// The checks of one horizon's calibration sample, whichever its layout.
std::optional<std::string> check_sample_size(const MotionConfig& config, int h,
                                             std::uint64_t count) {
  if (count <= config.calibration_capacity) return std::nullopt;
  return "calibration sample of horizon " + std::to_string(h + 1) + ": " + std::to_string(count) +
         " instances, more than its capacity " + std::to_string(config.calibration_capacity);
}
std::optional<std::string> add_sample(MotionTable& table, int h,
                                      const std::vector<HeldOutInstance>& sample) {
  const std::string where = "calibration sample of horizon " + std::to_string(h + 1);
  for (std::size_t i = 0; i < sample.size(); ++i) {
    if (sample[i].instance.context >= MotionFeatures::context_count) {
      return where + ": instance " + std::to_string(i) + ": context " +
             std::to_string(sample[i].instance.context) + " out of range";
    }
    table.add_held_out(h, sample[i]);
  }
  // Within its capacity every instance is kept, so the file's order must be the table's
  // (equal neighbours are allowed: merging tables trained on the same stream keeps both).
  if (table.calibration(h) != sample) return where + ": instances out of order";
  return std::nullopt;
}

ReadProblem read_fixed_rows_and_samples(ChunkReader& reader, std::uint64_t rows,
                                        RowChecker& checker, MotionTable& table) {
  std::array<std::uint8_t, motion_row_size> row_bytes{};
  for (std::uint64_t i = 0; i < rows; ++i) {
    if (const int error = reader.read(row_bytes.data(), row_bytes.size()); error != 0) {
      return {std::nullopt, error};
    }
    if (auto problem = checker.add(i, get_u64(&row_bytes[0]), decode_motion_row(&row_bytes[8]))) {
      return {std::move(problem), 0};
    }
  }
  if (auto problem = checker.finish()) return {std::move(problem), 0};
  std::array<std::uint8_t, held_out_size> held_bytes{};
  for (int h = 0; h < table.config().horizons; ++h) {
    std::uint32_t count = 0;
    if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
    if (auto problem = check_sample_size(table.config(), h, count)) {
      return {std::move(problem), 0};
    }
    std::vector<HeldOutInstance> sample;
    sample.reserve(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      if (const int error = reader.read(held_bytes.data(), held_bytes.size()); error != 0) {
        return {std::nullopt, error};
      }
      sample.push_back(decode_held_out(held_bytes.data()));
    }
    if (auto problem = add_sample(table, h, sample)) return {std::move(problem), 0};
  }
  return {};
}

// A compact block: its u64 length, then its bytes.
ReadProblem read_block(ChunkReader& reader, std::vector<std::uint8_t>& bytes) {
  std::uint64_t size = 0;
  if (const int error = reader.read_u64(size); error != 0) return {std::nullopt, error};
  // motion_extent checked the length against the file's before anything was read.
  bytes.resize(size);
  if (const int error = reader.read(bytes.data(), bytes.size()); error != 0) {
    return {std::nullopt, error};
  }
  return {};
}

ReadProblem read_compact_rows_and_samples(ChunkReader& reader, std::uint64_t rows,
                                          RowChecker& checker, MotionTable& table) {
  std::vector<std::uint8_t> bytes;
  if (ReadProblem problem = read_block(reader, bytes); problem.failed()) return problem;
  const std::uint8_t* pos = bytes.data();
  const std::uint8_t* const end = pos + bytes.size();
  MotionKey key = 0;
  for (std::uint64_t i = 0; i < rows; ++i) {
    const std::string where = "motion row " + std::to_string(i);
    std::uint64_t value = 0;
    if (!read_varint(pos, end, value)) return {where + ": cut off", 0};
    if (i > 0 && value == 0) return {where + ": rows out of order", 0};
    // A distance past the largest key: a key below the one before, wrapped.
    if (value > ~MotionKey{0} - key) return {where + ": rows out of order", 0};
    key += value;
    MotionRow row;
    for (std::int64_t& sum : row.sums) {
      if (!read_varint(pos, end, value)) return {where + ": cut off", 0};
      sum = unzigzag(value);
    }
    if (auto problem = checker.add(i, key, row)) return {std::move(problem), 0};
  }
  if (pos != end) return {std::string("bytes after the last motion row"), 0};
  if (auto problem = checker.finish()) return {std::move(problem), 0};

  if (ReadProblem problem = read_block(reader, bytes); problem.failed()) return problem;
  pos = bytes.data();
  const std::uint8_t* const samples_end = pos + bytes.size();
  for (int h = 0; h < table.config().horizons; ++h) {
    const std::string where = "calibration sample of horizon " + std::to_string(h + 1);
    std::uint64_t count = 0;
    if (!read_varint(pos, samples_end, count)) return {where + ": cut off", 0};
    if (auto problem = check_sample_size(table.config(), h, count)) {
      return {std::move(problem), 0};
    }
    std::vector<HeldOutInstance> sample(count);
    for (HeldOutInstance& held : sample) {
      if (!decode_compact_held_out(pos, samples_end, held)) return {where + ": cut off", 0};
    }
    if (auto problem = add_sample(table, h, sample)) return {std::move(problem), 0};
  }
  if (pos != samples_end) return {std::string("bytes after the last calibration sample"), 0};
  return {};
}

ReadProblem read_set_plays(ChunkReader& reader, MotionTable& table) {
  std::uint32_t episodes = 0;
  if (const int error = reader.read_u32(episodes); error != 0) return {std::nullopt, error};
  if (episodes > SetPlayMemory::max_episodes) {
    return {std::to_string(episodes) + " kick-offs, more than a memory keeps (" +
                std::to_string(SetPlayMemory::max_episodes) + ")",
            0};
  }
  std::array<std::uint8_t, set_play_snapshot_size> bytes{};
  std::optional<SetPlayEpisode> previous;
  for (std::uint32_t e = 0; e < episodes; ++e) {
    const std::string where = "kick-off " + std::to_string(e);
    std::uint32_t count = 0;
    if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
    if (count > SetPlayMemory::max_snapshots_per_episode) {
      return {where + ": " + std::to_string(count) + " snapshots, more than an episode keeps", 0};
    }
    SetPlayEpisode episode;
    for (std::uint32_t i = 0; i < count; ++i) {
      if (const int error = reader.read(bytes.data(), bytes.size()); error != 0) {
        return {std::nullopt, error};
      }
      episode.snapshots.push_back(decode_set_play_snapshot(bytes.data()));
    }
    if (!SetPlayMemory::valid_episode(episode)) return {where + ": invalid snapshots", 0};
    if (previous && episode < *previous) return {where + ": kick-offs out of order", 0};
    previous = episode;
    const std::size_t kept = table.set_plays().episodes().size();
    table.set_plays().add(std::move(episode));
    if (table.set_plays().episodes().size() != kept + 1) {
      return {where + ": no snapshot before the kick-off was over", 0};
    }
  }
  return {};
}

}  // namespace

ReadProblem read_motion_section(ChunkReader& reader, double header_step_s, MotionLayout layout,
                                std::optional<MotionTable>& out) {
  std::array<std::uint8_t, motion_fixed_size> fixed{};
  if (const int error = reader.read(fixed.data(), fixed.size()); error != 0) {
    return {std::nullopt, error};
  }
  std::uint32_t horizons = 0;
  const MotionConfig config = decode_motion_config(fixed.data(), horizons);
  if (horizons > static_cast<std::uint32_t>(MotionConfig::max_horizons) ||
      !valid_motion_config(config)) {
    return {std::string("invalid motion model configuration"), 0};
  }
  if (config.step_s != header_step_s) {
    return {"the motion model's step " + std::to_string(config.step_s) +
                " s differs from the header's " + std::to_string(header_step_s) + " s",
            0};
  }
  const std::uint64_t instances = get_u64(&fixed[motion_config_size]);
  const std::uint64_t seen = get_u64(&fixed[motion_config_size + 8]);
  const std::uint64_t rows = get_u64(&fixed[motion_rows_offset]);

  MotionTable table(config);
  RowChecker checker(table, instances);
  ReadProblem problem = layout == MotionLayout::compact
                            ? read_compact_rows_and_samples(reader, rows, checker, table)
                            : read_fixed_rows_and_samples(reader, rows, checker, table);
  if (problem.failed()) return problem;
  if (table.held_out() > seen) {
    return {"the calibration samples hold " + std::to_string(table.held_out()) +
                " instances, more than the " + std::to_string(seen) + " held out",
            0};
  }
  table.restore_held_out_seen(seen);
  if (layout != MotionLayout::fixed) {
    if (problem = read_set_plays(reader, table); problem.failed()) return problem;
  }
  out.emplace(std::move(table));
  return {};
}

}  // namespace detail
}  // namespace motion_model
}  // namespace ssl_formation
