// ssl-trainer merge: tables of the same grid and step added up, saved atomically.

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "ssl_formation/table_file.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

void merge_tables(const std::vector<std::string>& inputs, const std::filesystem::path& output) {
  if (inputs.empty()) throw app::UsageError("merge needs at least one input table");
  TableLoadResult first = load_table(inputs.front());
  if (!first) throw std::runtime_error(first.message);
  StoredTable merged = std::move(*first.stored);
  for (std::size_t i = 1; i < inputs.size(); ++i) {
    TableLoadResult next = load_table(inputs[i], merged.table.grid());
    if (!next) {
      throw std::runtime_error(
          next.message +
          (next.error == TableFileError::wrong_grid
               ? " (the grid of " + inputs.front() + "): tables of different grids cannot be merged"
               : std::string()));
    }
    if (next.stored->metadata.step_s != merged.metadata.step_s) {
      throw std::runtime_error(fmt::format(
          "{} was trained with a step of {} s, {} with {} s: their transitions cannot be added up",
          inputs[i], next.stored->metadata.step_s, inputs.front(), merged.metadata.step_s));
    }
    merged.table.merge(next.stored->table);
    merged.metadata.samples += next.stored->metadata.samples;
  }
  const TableSaveResult saved = save_table(output, merged.table, merged.metadata);
  if (!saved) throw std::runtime_error(saved.message);
  spdlog::info("merged {} tables into {}: grid {}, {} transitions from {} formations",
               inputs.size(), output.string(), merged.table.grid().to_string(),
               merged.table.transitions(), merged.metadata.samples);
}

}  // namespace ssl_formation::trainer
