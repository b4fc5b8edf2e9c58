#pragma once
// The motion section of a table file (the layouts in table_file.hpp): the motion model's
// configuration, its rows, its held-out calibration instances and its kick-offs.
//
// The fields of a row and of a calibration instance, in file order, are MotionRow::sums and
// motion_instance_values (motion_model.hpp; motion_table_file_test.cpp checks that no field of
// the structs is left out).

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ssl_formation/base/result.hpp"
#include "ssl_formation/files/chunk_reader.hpp"
#include "ssl_formation/files/durable_file.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace motion_model {
namespace detail {

// Written with the file codec (files/byte_codec.hpp, chunk_reader.hpp, durable_file.hpp).
using namespace files::detail;

inline constexpr std::uint64_t motion_config_size = 68;
// The configuration, then the u64 instances, held-out instances seen and row count.
inline constexpr std::uint64_t motion_fixed_size = motion_config_size + 3 * 8;

// How a file lays out its motion section: version 3 (fixed-width rows and calibration
// instances), version 4 (the same, then the kick-offs) or version 5 (compact: the rows and the
// calibration instances as varints, each block preceded by its length, then the kick-offs).
enum class MotionLayout { fixed, fixed_with_set_plays, compact };

// The compact section's variable parts, encoded; their sizes tell a file's size before it is
// written (the budget of prune_to_budget).
struct EncodedMotion {
  std::uint64_t rows = 0;
  std::vector<std::uint8_t> row_bytes;
  std::vector<std::uint8_t> calibration_bytes;
};

// `motion` encoded for a file whose header's step is `step_s`, or why it cannot go into one
// (every check load_table makes, so that save_table never writes a file it rejects).
Result<EncodedMotion> encode_motion_section(const MotionTable& motion, double step_s);
// The bytes of the compact motion section of `motion`, encoded as `encoded`.
std::uint64_t motion_section_size(const MotionTable& motion, const EncodedMotion& encoded);
// Writes the compact motion section of `motion`, encoded as `encoded`.
void write_motion_section(FileWriter& writer, const MotionTable& motion,
                          const EncodedMotion& encoded);

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
MotionExtent motion_extent(int fd, std::uint64_t begin, std::uint64_t limit, MotionLayout layout);

// Reads the motion section into `out`, checking every field; `header_step_s` is the step the
// file's header states.
ReadProblem read_motion_section(ChunkReader& reader, double header_step_s, MotionLayout layout,
                                std::optional<MotionTable>& out);

}  // namespace detail
}  // namespace motion_model
}  // namespace ssl_formation
