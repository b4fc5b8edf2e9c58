#pragma once
// Keeping a table file within a size: the motion table pruned (motion_table_pruning.hpp) until
// the file it makes fits. What every program that saves a trained table (ssl-trainer, its merge
// and scouting, ssl-evaluate's training) calls before save_table, with --max-table-mb.

#include <cstdint>

#include "ssl_formation/base/result.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_table_pruning.hpp"

namespace ssl_formation {
inline namespace models {

// A season of one opponent fits in a few megabytes once the rows that add nothing are folded
// (docs/benchmarks.md, the scale benchmark); the budget bounds what is left.
inline constexpr double default_max_table_mb = 4.0;

struct TableBudget {
  std::uint64_t max_bytes = static_cast<std::uint64_t>(default_max_table_mb * 1e6);
  MotionPruning pruning;
  // The estimates the pruning judges rows by: the model's defaults.
  MotionModelSettings settings;
};

// A budget of `megabytes` (0: no bound, the rows that add nothing are still folded).
TableBudget table_budget_mb(double megabytes);

struct BudgetFit {
  MotionPruned pruned;
  std::uint64_t file_bytes = 0;  // the size of the file it makes with the counts
  // False when even the motion table without a robot's or a zone's row does not fit (its
  // calibration sample, the kick-offs and the paper's counts are never cut).
  bool within_budget = true;
};

// `motion` pruned so that the file of `counts`, `metadata` and it stays within the budget; the
// error if the motion table cannot be saved at all (save_table's checks).
Result<BudgetFit> fit_table_to_budget(const TransitionTable& counts, const TableMetadata& metadata,
                                      const MotionTable& motion, const TableBudget& budget);

}  // namespace models
}  // namespace ssl_formation
