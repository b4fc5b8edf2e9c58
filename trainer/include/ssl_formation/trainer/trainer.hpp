#pragma once
// ssl-trainer's three modes: live training from the vision feed, offline training from log
// files, and merging tables. main.cpp wires them up; everything else (options included) is
// here, linkable by the tests. All three count through the core's Training and save through
// table_store.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/files/table_lock.hpp"
#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/pipeline/training.hpp"

namespace ssl_formation::trainer {

struct TrainerOptions {
  app::ModelOptions model;
  app::NetworkOptions network;
  app::DaemonOptions daemon;
  // --model motion: how far ahead the motion model learns, in seconds (--horizons), and the
  // steps that makes once the step is known (settle_trainer_options).
  std::string horizons = "auto";
  int horizon = 3;
  // --horizon N, the old spelling in steps; app::not_given without it.
  int old_horizon_steps = app::not_given;
  // --from-log -o FILE: the table to write, from nothing, in place of --table.
  app::OutputOptions output;
  std::string learn_during = "all";
  std::string table = app::default_table;
  // One table file per opponent team in this folder instead of --table (live training).
  std::string table_dir;
  double flush_interval_s = 10.0;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = net::kDefaultReceiveBufferBytes;
  bool reset = false;
  bool verbose = false;
  std::vector<std::string> from_logs;
  // --from-log: logs trained at once (0: one per core).
  int jobs = 0;
  // --from-log: a log whose last record is cut off (a recorder killed mid-write) is used up to
  // it with a warning; with strict, that also makes the exit status 1.
  bool strict = false;
  // The largest table file to save, MB (0: no bound); see table_budget.hpp.
  double max_table_mb = default_max_table_mb;
};

// Parses ssl-trainer's command line (not merge's) into `options`. Returns false when --help was
// printed and the program should exit 0; throws app::UsageError for anything wrong.
bool parse_trainer_options(int argc, const char* const argv[], TrainerOptions& options);
// What the options leave open once parsed: -o in place of --table, the grid, step and model
// from an existing --table, and the steps --horizons makes at that step. Throws app::UsageError.
void settle_trainer_options(TrainerOptions& options);

// The motion model's configuration the options ask for: none with --model paper. Throws
// app::UsageError for a bad --model or --horizon, or a model that keeps no table (a baseline).
std::optional<MotionConfig> motion_config(const TrainerOptions& options);
// A table file must be writable where it is asked for: a trainer that only finds out at its
// first save has lost the match (or the logs' work) by then. Throws app::UsageError when
// --table's folder does not exist.
void check_table_option(const TrainerOptions& options);

// The one-writer lock on --table, or on --table-dir (created if missing) for all its tables:
// held by run_live and run_offline for their whole run. Throws TableLockError naming the other
// writer.
TableWriterLock lock_tables(const TrainerOptions& options);
// How the training follows the referee, by --opponent-color, --opponent-attacks, --our-team,
// --opponent-team and --learn-during. Throws app::UsageError.
MatchRules match_rules(const TrainerOptions& options);

// Each returns the exit status. Throws app::UsageError for bad options and std::runtime_error
// when the table cannot be resumed.
int run_live(const TrainerOptions& options);     // live_trainer.cpp
int run_offline(const TrainerOptions& options);  // offline_training.cpp

// Adds up tables of the same grid and step into `output` (atomically), within `max_table_mb`:
// the paper's counts and, when every input has one, the motion tables. Throws
// std::runtime_error naming the file and the reason when one cannot be read or added, including
// a mix of version-1 and version-3 files or motion tables of other settings.
void merge_tables(const std::vector<std::string>& inputs, const std::filesystem::path& output,
                  double max_table_mb = default_max_table_mb);

}  // namespace ssl_formation::trainer
