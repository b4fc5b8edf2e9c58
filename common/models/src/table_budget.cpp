#include "ssl_formation/models/table_budget.hpp"

#include <algorithm>
#include <cmath>

#include "ssl_formation/motion_model/motion_table_format.hpp"
#include "table_format.hpp"

namespace ssl_formation {
inline namespace models {

using namespace detail;
using namespace files::detail;
using namespace motion_model::detail;

TableBudget table_budget_mb(double megabytes) {
  TableBudget budget;
  budget.max_bytes =
      megabytes > 0.0 ? static_cast<std::uint64_t>(std::llround(megabytes * 1e6)) : 0;
  return budget;
}

Result<BudgetFit> fit_table_to_budget(const TransitionTable& counts, const TableMetadata& metadata,
                                      const MotionTable& motion, const TableBudget& budget) {
  const std::uint64_t fixed =
      header_size + counts_size(header_for(counts, metadata, table_file_compact_motion_version)) +
      checksum_size;
  std::uint64_t row_bytes = 0;  // of the last fit's rows
  const MotionPruner pruner(motion, budget.settings);
  const auto fit = [&](std::size_t max_rows) -> Result<BudgetFit> {
    MotionPruning pruning = budget.pruning;
    pruning.max_rows = max_rows;
    BudgetFit result{pruner.prune(pruning), 0, true};
    const auto encoded = encode_motion_section(result.pruned.table, metadata.step_s);
    if (!encoded) return Unexpected(encoded.error());
    result.file_bytes = fixed + motion_section_size(result.pruned.table, *encoded);
    row_bytes = encoded->row_bytes.size();
    return result;
  };
  auto result = fit(0);
  if (!result || budget.max_bytes == 0) return result;
  // Over the budget: as many rows as the bytes left hold at the rows' mean size, a little under
  // so that the second try mostly fits; a few more tries if the rows kept are larger.
  for (int attempt = 0; attempt < 6 && result->file_bytes > budget.max_bytes; ++attempt) {
    const std::size_t rows = result->pruned.rows_after;
    if (rows <= 1) break;
    const double over = static_cast<double>(result->file_bytes - budget.max_bytes);
    const double bytes_per_row = static_cast<double>(row_bytes) / static_cast<double>(rows);
    const double cut = std::max(1.0, std::ceil(over / bytes_per_row * 1.02));
    const std::size_t max_rows =
        cut >= static_cast<double>(rows) ? 1 : rows - static_cast<std::size_t>(cut);
    // The try that did not fit is let go first: a season's table is tens of megabytes.
    result->pruned.table = MotionTable(motion.config());
    result = fit(max_rows);
    if (!result) return result;
  }
  result->within_budget = result->file_bytes <= budget.max_bytes;
  return result;
}

}  // namespace models
}  // namespace ssl_formation
