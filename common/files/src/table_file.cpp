#include "ssl_formation/files/table_file.hpp"

#include "ssl_formation/match/match.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

namespace ssl_formation {

namespace {

static_assert(std::numeric_limits<double>::is_iec559, "doubles are stored as IEEE-754 bits");

constexpr std::array<std::uint8_t, 8> magic = {'S', 'S', 'L', 'F', 'T', 'A', 'B', 'L'};
constexpr std::uint64_t version_offset = 8;
constexpr std::uint64_t header_fields_size = 80;  // everything the header checksum covers
constexpr std::uint64_t header_size = header_fields_size + 4;
constexpr std::uint64_t checksum_size = 4;
constexpr std::uint32_t encoding_dense = 0;
constexpr std::uint32_t encoding_sparse = 1;
constexpr std::size_t io_chunk = std::size_t{1} << 16;

// ---- Little-endian encoding, byte by byte so the host's layout never matters.

void put_u32(std::uint8_t* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}
void put_u64(std::uint8_t* out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}
std::uint32_t get_u32(const std::uint8_t* in) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= std::uint32_t{in[i]} << (8 * i);
  return value;
}
std::uint64_t get_u64(const std::uint8_t* in) {
  std::uint64_t value = 0;
  for (int i = 0; i < 8; ++i) value |= std::uint64_t{in[i]} << (8 * i);
  return value;
}

// zlib's crc32 takes a uInt length; our chunks are far below that, but large spans are split
// anyway so the function is correct for any size.
std::uint32_t crc_update(std::uint32_t crc, const std::uint8_t* data, std::size_t size) {
  uLong value = crc;
  while (size > 0) {
    const std::size_t part = std::min<std::size_t>(size, std::numeric_limits<uInt>::max());
    value = ::crc32(value, data, static_cast<uInt>(part));
    data += part;
    size -= part;
  }
  return static_cast<std::uint32_t>(value);
}
std::uint32_t crc_of(const std::uint8_t* data, std::size_t size) {
  return crc_update(static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0)), data, size);
}

std::string errno_text(int error) { return std::strerror(error); }

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd = -1) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  void reset(int fd) noexcept {
    close();
    fd_ = fd;
  }
  // Closes now and reports the error, because close can be the first to report a failed write.
  // noexcept: the destructors of this and TemporaryFile call it.
  int close() noexcept {
    const int fd = std::exchange(fd_, -1);
    return fd >= 0 && ::close(fd) != 0 ? errno : 0;
  }

 private:
  int fd_;
};

// The table's dimensions as the file states them.
struct Header {
  std::uint32_t version = 0;
  std::uint32_t length = 0;
  std::uint32_t width = 0;
  std::uint32_t encoding = 0;
  TableMetadata metadata;
  std::uint64_t transitions = 0;
  std::uint64_t rows = 0;
  std::uint64_t entries = 0;
};

std::array<std::uint8_t, header_size> encode_header(const Header& header) {
  std::array<std::uint8_t, header_size> out{};
  std::copy(magic.begin(), magic.end(), out.begin());
  put_u32(&out[8], header.version);
  put_u32(&out[12], header.length);
  put_u32(&out[16], header.width);
  put_u32(&out[20], header.encoding);
  put_u64(&out[24], std::bit_cast<std::uint64_t>(header.metadata.field.length_mm));
  put_u64(&out[32], std::bit_cast<std::uint64_t>(header.metadata.field.width_mm));
  put_u64(&out[40], std::bit_cast<std::uint64_t>(header.metadata.step_s));
  put_u64(&out[48], header.metadata.samples);
  put_u64(&out[56], header.transitions);
  put_u64(&out[64], header.rows);
  put_u64(&out[72], header.entries);
  put_u32(&out[header_fields_size], crc_of(out.data(), header_fields_size));
  return out;
}

Header decode_header(const std::uint8_t* in) {
  Header header;
  header.version = get_u32(&in[8]);
  header.length = get_u32(&in[12]);
  header.width = get_u32(&in[16]);
  header.encoding = get_u32(&in[20]);
  header.metadata.field.length_mm = std::bit_cast<double>(get_u64(&in[24]));
  header.metadata.field.width_mm = std::bit_cast<double>(get_u64(&in[32]));
  header.metadata.step_s = std::bit_cast<double>(get_u64(&in[40]));
  header.metadata.samples = get_u64(&in[48]);
  header.transitions = get_u64(&in[56]);
  header.rows = get_u64(&in[64]);
  header.entries = get_u64(&in[72]);
  return header;
}

bool valid_step(double step_s) { return std::isfinite(step_s) && step_s > 0.0; }

// ---- Loading

// Reads a byte range of the file through a fixed buffer, so that loading costs memory in
// proportion to the table it builds, never to the file. pread leaves the file offset alone and
// the descriptor is read-only, so nothing here can change the file.
class ChunkReader {
 public:
  ChunkReader(int fd, std::uint64_t begin, std::uint64_t end)
      : fd_(fd), next_(begin), end_(end), buffer_(io_chunk) {}

  // 0 on success, else an errno value; EOF before `end` reports ENODATA.
  int read(std::uint8_t* out, std::size_t size) {
    while (size > 0) {
      if (pos_ == filled_) {
        if (const int error = refill(); error != 0) return error;
      }
      const std::size_t part = std::min(size, filled_ - pos_);
      std::memcpy(out, &buffer_[pos_], part);
      pos_ += part;
      out += part;
      size -= part;
    }
    return 0;
  }
  int read_u32(std::uint32_t& value) {
    if (filled_ - pos_ >= 4) {  // the common case, without the copy
      value = get_u32(&buffer_[pos_]);
      pos_ += 4;
      return 0;
    }
    std::uint8_t bytes[4];
    if (const int error = read(bytes, 4); error != 0) return error;
    value = get_u32(bytes);
    return 0;
  }
  int read_u64(std::uint64_t& value) {
    std::uint8_t bytes[8];
    if (const int error = read(bytes, 8); error != 0) return error;
    value = get_u64(bytes);
    return 0;
  }
  // Exposes each chunk in turn until `end`; used to checksum a range.
  template <typename Visit>
  int for_each_chunk(Visit&& visit) {
    while (true) {
      if (pos_ == filled_) {
        if (next_ == end_) return 0;
        if (const int error = refill(); error != 0) return error;
      }
      visit(&buffer_[pos_], filled_ - pos_);
      pos_ = filled_;
    }
  }

 private:
  int refill() {
    if (next_ >= end_) return ENODATA;
    const std::size_t want =
        static_cast<std::size_t>(std::min<std::uint64_t>(buffer_.size(), end_ - next_));
    ssize_t got = 0;
    do {
      got = ::pread(fd_, buffer_.data(), want, static_cast<off_t>(next_));
    } while (got < 0 && errno == EINTR);
    if (got < 0) return errno;
    if (got == 0) return ENODATA;  // the file shrank under us
    next_ += static_cast<std::uint64_t>(got);
    pos_ = 0;
    filled_ = static_cast<std::size_t>(got);
    return 0;
  }

  int fd_;
  std::uint64_t next_;
  std::uint64_t end_;
  std::vector<std::uint8_t> buffer_;
  std::size_t pos_ = 0;
  std::size_t filled_ = 0;
};

Unexpected<TableLoadError> load_failure(TableFileError kind, const std::filesystem::path& path,
                                        const std::string& what) {
  return Unexpected(TableLoadError{kind, path.string() + ": " + what});
}

Unexpected<TableLoadError> read_failure(const std::filesystem::path& path, int error) {
  if (error == ENODATA) {
    return load_failure(TableFileError::truncated, path,
                        "truncated: the file ended while it was being read");
  }
  return load_failure(TableFileError::io_error, path, "read failed: " + errno_text(error));
}

// Everything a header must satisfy before its sizes are trusted; a reason if it does not.
std::optional<std::string> header_problem(const Header& header) {
  const std::uint32_t max = static_cast<std::uint32_t>(Grid::max_cells);
  if (header.length < 1 || header.width < 1 || header.length > max || header.width > max ||
      header.length * header.width > max) {
    return "invalid grid " + std::to_string(header.length) + "x" + std::to_string(header.width) +
           " in the header";
  }
  if (!header.metadata.field.valid()) return std::string("invalid field size in the header");
  if (!valid_step(header.metadata.step_s)) return std::string("invalid step in the header");
  const std::uint64_t cells = std::uint64_t{header.length} * header.width;
  const std::uint64_t states = cells * cells * cells;
  if (header.encoding == encoding_dense) {
    if (header.rows != states || header.entries != states * states) {
      return std::string("dense row and entry counts do not match the grid");
    }
  } else if (header.encoding == encoding_sparse) {
    // Every row record holds at least one entry and at most S.
    if (header.rows > states || header.entries < header.rows ||
        header.entries > header.rows * states) {
      return std::string("sparse row and entry counts are inconsistent");
    }
  } else {
    return "unknown count encoding " + std::to_string(header.encoding);
  }
  if (header.entries == 0 && header.transitions != 0) {
    return std::string("nonzero transition total with no counts");
  }
  return std::nullopt;
}

std::uint64_t body_size(const Header& header) {
  return header.encoding == encoding_dense ? header.entries * 4
                                           : header.rows * 8 + header.entries * 8;
}

// Reads the counts into `table`; a reason on inconsistent content or an errno on a failed read.
struct BodyProblem {
  std::optional<std::string> content;
  int read_error = 0;
};

BodyProblem read_dense_body(ChunkReader& reader, TransitionTable& table, std::uint64_t& sum) {
  const StateIndex states = table.codec().state_count();
  for (StateIndex from = 0; from < states; ++from) {
    for (StateIndex to = 0; to < states; ++to) {
      std::uint32_t count = 0;
      if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
      if (count == 0) continue;
      table.add(from, to, count);
      sum += count;
    }
  }
  return {};
}

BodyProblem read_sparse_body(ChunkReader& reader, const Header& header, TransitionTable& table,
                             std::uint64_t& sum) {
  const StateIndex states = table.codec().state_count();
  std::uint64_t entries_read = 0;
  std::optional<StateIndex> previous_from;
  for (std::uint64_t row = 0; row < header.rows; ++row) {
    std::uint32_t from = 0;
    std::uint32_t n = 0;
    if (const int error = reader.read_u32(from); error != 0) return {std::nullopt, error};
    if (const int error = reader.read_u32(n); error != 0) return {std::nullopt, error};
    const std::string where =
        "row record " + std::to_string(row) + " (from state " + std::to_string(from) + ")";
    if (from >= states) return {where + ": state index out of range", 0};
    if (previous_from && from <= *previous_from) return {where + ": rows out of order", 0};
    if (n == 0 || n > header.entries - entries_read) {
      return {where + ": entry count " + std::to_string(n) + " is inconsistent", 0};
    }
    previous_from = from;
    std::optional<StateIndex> previous_to;
    for (std::uint32_t i = 0; i < n; ++i) {
      std::uint32_t to = 0;
      std::uint32_t count = 0;
      if (const int error = reader.read_u32(to); error != 0) return {std::nullopt, error};
      if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
      if (to >= states) return {where + ": target state index out of range", 0};
      if (previous_to && to <= *previous_to) return {where + ": targets out of order", 0};
      if (count == 0) return {where + ": zero count stored", 0};
      previous_to = to;
      table.add(from, to, count);
      sum += count;
    }
    entries_read += n;
  }
  if (entries_read != header.entries) {
    return {"the rows hold " + std::to_string(entries_read) + " entries, the header says " +
                std::to_string(header.entries),
            0};
  }
  return {};
}

// ---- The motion section (version 3)

// The fields of a row and of a calibration instance, in file order, are MotionRow::sums and
// motion_instance_values (motion_model.hpp; motion_table_file_test.cpp checks that no field of
// the structs is left out).

constexpr std::uint64_t motion_config_size = 68;
constexpr std::uint64_t motion_fixed_size = motion_config_size + 3 * 8;  // + instances, seen, rows
constexpr std::uint64_t motion_row_size = 8 + 8 * MotionRow::size;
// hash, robot_id, the values, context
constexpr std::uint64_t held_out_size = 8 + 4 + 4 * motion_instance_values.size() + 4;
constexpr std::uint64_t motion_horizons_offset = 8;  // in the configuration
constexpr std::uint64_t motion_rows_offset = motion_config_size + 16;  // the row count

MotionConfig decode_motion_config(const std::uint8_t* in, std::uint32_t& horizons) {
  MotionConfig config;
  config.step_s = std::bit_cast<double>(get_u64(&in[0]));
  horizons = get_u32(&in[8]);
  config.horizons = static_cast<int>(std::min<std::uint32_t>(
      horizons, static_cast<std::uint32_t>(MotionConfig::max_horizons) + 1));
  config.velocity_window_s = std::bit_cast<double>(get_u64(&in[12]));
  config.tolerance_s = std::bit_cast<double>(get_u64(&in[20]));
  config.calibration_block_s = std::bit_cast<double>(get_u64(&in[28]));
  config.calibration_one_in = get_u32(&in[36]);
  config.calibration_capacity = get_u32(&in[40]);
  config.settle_window_s = std::bit_cast<double>(get_u64(&in[44]));
  config.long_settle_window_s = std::bit_cast<double>(get_u64(&in[52]));
  config.learn_interval_s = std::bit_cast<double>(get_u64(&in[60]));
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
  if (parts.level != MotionLevel::robot) return std::string("not a robot-level key");
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

// Where the motion section that starts at `begin` ends, from its sizes, or why that is unknown.
struct MotionExtent {
  std::uint64_t end = 0;       // the first byte after it, when known
  bool known = false;          // false: its horizons are invalid (the content check says so)
  bool past_end = false;       // its sizes say it runs into or past the file's checksum
  std::uint64_t at_least = 0;  // with past_end: the file size the sizes read so far imply
  int read_error = 0;
};

MotionExtent motion_extent(int fd, std::uint64_t begin, std::uint64_t file_size) {
  MotionExtent extent;
  const std::uint64_t limit = file_size - checksum_size;  // where the checksum starts
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
    extent.at_least = pos + needed + checksum_size;
    return extent;
  };
  const std::uint64_t rows = get_u64(&fixed[motion_rows_offset]);
  if (rows > (limit - pos) / motion_row_size) {
    // at_least saturates rather than overflows for an absurd row count.
    return past(rows > (UINT64_MAX / 2) / motion_row_size ? UINT64_MAX / 2 : rows * motion_row_size);
  }
  pos += rows * motion_row_size;
  for (std::uint32_t h = 0; h < horizons; ++h) {
    if (limit - pos < 4) return past(4);
    std::uint8_t bytes[4];
    {
      ChunkReader reader(fd, pos, pos + 4);
      if ((extent.read_error = reader.read(bytes, 4)) != 0) return extent;
    }
    pos += 4;
    const std::uint64_t count = get_u32(bytes);
    if (count > (limit - pos) / held_out_size) return past(count * held_out_size);
    pos += count * held_out_size;
  }
  extent.end = pos;
  extent.known = true;
  return extent;
}

// Reads the motion section into `out`; a reason on inconsistent content or an errno on a
// failed read.
BodyProblem read_motion_section(ChunkReader& reader, double header_step_s,
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
  std::uint64_t sum = 0;
  std::optional<MotionKey> previous_key;
  std::array<std::uint8_t, motion_row_size> row_bytes{};
  for (std::uint64_t i = 0; i < rows; ++i) {
    if (const int error = reader.read(row_bytes.data(), row_bytes.size()); error != 0) {
      return {std::nullopt, error};
    }
    const MotionKey key = get_u64(&row_bytes[0]);
    const MotionRow row = decode_motion_row(&row_bytes[8]);
    const std::string where = "motion row " + std::to_string(i);
    if (previous_key && key <= *previous_key) return {where + ": rows out of order", 0};
    previous_key = key;
    if (const auto problem = motion_row_problem(key, row, config)) {
      return {where + ": " + *problem, 0};
    }
    if (static_cast<std::uint64_t>(row.n()) > instances - sum) {
      return {"the motion rows hold more than the " + std::to_string(instances) +
                  " instances the section says",
              0};
    }
    sum += static_cast<std::uint64_t>(row.n());
    table.add_row(key, row);
  }
  if (sum != instances) {
    return {"the motion rows hold " + std::to_string(sum) + " instances, the section says " +
                std::to_string(instances),
            0};
  }

  std::uint64_t held_out = 0;
  std::array<std::uint8_t, held_out_size> held_bytes{};
  for (int h = 0; h < config.horizons; ++h) {
    std::uint32_t count = 0;
    if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
    const std::string where = "calibration sample of horizon " + std::to_string(h + 1);
    if (count > config.calibration_capacity) {
      return {where + ": " + std::to_string(count) + " instances, more than its capacity " +
                  std::to_string(config.calibration_capacity),
              0};
    }
    std::vector<HeldOutInstance> sample;
    sample.reserve(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      if (const int error = reader.read(held_bytes.data(), held_bytes.size()); error != 0) {
        return {std::nullopt, error};
      }
      sample.push_back(decode_held_out(held_bytes.data()));
      if (sample.back().instance.context >= MotionFeatures::context_count) {
        return {where + ": instance " + std::to_string(i) + ": context " +
                    std::to_string(sample.back().instance.context) + " out of range",
                0};
      }
      table.add_held_out(h, sample.back());
    }
    // Within its capacity every instance is kept, so the file's order must be the table's
    // (equal neighbours are allowed: merging tables trained on the same stream keeps both).
    if (table.calibration(h) != sample) return {where + ": instances out of order", 0};
    held_out += count;
  }
  if (held_out > seen) {
    return {"the calibration samples hold " + std::to_string(held_out) +
                " instances, more than the " + std::to_string(seen) + " held out",
            0};
  }
  table.restore_held_out_seen(seen);
  out.emplace(std::move(table));
  return {};
}

// ---- Saving

// Writes through a fixed buffer, keeping the CRC of everything written and the first error,
// so that callers inside a visitor (which cannot stop early) just keep going until the end.
class BufferedWriter {
 public:
  explicit BufferedWriter(int fd) : fd_(fd) { buffer_.reserve(io_chunk); }

  void write(const std::uint8_t* data, std::size_t size) {
    if (error_ != 0) return;
    crc_ = crc_update(crc_, data, size);
    while (size > 0) {
      const std::size_t part = std::min(size, io_chunk - buffer_.size());
      buffer_.insert(buffer_.end(), data, data + part);
      data += part;
      size -= part;
      if (buffer_.size() == io_chunk) flush();
    }
  }
  void write_u32(std::uint32_t value) {
    std::uint8_t bytes[4];
    put_u32(bytes, value);
    write(bytes, 4);
  }
  void write_u64(std::uint64_t value) {
    std::uint8_t bytes[8];
    put_u64(bytes, value);
    write(bytes, 8);
  }
  void write_zero_u32s(std::uint64_t n) {
    static const std::array<std::uint8_t, 4096> zeros{};
    std::uint64_t bytes = n * 4;
    while (bytes > 0 && error_ == 0) {
      const std::size_t part = static_cast<std::size_t>(std::min<std::uint64_t>(bytes, 4096));
      write(zeros.data(), part);
      bytes -= part;
    }
  }
  void flush() {
    const std::uint8_t* data = buffer_.data();
    std::size_t left = buffer_.size();
    while (left > 0 && error_ == 0) {
      const ssize_t wrote = ::write(fd_, data, left);
      if (wrote < 0) {
        if (errno != EINTR) error_ = errno;
        continue;
      }
      data += wrote;
      left -= static_cast<std::size_t>(wrote);
    }
    buffer_.clear();
  }
  std::uint32_t crc() const { return crc_; }
  int error() const { return error_; }

 private:
  int fd_;
  std::vector<std::uint8_t> buffer_;
  std::uint32_t crc_ = static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0));
  int error_ = 0;
};

// The temporary file of one save: removed on every way out unless it was renamed into place.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path path) : path_(std::move(path)) {}
  ~TemporaryFile() {
    fd.close();
    if (!renamed_) ::unlink(path_.c_str());
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const std::filesystem::path& path() const { return path_; }
  void mark_renamed() { renamed_ = true; }

  FileDescriptor fd;

 private:
  std::filesystem::path path_;
  bool renamed_ = false;
};

std::filesystem::path temporary_path_for(const std::filesystem::path& path) {
  // The pid keeps processes apart, the counter keeps concurrent saves of one process apart.
  static std::atomic<unsigned> counter{0};
  std::filesystem::path temp = path;
  temp += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  return temp;
}

Unexpected<Error> save_failure(const std::filesystem::path& path, const std::string& what) {
  return fail("cannot save table " + path.string() + ": " + what);
}

}  // namespace

std::string_view to_string(TableFileError error) {
  switch (error) {
    case TableFileError::cannot_open:
      return "cannot_open";
    case TableFileError::not_a_table:
      return "not_a_table";
    case TableFileError::wrong_version:
      return "wrong_version";
    case TableFileError::wrong_grid:
      return "wrong_grid";
    case TableFileError::truncated:
      return "truncated";
    case TableFileError::corrupt:
      return "corrupt";
    case TableFileError::io_error:
      return "io_error";
  }
  return "unknown";
}

Result<StoredTable, TableLoadError> load_table(const std::filesystem::path& path,
                                               std::optional<Grid> expected_grid,
                                               TableStorage storage) {
  int fd_value = -1;
  do {
    fd_value = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY);
  } while (fd_value < 0 && errno == EINTR);
  if (fd_value < 0) {
    return load_failure(TableFileError::cannot_open, path, "cannot open: " + errno_text(errno));
  }
  const FileDescriptor fd(fd_value);
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) {
    return load_failure(TableFileError::io_error, path, "cannot stat: " + errno_text(errno));
  }
  if (!S_ISREG(info.st_mode)) {
    return load_failure(TableFileError::cannot_open, path, "cannot open: not a regular file");
  }
  const auto file_size = static_cast<std::uint64_t>(info.st_size);

  // Magic.
  std::array<std::uint8_t, header_size> header_bytes{};
  const std::uint64_t header_available = std::min<std::uint64_t>(file_size, header_size);
  if (header_available > 0) {
    ChunkReader reader(fd.get(), 0, header_available);
    if (const int error = reader.read(header_bytes.data(), header_available); error != 0) {
      return read_failure(path, error);
    }
  }
  const std::size_t magic_available =
      static_cast<std::size_t>(std::min<std::uint64_t>(header_available, magic.size()));
  if (!std::equal(magic.begin(), magic.begin() + magic_available, header_bytes.begin())) {
    return load_failure(TableFileError::not_a_table, path,
                        "not a table file: bad magic (a table file starts with \"SSLFTABL\")");
  }
  if (magic_available < magic.size()) {
    // A strict prefix of the magic (an empty file included) is most likely a cut-off table.
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) + " bytes, shorter than the " +
                            std::to_string(magic.size()) + "-byte magic");
  }

  // Version, before any checksum: another version may lay out or checksum its header otherwise.
  if (file_size < version_offset + 4) {
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) +
                            " bytes, the header is cut off before the format version");
  }
  const std::uint32_t version = get_u32(&header_bytes[version_offset]);
  if (version == table_file_retired_motion_version) {
    return load_failure(TableFileError::wrong_version, path,
                        "format version " + std::to_string(version) +
                            ": a motion table keyed by the features before 2026-12-03 (0.5 m "
                            "cells for every robot, no team phase), which this program would "
                            "misread; train it again from its logs (version " +
                            std::to_string(table_file_motion_version) + ")");
  }
  if (version != table_file_version && version != table_file_motion_version) {
    return load_failure(TableFileError::wrong_version, path,
                        "format version " + std::to_string(version) +
                            ", but this program reads version " +
                            std::to_string(table_file_version) + " or " +
                            std::to_string(table_file_motion_version));
  }
  const bool has_motion = version == table_file_motion_version;

  // Header.
  if (file_size < header_size) {
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) + " bytes, shorter than the " +
                            std::to_string(header_size) + "-byte header");
  }
  if (crc_of(header_bytes.data(), header_fields_size) !=
      get_u32(&header_bytes[header_fields_size])) {
    return load_failure(TableFileError::corrupt, path,
                        "header checksum mismatch: the file is corrupt");
  }
  const Header header = decode_header(header_bytes.data());
  if (const auto problem = header_problem(header)) {
    return load_failure(TableFileError::corrupt, path, "corrupt: " + *problem);
  }
  const Grid grid(static_cast<int>(header.length), static_cast<int>(header.width));
  if (expected_grid && *expected_grid != grid) {
    return fail(TableLoadError{TableFileError::wrong_grid,
                               path.string() + " holds a " + grid.to_string() + " grid, expected " +
                                   expected_grid->to_string()});
  }

  // Length.
  const std::uint64_t counts_end = header_size + body_size(header);
  std::uint64_t expected_size = counts_end + (has_motion ? motion_fixed_size : 0) + checksum_size;
  if (file_size < expected_size) {
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) + " bytes, its header says " +
                            (has_motion ? "at least " : "") + std::to_string(expected_size));
  }
  if (has_motion) {
    // The motion section's sizes are not covered by the header checksum: see table_file.hpp.
    const MotionExtent extent = motion_extent(fd.get(), counts_end, file_size);
    if (extent.read_error != 0) return read_failure(path, extent.read_error);
    if (extent.past_end) {
      // A file whose checksum matches is whole: its sizes themselves are wrong.
      std::uint32_t crc = static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0));
      ChunkReader reader(fd.get(), 0, file_size - checksum_size);
      const int error = reader.for_each_chunk(
          [&crc](const std::uint8_t* data, std::size_t size) { crc = crc_update(crc, data, size); });
      if (error != 0) return read_failure(path, error);
      std::uint32_t stored_crc = 0;
      ChunkReader crc_reader(fd.get(), file_size - checksum_size, file_size);
      if (const int read_error = crc_reader.read_u32(stored_crc); read_error != 0) {
        return read_failure(path, read_error);
      }
      if (crc == stored_crc) {
        return load_failure(TableFileError::corrupt, path,
                            "corrupt: the motion section's sizes run past the end of the file");
      }
      return load_failure(TableFileError::truncated, path,
                          "truncated: " + std::to_string(file_size) +
                              " bytes, the file ends inside its motion section (its sizes say "
                              "at least " +
                              std::to_string(extent.at_least) + ")");
    }
    // Invalid horizons leave the extent unknown: the whole file is checksummed as it is, and
    // the configuration is rejected after the checksum.
    expected_size = extent.known ? extent.end + checksum_size : file_size;
  }
  if (file_size > expected_size) {
    return load_failure(TableFileError::corrupt, path,
                        "corrupt: " + std::to_string(file_size) + " bytes, its header says " +
                            std::to_string(expected_size) + " (" +
                            std::to_string(file_size - expected_size) + " trailing bytes)");
  }

  // File checksum, before any count is trusted.
  const std::uint64_t checksum_offset = expected_size - checksum_size;
  std::uint32_t crc = static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0));
  {
    ChunkReader reader(fd.get(), 0, checksum_offset);
    const int error = reader.for_each_chunk(
        [&crc](const std::uint8_t* data, std::size_t size) { crc = crc_update(crc, data, size); });
    if (error != 0) return read_failure(path, error);
  }
  std::uint32_t stored_crc = 0;
  {
    ChunkReader reader(fd.get(), checksum_offset, expected_size);
    if (const int error = reader.read_u32(stored_crc); error != 0) {
      return read_failure(path, error);
    }
  }
  if (crc != stored_crc) {
    return load_failure(TableFileError::corrupt, path, "checksum mismatch: the file is corrupt");
  }

  // Counts, then the motion section. Both checksums matched, so a problem here comes from the
  // writer, not the disk.
  StoredTable stored{TransitionTable(grid, storage), header.metadata, std::nullopt};
  std::uint64_t sum = 0;
  ChunkReader reader(fd.get(), header_size, checksum_offset);
  const BodyProblem problem = header.encoding == encoding_dense
                                  ? read_dense_body(reader, stored.table, sum)
                                  : read_sparse_body(reader, header, stored.table, sum);
  if (problem.read_error != 0) return read_failure(path, problem.read_error);
  if (problem.content)
    return load_failure(TableFileError::corrupt, path, "corrupt: " + *problem.content);
  if (sum != header.transitions) {
    return load_failure(TableFileError::corrupt, path,
                        "corrupt: the counts sum to " + std::to_string(sum) +
                            " transitions, the header says " + std::to_string(header.transitions));
  }
  if (has_motion) {
    const BodyProblem motion_problem =
        read_motion_section(reader, header.metadata.step_s, stored.motion);
    if (motion_problem.read_error != 0) return read_failure(path, motion_problem.read_error);
    if (motion_problem.content) {
      return load_failure(TableFileError::corrupt, path, "corrupt: " + *motion_problem.content);
    }
  }

  return stored;
}

namespace {

void write_motion_section(BufferedWriter& writer, const MotionConfig& config,
                          const MotionTable& motion,
                          const std::vector<std::pair<MotionKey, MotionRow>>& rows) {
  writer.write_u64(std::bit_cast<std::uint64_t>(config.step_s));
  writer.write_u32(static_cast<std::uint32_t>(config.horizons));
  writer.write_u64(std::bit_cast<std::uint64_t>(config.velocity_window_s));
  writer.write_u64(std::bit_cast<std::uint64_t>(config.tolerance_s));
  writer.write_u64(std::bit_cast<std::uint64_t>(config.calibration_block_s));
  writer.write_u32(config.calibration_one_in);
  writer.write_u32(config.calibration_capacity);
  writer.write_u64(std::bit_cast<std::uint64_t>(config.settle_window_s));
  writer.write_u64(std::bit_cast<std::uint64_t>(config.long_settle_window_s));
  writer.write_u64(std::bit_cast<std::uint64_t>(config.learn_interval_s));
  writer.write_u64(motion.instances());
  writer.write_u64(motion.held_out());
  writer.write_u64(rows.size());
  for (const auto& [key, row] : rows) {
    writer.write_u64(key);
    for (const std::int64_t sum : row.sums) writer.write_u64(static_cast<std::uint64_t>(sum));
  }
  for (int h = 0; h < config.horizons; ++h) {
    const std::vector<HeldOutInstance> sample = motion.calibration(h);
    writer.write_u32(static_cast<std::uint32_t>(sample.size()));
    for (const HeldOutInstance& held : sample) {
      const MotionInstance& i = held.instance;
      writer.write_u64(held.hash);
      writer.write_u32(i.robot_id);
      for (const auto value : motion_instance_values) {
        writer.write_u32(static_cast<std::uint32_t>(i.*value));
      }
      writer.write_u32(i.context);
    }
  }
}

Result<TableSaved> save_any_table(const std::filesystem::path& path, const TransitionTable& table,
                                  const TableMetadata& metadata, const MotionTable* motion,
                                  const SaveHooks& hooks) {
  // Never write a file that load_table would reject.
  if (!metadata.field.valid()) return save_failure(path, "invalid field size");
  if (!valid_step(metadata.step_s)) return save_failure(path, "invalid step");
  std::vector<std::pair<MotionKey, MotionRow>> motion_rows;
  if (motion) {
    const MotionConfig& config = motion->config();
    if (!valid_motion_config(config)) {
      return save_failure(path, "invalid motion model configuration");
    }
    if (config.step_s != metadata.step_s) {
      return save_failure(path, "the motion model's step differs from the table's");
    }
    motion_rows = motion->sorted_rows();
    std::uint64_t sum = 0;
    for (const auto& [key, row] : motion_rows) {
      if (const auto problem = motion_row_problem(key, row, config)) {
        return save_failure(path, "invalid motion row: " + *problem);
      }
      sum += static_cast<std::uint64_t>(row.n());
    }
    if (sum != motion->instances()) {
      return save_failure(path, "the motion rows do not add up to the motion table's instances");
    }
  }

  const bool dense = table.is_dense();
  const std::uint64_t states = table.codec().state_count();
  Header header;
  header.version = motion ? table_file_motion_version : table_file_version;
  header.length = static_cast<std::uint32_t>(table.grid().length());
  header.width = static_cast<std::uint32_t>(table.grid().width());
  header.encoding = dense ? encoding_dense : encoding_sparse;
  header.metadata = metadata;
  // Totals counted from the very entries that are written, so header and body always agree.
  std::uint64_t sparse_rows = 0;
  std::uint64_t nonzero = 0;
  std::optional<StateIndex> last_from;
  table.for_each_nonzero([&](StateIndex from, StateIndex, TransitionTable::Count count) {
    if (!last_from || *last_from != from) ++sparse_rows;
    last_from = from;
    ++nonzero;
    header.transitions += count;
  });
  header.rows = dense ? states : sparse_rows;
  header.entries = dense ? states * states : nonzero;

  TemporaryFile temp(temporary_path_for(path));
  int fd_value = -1;
  do {
    fd_value =
        ::open(temp.path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOCTTY, 0644);
  } while (fd_value < 0 && errno == EINTR);
  if (fd_value < 0) {
    return save_failure(
        path, "cannot create temporary file " + temp.path().string() + ": " + errno_text(errno));
  }
  temp.fd.reset(fd_value);

  BufferedWriter writer(temp.fd.get());
  const auto header_bytes = encode_header(header);
  writer.write(header_bytes.data(), header_bytes.size());
  if (dense) {
    // Fill the zeros between the nonzero counts that for_each_nonzero visits in order. Were
    // that order ever broken, `index - next` would wrap and fill the disk, so it is checked.
    std::uint64_t next = 0;
    bool in_order = true;
    table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
      const std::uint64_t index = std::uint64_t{from} * states + to;
      if (!in_order || index < next) {
        in_order = false;
        return;
      }
      writer.write_zero_u32s(index - next);
      writer.write_u32(count);
      next = index + 1;
    });
    writer.write_zero_u32s(states * states - next);
    if (!in_order) return save_failure(path, "the table listed its counts out of order");
  } else {
    // One row is buffered because its record starts with its entry count.
    std::vector<std::pair<StateIndex, TransitionTable::Count>> row;
    std::optional<StateIndex> row_from;
    const auto write_row = [&] {
      if (!row_from) return;
      writer.write_u32(*row_from);
      writer.write_u32(static_cast<std::uint32_t>(row.size()));
      for (const auto& [to, count] : row) {
        writer.write_u32(to);
        writer.write_u32(count);
      }
      row.clear();
    };
    table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
      if (row_from != from) {
        write_row();
        row_from = from;
      }
      row.emplace_back(to, count);
    });
    write_row();
  }
  if (motion) write_motion_section(writer, motion->config(), *motion, motion_rows);
  writer.write_u32(writer.crc());
  writer.flush();
  if (writer.error() != 0) {
    return save_failure(path,
                        "cannot write " + temp.path().string() + ": " + errno_text(writer.error()));
  }
  if (::fsync(temp.fd.get()) != 0) {
    return save_failure(path, "cannot sync " + temp.path().string() + ": " + errno_text(errno));
  }
  if (const int error = temp.fd.close(); error != 0) {
    return save_failure(path, "cannot close " + temp.path().string() + ": " + errno_text(error));
  }

  if (hooks.before_rename && !hooks.before_rename()) {
    return save_failure(path, "aborted before the rename; the old file is unchanged");
  }
  if (::rename(temp.path().c_str(), path.c_str()) != 0) {
    return save_failure(path,
                        "cannot rename " + temp.path().string() + " over it: " + errno_text(errno));
  }
  temp.mark_renamed();

  // The rename lives in the folder; until the folder is synced a crash of the machine may
  // bring the old file back. The new file is in place and whole all the same, so a folder that
  // cannot be synced makes the save less durable, not failed: reporting a failure would make the
  // caller (the trainer exits 1) treat a safe table as lost.
  std::filesystem::path folder = path.parent_path();
  if (folder.empty()) folder = ".";
  const FileDescriptor folder_fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  int sync_error = folder_fd.valid() ? 0 : errno;
  if (sync_error == 0) {
    if (hooks.sync_folder) {
      sync_error = hooks.sync_folder(folder_fd.get());
    } else if (::fsync(folder_fd.get()) != 0) {
      sync_error = errno;
    }
  }
  if (sync_error != 0) {
    return TableSaved{false, "saved table " + path.string() + ", but cannot sync its folder " +
                                 folder.string() + ": " + errno_text(sync_error) +
                                 "; a crash of the machine now may restore the old file"};
  }
  return TableSaved{};
}

}  // namespace

Result<TableSaved> save_table(const std::filesystem::path& path, const TransitionTable& table,
                              const TableMetadata& metadata, const SaveHooks& hooks) {
  return save_any_table(path, table, metadata, nullptr, hooks);
}

Result<TableSaved> save_table(const std::filesystem::path& path, const TransitionTable& table,
                              const TableMetadata& metadata, const MotionTable& motion,
                              const SaveHooks& hooks) {
  return save_any_table(path, table, metadata, &motion, hooks);
}

Result<TableSaved> save_table(const std::filesystem::path& path, const StoredTable& stored,
                              const SaveHooks& hooks) {
  return save_any_table(path, stored.table, stored.metadata,
                        stored.motion ? &*stored.motion : nullptr, hooks);
}

std::string team_table_file_name(std::string_view team) {
  team = trimmed_team_name(team);
  constexpr std::size_t longest = 100;
  std::string name;
  for (const char raw : team.substr(0, longest)) {
    const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(raw)));
    const bool kept = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_' ||
                      (c == '.' && !name.empty());
    name += kept ? c : '_';
  }
  if (name.empty()) name = "unknown";
  return name + ".bin";
}

}  // namespace ssl_formation
