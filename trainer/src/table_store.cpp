#include "ssl_formation/trainer/table_store.hpp"

#include <signal.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <stdexcept>
#include <string>

namespace ssl_formation::trainer {

namespace {
// save_table writes "<table>.tmp-<pid>-<n>" and renames it; a trainer killed in between (power
// cut, SIGKILL) leaves that file behind. Removes those of processes that no longer exist.
void remove_stale_temporaries(const std::filesystem::path& table_path) {
  std::error_code error;
  const std::filesystem::path folder =
      table_path.has_parent_path() ? table_path.parent_path() : std::filesystem::path(".");
  const std::string prefix = table_path.filename().string() + ".tmp-";
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    long pid = 0;
    const char* begin = name.data() + prefix.size();
    const auto [end, parsed] = std::from_chars(begin, name.data() + name.size(), pid);
    if (parsed != std::errc() || end == begin || *end != '-' || pid <= 0) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // still alive
    std::error_code ignored;
    if (std::filesystem::remove(entry.path(), ignored)) {
      spdlog::info("removed {}, left by an earlier trainer (process {}) that stopped mid-save",
                   entry.path().string(), pid);
    }
  }
}

std::string describe_motion(const MotionConfig& config) {
  return fmt::format(
      "horizons={} step={} velocity_window={} learn_interval={} settle_window={} "
      "long_settle_window={} tolerance={} calibration_block={} calibration_one_in={} "
      "calibration_capacity={}",
      config.horizons, config.step_s, config.velocity_window_s, config.learn_interval_s,
      config.settle_window_s, config.long_settle_window_s, config.tolerance_s,
      config.calibration_block_s, config.calibration_one_in, config.calibration_capacity);
}
}  // namespace

std::unique_ptr<Training> open_training(const std::filesystem::path& table_path,
                                        const SamplerConfig& config, bool reset,
                                        const std::optional<MotionConfig>& motion,
                                        const std::optional<MatchRules>& rules,
                                        bool tracked_vision) {
  TrainingConfig training;
  training.sampler = config;
  training.rules = rules;
  training.tracked_vision = tracked_vision;
  remove_stale_temporaries(table_path);
  std::error_code ignored;
  if (reset || !std::filesystem::exists(table_path, ignored)) {
    const std::string what =
        config.grid.to_string() + (motion ? " table with the motion model" : " table");
    if (reset && std::filesystem::exists(table_path, ignored))
      spdlog::info("starting an empty {}; {} will be replaced at the first save", what,
                   table_path.string());
    else if (!reset)
      spdlog::info("no table at {} yet: starting an empty {}", table_path.string(), what);
    ResumedLearner empty = empty_table_learner(config.grid, motion);
    return std::make_unique<Training>(training, empty.kind, std::move(empty.learner));
  }
  auto loaded = load_table(table_path, config.grid);
  if (!loaded) {
    throw std::runtime_error(loaded.error().message +
                             "; the file is left as it is: give another --table, or --reset to "
                             "replace it with an empty table");
  }
  StoredTable& stored = *loaded;
  if (motion && !stored.motion) {
    throw std::runtime_error(fmt::format(
        "{} holds only the paper's counts (a version-1 table), not the motion model's: pass "
        "--model paper to go on training it, or give a new --table (or --reset to replace it) "
        "for --model motion",
        table_path.string()));
  }
  if (!motion && stored.motion) {
    throw std::runtime_error(fmt::format(
        "{} also holds the motion model's table (a version-3 table), which --model paper would "
        "drop: pass --model motion to go on training it, or give a new --table (or --reset to "
        "replace it) for --model paper",
        table_path.string()));
  }
  // The model first: a table of the other model also has the other model's default step.
  if (stored.metadata.step_s != config.step_s) {
    throw std::runtime_error(fmt::format(
        "{} was trained with --step {}, not {}: its transitions mean another time scale; use the "
        "same --step, another --table, or --reset",
        table_path.string(), stored.metadata.step_s, config.step_s));
  }
  if (motion && !(stored.motion->config() == *motion)) {
    const MotionConfig& saved = stored.motion->config();
    throw std::runtime_error(
        saved.horizons != motion->horizons
            ? fmt::format("{} was trained with --horizons {:g} ({} steps), not {:g}: use the "
                          "same --horizons, another --table, or --reset",
                          table_path.string(), saved.horizons * saved.step_s, saved.horizons,
                          motion->horizons * motion->step_s)
            : fmt::format("{} was trained with other motion model settings ({}) than this "
                          "program's ({}): give another --table, or --reset",
                          table_path.string(), describe_motion(saved), describe_motion(*motion)));
  }
  if (stored.format_version != table_file_version &&
      stored.format_version != table_file_compact_motion_version) {
    spdlog::info(
        "{} is a version-{} table: it is read as it is and will be saved as version {} "
        "(compact, its rows that add nothing folded into coarser ones)",
        table_path.string(), stored.format_version, table_file_compact_motion_version);
  }
  if (stored.motion) {
    spdlog::info(
        "resumed {}: grid {}, {} transitions, {} formations, {} states seen; motion model: {} "
        "horizons, {} instances, {} held out",
        table_path.string(), stored.table.grid().to_string(), stored.table.transitions(),
        stored.metadata.samples, stored.table.rows_seen(), stored.motion->config().horizons,
        stored.motion->instances(), stored.motion->held_out());
  } else {
    spdlog::info("resumed {}: grid {}, {} transitions, {} formations, {} states seen",
                 table_path.string(), stored.table.grid().to_string(), stored.table.transitions(),
                 stored.metadata.samples, stored.table.rows_seen());
  }
  ResumedLearner resumed = resume_learner(std::move(stored));
  return std::make_unique<Training>(training, resumed.kind, std::move(resumed.learner),
                                    stored.metadata.samples);
}

namespace {
TableMetadata metadata_of(const Training& training) {
  TableMetadata metadata;
  metadata.field = training.sampler().field();
  metadata.step_s = training.sampler().config().step_s;
  metadata.samples = training.samples();
  return metadata;
}
}  // namespace

TableSnapshot snapshot_training(const Training& training) {
  return training.stored_table(metadata_of(training));
}

std::optional<TableSaveReport> save_training(const std::filesystem::path& table_path,
                                             Training& training, const TableBudget& budget) {
  const auto report = save_snapshot(table_path, snapshot_training(training), budget);
  if (report) training.mark_saved();
  return report;
}

std::optional<TableSaveReport> save_snapshot(const std::filesystem::path& table_path,
                                             const TableSnapshot& snapshot,
                                             const TableBudget& budget, const SaveHooks& hooks) {
  const TableMetadata& metadata = snapshot.metadata;
  TableSaveReport report;
  Result<TableSaved> saved = fail("nothing saved");
  if (snapshot.motion) {
    auto fit = fit_table_to_budget(snapshot.table, metadata, *snapshot.motion, budget);
    if (!fit) {
      spdlog::error("cannot save table {}: {}", table_path.string(), fit.error().message);
      return std::nullopt;
    }
    if (!fit->within_budget) {
      // Said once: every later save would say it again.
      static std::atomic<bool> said{false};
      if (!said.exchange(true)) {
        spdlog::warn(
            "{} takes {:.2f} MB, over --max-table-mb {:.2f}, with every robot's and "
            "zone's row folded: its calibration sample and the paper's counts alone "
            "take that",
            table_path.string(), static_cast<double>(fit->file_bytes) / 1e6,
            static_cast<double>(budget.max_bytes) / 1e6);
      }
    }
    report = {fit->file_bytes, fit->pruned.rows_after, fit->pruned.folded};
    saved = save_table(table_path, snapshot.table, metadata, fit->pruned.table, hooks);
  } else {
    saved = save_table(table_path, snapshot.table, metadata, hooks);
  }
  if (!saved) {
    spdlog::error("{}", saved.error().message);
    return std::nullopt;
  }
  // The new file is in place; only its survival of a machine crash is in doubt.
  if (!saved->durable) spdlog::warn("{}", saved->warning);
  spdlog::debug("saved {} ({} transitions, {} formations)", table_path.string(),
                snapshot.table.transitions(), metadata.samples);
  return report;
}

}  // namespace ssl_formation::trainer
