#pragma once
// Where the trainer's table comes from and goes to: resume an existing table file (or refuse
// one of another grid, step or model unless --reset), and save it atomically with its metadata.

#include <filesystem>
#include <memory>
#include <optional>

#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation::trainer {

// Opens the training for `table_path`: resumes its counts if the file exists, or starts empty.
// With `motion` (--model motion) the training also counts the motion model's table of that
// configuration, resumed from a version-3 to 5 file; without it (--model paper) only the paper's
// counts, resumed from a version-1 file. Throws std::runtime_error, with the file's own message
// and what to do, when the file cannot be resumed (corrupt, another grid or step, the other
// model's file, other motion settings) and `reset` is false. With `reset` the old file is left
// alone until the first save replaces it. `rules`: how the training follows the referee (see
// Training).
// `tracked_vision`: --vision-source tracked (TrainingConfig).
std::unique_ptr<Training> open_training(const std::filesystem::path& table_path,
                                        const SamplerConfig& config, bool reset,
                                        const std::optional<MotionConfig>& motion = std::nullopt,
                                        const std::optional<MatchRules>& rules = std::nullopt,
                                        bool tracked_vision = false);

// What a save wrote.
struct TableSaveReport {
  std::uint64_t bytes = 0;
  std::size_t motion_rows = 0;    // stored, after pruning
  std::size_t motion_folded = 0;  // robot and zone rows folded into their parents
};

// A training's table copied as it is now, to save while the training goes on.
using TableSnapshot = StoredTable;
// Copies the training's table.
TableSnapshot snapshot_training(const Training& training);
// Saves a snapshot atomically, as save_training does; logs and returns nothing on failure.
std::optional<TableSaveReport> save_snapshot(const std::filesystem::path& table_path,
                                             const TableSnapshot& snapshot,
                                             const TableBudget& budget = {},
                                             const SaveHooks& hooks = {});

// Saves the training's table atomically (version 5 with its motion table, pruned to `budget`;
// else version 1); logs and returns nothing on failure. A save whose folder could not be synced
// after the rename is a success, logged as a warning. The training's own table is left whole:
// what it learns next adds to every row it has.
std::optional<TableSaveReport> save_training(const std::filesystem::path& table_path,
                                             Training& training, const TableBudget& budget = {});

}  // namespace ssl_formation::trainer
