#pragma once
// The table the trainer counts into: --table's one file, or with --table-dir one file per
// opponent team, named after it (team_table_file_name). With --table-dir the training runs on
// the current opponent's table; when the referee names another opponent, the old table is saved
// first and the new opponent's file resumed (or started empty).

#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string_view>

#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/trainer/table_saver.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

class OpponentTables {
 public:
  // Opens --table, or --table-dir's table of the opponent the options name (the unnamed team's
  // until a referee names one). Throws std::runtime_error when that file cannot be resumed, and
  // app::UsageError for bad options.
  // With `saver`, the saves while training runs (save_if_changed) are handed to it and made on
  // its thread; without, they are made at once.
  explicit OpponentTables(const TrainerOptions& options, TableSaver* saver = nullptr);

  Training& training() { return *training_; }
  const Training& training() const { return *training_; }
  // The current table's file.
  const std::filesystem::path& path() const { return path_; }
  bool per_opponent() const { return !options_.table_dir.empty(); }

  // One of the match's events, handed to the training. With --table-dir, when a referee message
  // names another opponent, the old table is saved and the new opponent's resumed, which then
  // takes the message too. A file that cannot be resumed is reported, and that opponent is
  // trained into an empty table that is not saved (the file is left as it is).
  RefereeChange handle(const MatchEvent& event);

  // Saves the current table if it counted anything since it was opened or last saved (an
  // opponent only seen for a moment leaves no empty file behind). False if the save failed.
  bool save_if_changed();
  // At exit: --table's file is written in any case (a supervisor finds the table there even
  // after a run that saw nothing); under --table-dir, as save_if_changed().
  bool save_at_exit();

 private:
  std::unique_ptr<Training> open(const std::filesystem::path& path);

  const TrainerOptions& options_;
  TableSaver* saver_;
  SamplerConfig config_;
  std::optional<MotionConfig> motion_;
  MatchRules rules_;
  bool tracked_vision_;
  std::filesystem::path path_;
  std::unique_ptr<Training> training_;
  bool saving_ = true;  // false for a table whose file could not be resumed
  // Tables opened in this run: --reset empties each only the first time (an opponent met again
  // later in the run keeps what it was taught earlier).
  std::set<std::filesystem::path> opened_;
};

}  // namespace ssl_formation::trainer
