// ssl-trainer merge: tables of the same grid, step and model added up, saved atomically. The
// paper's counts add up entry by entry; the motion tables add up key by key (pruned tables too:
// a folded row is already at its parent's key) and are pruned again to the budget.

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "ssl_formation/files/table_lock.hpp"
#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

namespace {
std::string describe_version(const StoredTable& table) {
  return table.motion ? "a version-" + std::to_string(table.format_version) +
                            " table (the paper's counts and the motion model's)"
                      : "a version-1 table (the paper's counts only)";
}
}  // namespace

void merge_tables(const std::vector<std::string>& inputs, const std::filesystem::path& output,
                  double max_table_mb) {
  if (inputs.empty()) throw app::UsageError("merge needs at least one input table");
  auto first = load_table(inputs.front());
  if (!first) throw std::runtime_error(first.error().message);
  StoredTable merged = std::move(*first);
  // The sum of the motion sections is a table of its own (a loaded section is shared read-only).
  const std::shared_ptr<MotionTable> motion_sum =
      merged.motion ? std::make_shared<MotionTable>(*merged.motion) : nullptr;
  merged.motion = motion_sum;
  for (std::size_t i = 1; i < inputs.size(); ++i) {
    auto next = load_table(inputs[i], merged.table.grid());
    if (!next) {
      throw std::runtime_error(
          next.error().message +
          (next.error().kind == TableFileError::wrong_grid
               ? " (the grid of " + inputs.front() + "): tables of different grids cannot be merged"
               : std::string()));
    }
    if ((next->motion != nullptr) != (merged.motion != nullptr)) {
      throw std::runtime_error(fmt::format(
          "{} is {}, {} is {}: tables of the two models cannot be merged (train them with the "
          "same --model)",
          inputs[i], describe_version(*next), inputs.front(), describe_version(merged)));
    }
    // The model first: tables of the two models usually differ in step too.
    if (next->metadata.step_s != merged.metadata.step_s) {
      throw std::runtime_error(fmt::format(
          "{} was trained with a step of {} s, {} with {} s: their transitions cannot be added up",
          inputs[i], next->metadata.step_s, inputs.front(), merged.metadata.step_s));
    }
    if (merged.motion && !(merged.motion->config() == next->motion->config())) {
      const MotionConfig& a = next->motion->config();
      const MotionConfig& b = merged.motion->config();
      throw std::runtime_error(
          a.horizons != b.horizons
              ? fmt::format("{} learned {} steps ahead (--horizon), {} {}: their motion tables "
                            "cannot be added up",
                            inputs[i], a.horizons, inputs.front(), b.horizons)
              : fmt::format("{} and {} were trained with other motion model settings: their "
                            "motion tables cannot be added up",
                            inputs[i], inputs.front()));
    }
    merged.table.merge(next->table);
    merged.metadata.samples += next->metadata.samples;
    if (motion_sum) motion_sum->merge(*next->motion);
  }
  // No live trainer may be writing the output meanwhile: its next save would undo the merge.
  const TableWriterLock lock(TableWriterLock::lock_path_for_table(output),
                             "the table " + output.string());
  std::size_t rows_saved = 0;
  if (merged.motion) {
    // The sum of pruned tables: its rows are judged again on all their evidence.
    auto fit = fit_table_to_budget(merged.table, merged.metadata, *merged.motion,
                                   table_budget_mb(max_table_mb));
    if (!fit)
      throw std::runtime_error("cannot save " + output.string() + ": " + fit.error().message);
    rows_saved = fit->pruned.rows_after;
    merged.motion = std::make_shared<const MotionTable>(std::move(fit->pruned.table));
  }
  const auto saved = save_table(output, merged);
  if (!saved) throw std::runtime_error(saved.error().message);
  if (!saved->durable) spdlog::warn("{}", saved->warning);
  spdlog::info("merged {} tables into {}: grid {}, {} transitions from {} formations",
               inputs.size(), output.string(), merged.table.grid().to_string(),
               merged.table.transitions(), merged.metadata.samples);
  if (merged.motion) {
    spdlog::info(
        "merged motion model: {} horizons, motion_instances={} motion_held_out={} "
        "motion_rows={}",
        merged.motion->config().horizons, merged.motion->instances(), merged.motion->held_out(),
        rows_saved);
  }
}

}  // namespace ssl_formation::trainer
