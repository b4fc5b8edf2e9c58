// ssl-trainer's options (the merge subcommand parses its own in main.cpp).

#include <string>

#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

namespace po = boost::program_options;

bool parse_trainer_options(int argc, const char* const argv[], TrainerOptions& o) {
  po::options_description general("Options");
  // clang-format off
  general.add_options()
      ("table", po::value(&o.table)->default_value(o.table),
       "table file to resume and save (written atomically)")
      ("table-dir", po::value(&o.table_dir)->value_name("DIR"),
       "instead of --table: one table file per opponent team in DIR, named after the team as the "
       "referee names it (unknown.bin for an unnamed one); the trainer switches tables when the "
       "referee names another opponent, saving the old one first")
      ("reset", po::bool_switch(&o.reset),
       "start an empty table even if --table holds one of another grid, step, model or "
       "motion-model settings (an older version's)")
      ("flush-interval", po::value(&o.flush_interval_s)->default_value(o.flush_interval_s),
       "seconds between saves of the table (it is also saved on SIGINT/SIGTERM)")
      ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
       "seconds between status lines on stderr")
      ("receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
       "socket receive buffer (SO_RCVBUF) to request, bytes")
      ("verbose", po::bool_switch(&o.verbose), "log every save")
      ("from-log", po::value(&o.from_logs)->multitoken(),
       "train from these official SSL log files (.log or .log.gz) instead of the network, "
       "save the table and exit. With --opponent-team NAME only that team is learned, found by "
       "the referee's names in each log (logs where it does not play are skipped); with "
       "--opponent-team all and --table-dir, every named team into its own table")
      ("jobs", po::value(&o.jobs)->default_value(o.jobs, "0 (every core)"),
       "--from-log: logs trained at once, each in its own thread; their tables are added up in "
       "the order the files are given, the same as training them one after the other")
      ("strict", po::bool_switch(&o.strict),
       "--from-log: exit 1 also when a log only ends inside its last message (by default that "
       "is a warning: a recorder killed mid-write leaves such files)");
  // clang-format on
  app::add_horizons_option(general, o.horizons,
                           "--model motion: how far ahead to learn (up to 16 steps); auto: 3 "
                           "steps, 1.5 s at the default --step (ssl-predictor extrapolates "
                           "beyond)");
  app::add_output_options(general, o.output,
                          "--from-log: the table file to write, trained from nothing (in place "
                          "of --table, which resumes a table)");
  app::add_vision_options(general, o.network);
  app::add_model_options(general, o.model);
  app::add_learn_during_option(general, o.learn_during);
  app::add_max_table_option(general, o.max_table_mb);
  app::add_daemon_options(general, o.daemon);
  app::OldSpellings old;
  old.add("horizon", "--horizons", po::value(&o.old_horizon_steps),
          "in seconds: --horizon 3 at a 0.5 s step is --horizons 1.5");
  return app::parse_command_line(
      argc, argv, general,
      "ssl-trainer [options]\n       ssl-trainer --from-log FILE... [-o TABLE] [options]\n"
      "       ssl-trainer merge TABLE... -o OUT",
      "Counts the opponent's formation transitions (and, with --model motion, how each robot "
      "moves) from the vision feed (or from logs) into a table file.",
      nullptr, &old);
}

void settle_trainer_options(TrainerOptions& o) {
  if (!o.output.path.empty()) {
    if (o.from_logs.empty()) {
      throw app::UsageError("-o/--output is for --from-log; live, the table is --table");
    }
    if (!o.table_dir.empty()) throw app::UsageError("give -o/--output or --table-dir, not both");
    if (o.output.path == "-") throw app::UsageError("-o/--output: a table is a file, not -");
    app::check_output_free(o.output);
    o.table = o.output.path;
    o.reset = true;  // from nothing: what the file held is replaced once the training succeeds
  } else if (o.table_dir.empty()) {
    app::take_table_settings(o.model, o.table);
  }
  if (o.old_horizon_steps != app::not_given && o.horizons != "auto") {
    throw app::UsageError("give --horizons or its old spelling --horizon, not both");
  }
  const int auto_steps = o.old_horizon_steps != app::not_given ? o.old_horizon_steps : 3;
  // The paper's model learns no horizons: a step it does not use cannot be refused.
  if (!describe(o.model.parsed_model()).keeps_motion_rows) return;
  o.horizon = app::horizon_steps(o.horizons, o.model.step(), auto_steps);
}

std::optional<MotionConfig> motion_config(const TrainerOptions& options) {
  const ModelDescription& model = describe(options.model.parsed_model());
  if (!model.keeps_table) {
    throw app::UsageError("--model " + std::string(model.name) +
                          " keeps no table: there is nothing to train (ssl-predictor runs it "
                          "without one, ssl-evaluate compares it)");
  }
  if (!model.keeps_motion_rows) return std::nullopt;
  if (options.horizon < 1 || options.horizon > MotionConfig::max_horizons) {
    throw app::UsageError("--horizons must be 1 to " + std::to_string(MotionConfig::max_horizons) +
                          " steps, not " + std::to_string(options.horizon));
  }
  MotionConfig config;
  config.step_s = options.model.step();
  config.horizons = options.horizon;
  if (!config.valid()) throw app::UsageError("invalid --step for the motion model");
  return config;
}

void check_table_option(const TrainerOptions& options) {
  if (!options.table_dir.empty()) return;  // created where it is missing
  const std::filesystem::path table(options.table);
  const std::filesystem::path folder = table.has_parent_path() ? table.parent_path() : ".";
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) {
    throw app::UsageError("--table " + options.table + ": the folder " + folder.string() +
                          " does not exist; create it or give another --table");
  }
}

TableWriterLock lock_tables(const TrainerOptions& options) {
  if (options.table_dir.empty()) {
    return TableWriterLock(TableWriterLock::lock_path_for_table(options.table),
                           "the table " + options.table);
  }
  std::error_code error;
  std::filesystem::create_directories(options.table_dir, error);
  if (error) {
    throw std::runtime_error("--table-dir " + options.table_dir +
                             ": cannot create it: " + error.message());
  }
  return TableWriterLock(TableWriterLock::lock_path_for_folder(options.table_dir),
                         "the table folder " + options.table_dir);
}

MatchRules match_rules(const TrainerOptions& options) {
  return MatchRules{options.model.opponent_choice(),
                    app::parsed_learn_during(options.learn_during)};
}

}  // namespace ssl_formation::trainer
