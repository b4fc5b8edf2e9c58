#pragma once
// The motion section of a version-3 table file (the layout in table_file.hpp): the motion
// model's configuration, its rows and its held-out calibration instances.
//
// The fields of a row and of a calibration instance, in file order, are MotionRow::sums and
// motion_instance_values (motion_model.hpp; motion_table_file_test.cpp checks that no field of
// the structs is left out).

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "chunk_reader.hpp"
#include "durable_file.hpp"
#include "ssl_formation/base/result.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation::detail {

inline constexpr std::uint64_t motion_config_size = 68;
// The configuration, then the u64 instances, held-out instances seen and row count.
inline constexpr std::uint64_t motion_fixed_size = motion_config_size + 3 * 8;

using MotionRows = std::vector<std::pair<MotionKey, MotionRow>>;

// The rows of `motion` in file order, or why it cannot go into a file whose header's step is
// `step_s` (every check load_table makes, so that save_table never writes a file it rejects).
Result<MotionRows> motion_rows_to_save(const MotionTable& motion, double step_s);
// Writes the motion section of `motion`, whose rows motion_rows_to_save gave, with its
// kick-offs' memory if it holds any (then the file is version 4).
void write_motion_section(FileWriter& writer, const MotionTable& motion, const MotionRows& rows);

// Where the motion section that starts at `begin` ends, from its sizes, or why that is unknown.
struct MotionExtent {
  std::uint64_t end = 0;       // the first byte after it, when known
  bool known = false;          // false: its horizons are invalid (the content check says so)
  bool past_end = false;       // its sizes say it runs past `limit`
  std::uint64_t at_least = 0;  // with past_end: where the section ends at least, by those sizes
  int read_error = 0;
};
// Reads the section's sizes from `fd`, never past `limit` (where the file checksum starts).
// The sizes have no checksum of their own: table_file.hpp says how a file that ends inside them
// is told from a corrupt one.
// With `with_set_plays` (format version 4) the section ends with the kick-offs' memory.
MotionExtent motion_extent(int fd, std::uint64_t begin, std::uint64_t limit, bool with_set_plays);

// Reads the motion section into `out`, checking every field; `header_step_s` is the step the
// file's header states.
ReadProblem read_motion_section(ChunkReader& reader, double header_step_s, bool with_set_plays,
                                std::optional<MotionTable>& out);

}  // namespace ssl_formation::detail
