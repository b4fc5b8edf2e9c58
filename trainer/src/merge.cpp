// ssl-trainer merge: tables of the same grid and step added up, saved atomically.

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "ssl_formation/table_file.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

void merge_tables(const std::vector<std::string>& inputs, const std::filesystem::path& output) {
  if (inputs.empty()) throw app::UsageError("merge needs at least one input table");
  auto first = load_table(inputs.front());
  if (!first) throw std::runtime_error(first.error().message);
  StoredTable merged = std::move(*first);
  for (std::size_t i = 1; i < inputs.size(); ++i) {
    auto next = load_table(inputs[i], merged.table.grid());
    if (!next) {
      throw std::runtime_error(
          next.error().message +
          (next.error().kind == TableFileError::wrong_grid
               ? " (the grid of " + inputs.front() + "): tables of different grids cannot be merged"
               : std::string()));
    }
    if (next->metadata.step_s != merged.metadata.step_s) {
      throw std::runtime_error(fmt::format(
          "{} was trained with a step of {} s, {} with {} s: their transitions cannot be added up",
          inputs[i], next->metadata.step_s, inputs.front(), merged.metadata.step_s));
    }
    merged.table.merge(next->table);
    merged.metadata.samples += next->metadata.samples;
  }
  const auto saved = save_table(output, merged.table, merged.metadata);
  if (!saved) throw std::runtime_error(saved.error().message);
  if (!saved->durable) spdlog::warn("{}", saved->warning);
  spdlog::info("merged {} tables into {}: grid {}, {} transitions from {} formations",
               inputs.size(), output.string(), merged.table.grid().to_string(),
               merged.table.transitions(), merged.metadata.samples);
}

}  // namespace ssl_formation::trainer
