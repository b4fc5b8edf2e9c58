// load_table and save_table: the header and counts (table_format), the motion section
// (motion_table_format) and the durable write (durable_file) put together, with the checks in
// the order table_file.hpp gives and the messages that name the file.

#include "ssl_formation/models/table_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>

#include "ssl_formation/files/chunk_reader.hpp"
#include "ssl_formation/files/durable_file.hpp"
#include "ssl_formation/files/file_descriptor.hpp"
#include "ssl_formation/motion_model/motion_table_format.hpp"
#include "table_format.hpp"

namespace ssl_formation {
inline namespace models {

using namespace detail;
using namespace files::detail;
using namespace motion_model::detail;

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

namespace {

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

Unexpected<TableLoadError> content_failure(const std::filesystem::path& path,
                                           const ReadProblem& problem) {
  if (problem.read_error != 0) return read_failure(path, problem.read_error);
  return load_failure(TableFileError::corrupt, path, "corrupt: " + *problem.content);
}

// How a version lays out its motion section; none for version 1 (or a version not read).
std::optional<MotionLayout> motion_layout_of(std::uint32_t version) {
  switch (version) {
    case table_file_motion_version:
      return MotionLayout::fixed;
    case table_file_set_play_version:
      return MotionLayout::fixed_with_set_plays;
    case table_file_compact_motion_version:
      return MotionLayout::compact;
    default:
      return std::nullopt;
  }
}

// The magic and the version, from the first bytes of the file (`available` of them): the
// version, or why the file is not one this program reads.
Result<std::uint32_t, TableLoadError> check_magic_and_version(
    const std::filesystem::path& path, const std::array<std::uint8_t, header_size>& header_bytes,
    std::uint64_t available, std::uint64_t file_size) {
  const std::size_t magic_available =
      static_cast<std::size_t>(std::min<std::uint64_t>(available, table_magic.size()));
  if (!std::equal(table_magic.begin(), table_magic.begin() + magic_available,
                  header_bytes.begin())) {
    return load_failure(TableFileError::not_a_table, path,
                        "not a table file: bad magic (a table file starts with \"SSLFTABL\")");
  }
  if (magic_available < table_magic.size()) {
    // A strict prefix of the magic (an empty file included) is most likely a cut-off table.
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) + " bytes, shorter than the " +
                            std::to_string(table_magic.size()) + "-byte magic");
  }

  // Before any checksum: another version may lay out or checksum its header otherwise.
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
                            std::to_string(table_file_compact_motion_version) + ")");
  }
  if (version != table_file_version && !motion_layout_of(version)) {
    return load_failure(
        TableFileError::wrong_version, path,
        "format version " + std::to_string(version) + ", but this program reads version " +
            std::to_string(table_file_version) + ", " + std::to_string(table_file_motion_version) +
            ", " + std::to_string(table_file_set_play_version) + " or " +
            std::to_string(table_file_compact_motion_version));
  }
  return version;
}

// The size the file must have by its header and, for version 3, its motion section's sizes,
// or why the file is truncated or corrupt; never past `file_size`.
Result<std::uint64_t, TableLoadError> expected_file_size(const std::filesystem::path& path, int fd,
                                                         const TableHeader& header,
                                                         std::uint64_t file_size) {
  const std::optional<MotionLayout> layout = motion_layout_of(header.version);
  const bool has_motion = layout.has_value();
  const std::uint64_t counts_end = header_size + counts_size(header);
  const std::uint64_t least = counts_end + (has_motion ? motion_fixed_size : 0) + checksum_size;
  if (file_size < least) {
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) + " bytes, its header says " +
                            (has_motion ? "at least " : "") + std::to_string(least));
  }
  if (!has_motion) return least;

  // The motion section's sizes are not covered by the header checksum: see table_file.hpp.
  const MotionExtent extent = motion_extent(fd, counts_end, file_size - checksum_size, *layout);
  if (extent.read_error != 0) return read_failure(path, extent.read_error);
  if (extent.past_end) {
    // A file whose checksum matches is whole: its sizes themselves are wrong.
    std::uint32_t crc = 0;
    if (const int error = crc_of_range(fd, 0, file_size - checksum_size, crc); error != 0) {
      return read_failure(path, error);
    }
    std::uint32_t stored_crc = 0;
    ChunkReader crc_reader(fd, file_size - checksum_size, file_size);
    if (const int error = crc_reader.read_u32(stored_crc); error != 0) {
      return read_failure(path, error);
    }
    if (crc == stored_crc) {
      return load_failure(TableFileError::corrupt, path,
                          "corrupt: the motion section's sizes run past the end of the file");
    }
    return load_failure(TableFileError::truncated, path,
                        "truncated: " + std::to_string(file_size) +
                            " bytes, the file ends inside its motion section (its sizes say "
                            "at least " +
                            std::to_string(extent.at_least + checksum_size) + ")");
  }
  // Invalid horizons leave the extent unknown: the whole file is checksummed as it is, and the
  // configuration is rejected after the checksum.
  return extent.known ? extent.end + checksum_size : file_size;
}

}  // namespace

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

  // Magic and version.
  std::array<std::uint8_t, header_size> header_bytes{};
  const std::uint64_t header_available = std::min<std::uint64_t>(file_size, header_size);
  if (header_available > 0) {
    ChunkReader reader(fd.get(), 0, header_available);
    if (const int error = reader.read(header_bytes.data(), header_available); error != 0) {
      return read_failure(path, error);
    }
  }
  const auto version = check_magic_and_version(path, header_bytes, header_available, file_size);
  if (!version) return Unexpected(version.error());

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
  const TableHeader header = decode_header(header_bytes.data());
  if (const auto problem = header_problem(header)) {
    return load_failure(TableFileError::corrupt, path, "corrupt: " + *problem);
  }
  const Grid grid(static_cast<int>(header.length), static_cast<int>(header.width));
  if (expected_grid && *expected_grid != grid) {
    return fail(TableLoadError{TableFileError::wrong_grid,
                               path.string() + " holds a " + grid.to_string() + " grid, expected " +
                                   expected_grid->to_string() + " (give --grid " +
                                   grid.to_string() + " to use it)"});
  }

  // Length.
  const auto expected_size = expected_file_size(path, fd.get(), header, file_size);
  if (!expected_size) return Unexpected(expected_size.error());
  if (file_size > *expected_size) {
    return load_failure(TableFileError::corrupt, path,
                        "corrupt: " + std::to_string(file_size) + " bytes, its header says " +
                            std::to_string(*expected_size) + " (" +
                            std::to_string(file_size - *expected_size) + " trailing bytes)");
  }

  // File checksum, before any count is trusted.
  const std::uint64_t checksum_offset = *expected_size - checksum_size;
  std::uint32_t crc = 0;
  if (const int error = crc_of_range(fd.get(), 0, checksum_offset, crc); error != 0) {
    return read_failure(path, error);
  }
  std::uint32_t stored_crc = 0;
  {
    ChunkReader reader(fd.get(), checksum_offset, *expected_size);
    if (const int error = reader.read_u32(stored_crc); error != 0) {
      return read_failure(path, error);
    }
  }
  if (crc != stored_crc) {
    return load_failure(TableFileError::corrupt, path, "checksum mismatch: the file is corrupt");
  }

  // Counts, then the motion section. Both checksums matched, so a problem here comes from the
  // writer, not the disk.
  StoredTable stored{TransitionTable(grid, storage), header.metadata, nullptr};
  std::uint64_t sum = 0;
  ChunkReader reader(fd.get(), header_size, checksum_offset);
  if (const ReadProblem problem = read_counts(reader, header, stored.table, sum);
      problem.failed()) {
    return content_failure(path, problem);
  }
  if (sum != header.transitions) {
    return load_failure(TableFileError::corrupt, path,
                        "corrupt: the counts sum to " + std::to_string(sum) +
                            " transitions, the header says " + std::to_string(header.transitions));
  }
  if (const std::optional<MotionLayout> layout = motion_layout_of(header.version)) {
    std::optional<MotionTable> motion;
    if (const ReadProblem problem =
            read_motion_section(reader, header.metadata.step_s, *layout, motion);
        problem.failed()) {
      return content_failure(path, problem);
    }
    if (motion) stored.motion = std::make_shared<const MotionTable>(std::move(*motion));
  }
  stored.format_version = header.version;
  return stored;
}

namespace {

Unexpected<Error> save_failure(const std::filesystem::path& path, const std::string& what) {
  return fail("cannot save table " + path.string() + ": " + what);
}

Result<TableSaved> save_any_table(const std::filesystem::path& path, const TransitionTable& table,
                                  const TableMetadata& metadata, const MotionTable* motion,
                                  const SaveHooks& hooks) {
  // Never write a file that load_table would reject.
  if (!metadata.field.valid()) return save_failure(path, "invalid field size");
  if (!valid_step(metadata.step_s)) return save_failure(path, "invalid step");
  EncodedMotion encoded;
  if (motion) {
    auto section = encode_motion_section(*motion, metadata.step_s);
    if (!section) return save_failure(path, section.error().message);
    encoded = std::move(*section);
  }

  const TableHeader header =
      header_for(table, metadata, motion ? table_file_compact_motion_version : table_file_version);
  const auto write_content = [&](FileWriter& writer) -> std::optional<std::string> {
    const auto header_bytes = encode_header(header);
    writer.write(header_bytes.data(), header_bytes.size());
    if (auto problem = write_counts(writer, table)) return problem;
    if (motion) write_motion_section(writer, *motion, encoded);
    writer.write_u32(writer.crc());
    return std::nullopt;
  };
  const auto written =
      write_file_durably(path, write_content, {hooks.before_rename, hooks.sync_folder});
  if (!written) return save_failure(path, written.error().message);
  if (!written->folder_not_synced.empty()) {
    return TableSaved{false, "saved table " + path.string() + ", but " +
                                 written->folder_not_synced +
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

}  // namespace models
}  // namespace ssl_formation
