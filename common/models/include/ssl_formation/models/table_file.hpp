#pragma once
// The table file: a transition table with what its counts mean (grid, field
// size, step, totals), and optionally the motion model's table, saved atomically and loaded with
// every field checked. In src/: table_format (the header and the counts), motion_table_format
// (the motion section), byte_codec (the encodings and the CRC), durable_file (the atomic write).
//
// Four format versions are read. Version 1 holds the paper's counts only; a table without a
// motion table is still saved as version 1, byte for byte as before motion tables existed.
// Version 3 is version 1 with 3 in its version field and the motion section between the counts
// and the file checksum; version 4 is version 3 with the opponent's kick-offs at the end of the
// motion section. Version 5, the one a motion table is saved as, is version 4 with the rows and
// the calibration instances in a compact form (varints), and rows at any level of the back-off
// (a pruned table: motion_table_pruning.hpp); versions 3 and 4 load as they are and are saved
// as version 5. Version 2 had the same layout, but its motion rows are keyed by the
// features before the zones and the team's phase (a context of the standing time alone): read
// as version 3 they would mean something else, so a version-2 file is refused and must be
// trained again (table_file_retired_motion_version).
//
// Layout, all integers little-endian, doubles as their IEEE-754 bits in a little-endian u64:
//
//   offset size  field
//        0    8  magic "SSLFTABL"
//        8    4  u32 format version: 1 (table_file_version), 3 (table_file_motion_version) or
//                4 (table_file_set_play_version) or 5 (table_file_compact_motion_version)
//       12    4  u32 grid length L (cells along x)
//       16    4  u32 grid width W (cells along y)
//       20    4  u32 encoding: 0 dense, 1 sparse
//       24    8  f64 field length in mm
//       32    8  f64 field width in mm
//       40    8  f64 step in s
//       48    8  u64 formations sampled while training
//       56    8  u64 transitions: the sum of all counts
//       64    8  u64 rows: dense S; sparse the number of row records
//       72    8  u64 entries: dense S*S; sparse the number of (to, count) pairs
//       80    4  u32 CRC-32 of bytes 0..79 (the header checksum)
//       84       counts:
//                  dense:  S*S u32 counts, row-major (FROM by row, TO by column)
//                  sparse: `rows` records in increasing FROM order, each
//                          u32 from, u32 n (>= 1), then n pairs u32 to, u32 count (> 0)
//                          in increasing TO order
//        M       versions 3 and 4, the motion section (M = 84 + the counts' size):
//                  MotionConfig: f64 step_s (equal to the header's step), u32 horizons,
//                                f64 velocity_window_s, f64 tolerance_s,
//                                f64 calibration_block_s, u32 calibration_one_in,
//                                u32 calibration_capacity, f64 settle_window_s,
//                                f64 long_settle_window_s, f64 learn_interval_s (68 bytes)
//                  u64 instances (the sum of the rows' n)
//                  u64 held-out instances seen (>= the calibration instances stored)
//                  u64 row count, then the rows in increasing key order, each
//                    u64 MotionKey (a finest, robot-level key of a horizon < horizons),
//                    then MotionRow::size (34) i64 sums in MotionRow::sums order: n (>= 1),
//                    d_x, d_y, each regressor's x and y (2 x motion_regressors), dd (>= 0),
//                    each d.x_i, then x_i.x_j for i <= j (x_i.x_i >= 0)         (280 bytes)
//                  per horizon 0..horizons-1: u32 count (<= calibration_capacity), then
//                    `count` HeldOutInstances in MotionTable::calibration's order (by hash,
//                    then content): u64 hash, u32 robot_id, the 14 i32 of
//                    motion_instance_values (x, y, d_x, d_y, v_x, v_y, a_x, a_y, g_x, g_y,
//                    s_x, s_y, t_x, t_y), u32 context                          (72 bytes)
//                  version 4 only: u32 kick-off count (<= SetPlayMemory::max_episodes), then
//                    the kick-offs in SetPlayMemory's order, each u32 snapshot count (1 to
//                    max_snapshots_per_episode), then the snapshots, each i32 offset_ms (0 for
//                    the first, then increasing), i32 since_command_ms (>= 0), u32 stage
//                    (SetPlayStage), u32 robots seen (a bit per id 0-15), then 16 x (i32 x,
//                    i32 y) normalised mm                                      (144 bytes)
//        M       version 5, the compact motion section: the same configuration, instances,
//                held-out instances seen and row count, then
//                  u64 length in bytes of the rows, then the rows in increasing key order,
//                    each the key's distance from the previous row's key (the first row's from
//                    0; at least 1 after it) as a varint, then the 34 sums as zigzag varints;
//                    a key of any level (MotionKey, canonical: encode(decode(key)) == key)
//                  u64 length in bytes of the calibration samples, then per horizon: varint
//                    count, then the instances, each u64 hash, varint robot_id, the 14 values
//                    as zigzag varints, varint context
//                  the kick-offs as in version 4 (a count of 0 when there are none)
//                A varint is LEB128: 7 bits a byte, least significant first, the high bit set
//                on all but the last byte; zigzag maps 0, -1, 1, -2... to 0, 1, 2, 3...
//      end-4   4  u32 CRC-32 of every byte before it (the file checksum)
//
// The header has its own checksum so that the size fields can be trusted before the file
// length is compared with them: that is what tells a truncated file (shorter than its trusted
// header says) from a corrupt one (a flipped byte anywhere, including in a size field). The
// motion section's sizes have no checksum of their own: a file that ends inside the motion
// section is truncated, and so reads a corrupt motion size that points past the end of a file
// whose checksum does not match; one that points short of the end is corrupt (trailing bytes).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/result.hpp"
#include "ssl_formation/files/team_file_name.hpp"  // team_table_file_name, kept here for callers
#include "ssl_formation/model_api/stored_table.hpp"
#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace models {

// The version of a file without a motion table (the paper's counts only).
inline constexpr std::uint32_t table_file_version = 1;
// The version of a file with a motion table, fixed-width (read, no longer written).
inline constexpr std::uint32_t table_file_motion_version = 3;
// The version of a file whose motion table remembers the opponent's kick-offs (SetPlayMemory);
// read, no longer written (a motion table is saved as version 5).
inline constexpr std::uint32_t table_file_set_play_version = 4;
// The version of a motion table saved compactly, with rows at any level: what a motion table is
// saved as.
inline constexpr std::uint32_t table_file_compact_motion_version = 5;
// The version of motion tables keyed by the earlier features, refused with a reason.
inline constexpr std::uint32_t table_file_retired_motion_version = 2;

enum class TableFileError {
  cannot_open,    // missing, unreadable or not a regular file
  not_a_table,    // bad magic
  wrong_version,  // a format version this build cannot read
  wrong_grid,     // a valid table of another grid than the caller expects
  truncated,      // shorter than its (checksum-verified) header says
  corrupt,        // checksum mismatch, trailing bytes or inconsistent content
  io_error,       // a read failed
};

std::string_view to_string(TableFileError error);

// Why a table did not load: the kind, for callers that treat them differently (the trainer
// explains wrong_grid), and a message that names the path and the problem.
struct TableLoadError {
  TableFileError kind = TableFileError::io_error;
  std::string message;
};

// Reads a table file (version 1, 3, 4 or 5; a retired version 2 is refused) without ever writing to
// it. The checks run in this order, and the first that fails decides the error: open; magic
// (not_a_table, or truncated for a file that is a strict prefix of the magic, including an
// empty file); version (wrong_version, checked before any checksum because another version may
// lay out or checksum its header differently); header length and header checksum (truncated,
// corrupt); header fields (corrupt); expected_grid (wrong_grid, naming both grids); file length
// against the header and, for versions 3 to 5, the motion section's sizes (truncated if shorter,
// corrupt if longer); file checksum (corrupt); then every count and the motion section
// (corrupt). A version-1 file loads with `motion` empty.
// `storage` chooses the in-memory layout of the loaded table; `automatic` keeps large grids
// sparse, so loading a sparse 12x9 file never allocates S*S.
Result<StoredTable, TableLoadError> load_table(const std::filesystem::path& path,
                                               std::optional<Grid> expected_grid = std::nullopt,
                                               TableStorage storage = TableStorage::automatic);

// A save that happened. The new file is in place either way; `durable` is false when the folder
// could not be synced after the rename, so a crash (of the machine, not the program) before the
// kernel writes the folder back may still bring the old file back. `warning` then says so.
struct TableSaved {
  bool durable = true;
  std::string warning;  // empty when durable
};

// Test hooks into save_table.
struct SaveHooks {
  // Called once the temporary file is written, fsynced and closed, before it is renamed over
  // the target. Returning false aborts the save as a crash at that moment would, except that
  // the temporary file is removed.
  std::function<bool()> before_rename;
  // Replaces the fsync of the folder after the rename: gets the folder's descriptor and returns
  // 0 or an errno value, as a failing disk or file system would.
  std::function<int(int folder_fd)> sync_folder;
};

// Writes the table to a temporary file in the same folder (`path` + ".tmp-<pid>-<n>"), fsyncs
// it, renames it over `path` and fsyncs the folder, so that a reader or a crash at any moment
// sees either the old file or the new one, never part of one. On failure (the error names the
// path and the cause) the temporary file is removed and `path` is left as it was. Once the
// rename has succeeded the save succeeds: a folder that cannot be synced then is reported in
// TableSaved::warning, not as a failure. Dense tables are written densely, sparse ones as rows.
// Without a motion table the file is version 1.
Result<TableSaved> save_table(const std::filesystem::path& path, const TransitionTable& table,
                              const TableMetadata& metadata, const SaveHooks& hooks = {});
// The same with the motion model's table: a version-5 file. Fails (writing nothing) if the
// motion table's step differs from metadata.step_s.
Result<TableSaved> save_table(const std::filesystem::path& path, const TransitionTable& table,
                              const TableMetadata& metadata, const MotionTable& motion,
                              const SaveHooks& hooks = {});
// `stored` as it is: version 5 if it has a motion table, else version 1.
Result<TableSaved> save_table(const std::filesystem::path& path, const StoredTable& stored,
                              const SaveHooks& hooks = {});

}  // namespace models
}  // namespace ssl_formation
