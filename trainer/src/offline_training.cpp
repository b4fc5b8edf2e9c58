// ssl-trainer --from-log: official log files through the same Training the live mode runs, then
// one atomic save per table. Each log is trained apart, on every core at once (a log is its own
// stream: nothing spans two files), and the logs' tables are added up in the order the files
// were given, so the result is the same as training them one after the other. A log that cannot
// be read whole (damaged, or cut off under --strict) fails the run, and a failed run writes no
// table.
//
// Scouting: with --opponent-team NAME (or --our-team) only that team's robots are learned, found
// by the referee's names in each log, through changes of colour and of ends; a log where the team
// does not play is skipped and said so. --opponent-team all learns every named team of every log,
// each into its own table under --table-dir.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "ssl_formation/app/progress.hpp"
#include "ssl_formation/files/log_events.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/trainer/table_store.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

namespace {

// Sets of logs above this size get a progress bar.
constexpr std::uint64_t progress_bar_bytes = 4 << 20;

// What the logs are trained into.
struct Destination {
  bool all_teams = false;  // --opponent-team all
  bool per_team = false;   // --table-dir
  bool tracked = false;    // --vision-source tracked: the logs' tracked vision (type 5) instead
  SamplerConfig config;
  std::optional<MotionConfig> motion;
  MatchRules rules;
};

// One team a log was trained for: its training (fresh tables: the log's counts alone).
struct TeamOfLog {
  std::unique_ptr<Training> training;
  bool found = true;  // false: a named team the referee never named in this log
};

struct LogOutcome {
  std::string file;
  std::string open_error;  // the log could not be opened: nothing else is set
  LogReader::Ending ending = LogReader::Ending::none;
  std::string read_error;
  LogReadCounters counters;
  std::uint64_t frames = 0;
  std::vector<TeamOfLog> teams;
};

// Work shared by the threads: which log is next, and how far they are all, for the bar.
struct Progress {
  std::atomic<std::size_t> next_file{0};
  std::atomic<std::uint64_t> bytes{0};
  std::atomic<std::uint64_t> frames{0};
};

std::unique_ptr<Training> new_training(const Destination& to, const OpponentChoice& opponent) {
  TrainingConfig config;
  config.sampler = to.config;
  config.rules = MatchRules{opponent, to.rules.learn_during};
  config.tracked_vision = to.tracked;
  ResumedLearner empty = empty_table_learner(to.config.grid, to.motion);
  return std::make_unique<Training>(config, empty.kind, std::move(empty.learner));
}

LogOutcome train_log(const std::string& file, const Destination& to, Progress& progress) {
  LogOutcome outcome;
  outcome.file = file;
  Result<LogReader> reader = LogReader::open(file);
  if (!reader) {
    outcome.open_error = reader.error().message;
    return outcome;
  }
  // --opponent-team all: a training per team, made as the referee first names it.
  if (!to.all_teams) outcome.teams.push_back({new_training(to, to.rules.opponent)});
  VisionFrame geometry;   // the last geometry, for the trainings made part-way (all teams)
  RefereeFollower names;  // --opponent-team all: who the referee names, to make their trainings
  LogEvents events(*reader);
  MatchEvent event;
  std::uint64_t reported_offset = 0;
  // What the trainings learn from: the raw vision, or with --vision-source tracked the
  // tracker's frames (the raw vision then gives only the field size).
  const MatchEventKind learned_from =
      to.tracked ? MatchEventKind::tracked_vision : MatchEventKind::vision;
  while (events.next(event)) {
    for (TeamOfLog& team : outcome.teams) team.training->on_event(event);
    if (event.kind == MatchEventKind::referee && to.all_teams) {
      // The names as the log's one followed game controller gives them.
      names.add(event.payload, event.receive_s);
      const RefereeView* view = names.heard() ? &names.view() : nullptr;
      for (const std::string* name :
           {view ? &view->yellow_name : nullptr, view ? &view->blue_name : nullptr}) {
        if (!name || name->empty()) continue;  // an unnamed team could be anyone
        const bool known =
            std::any_of(outcome.teams.begin(), outcome.teams.end(), [&](const TeamOfLog& team) {
              return same_team_name(team.training->match().choice().opponent_team, *name);
            });
        if (known) continue;
        OpponentChoice choice = to.rules.opponent;
        choice.our_team.clear();
        choice.opponent_team = *name;
        TeamOfLog& team = outcome.teams.emplace_back(TeamOfLog{new_training(to, choice)});
        // The field the log's geometry gave so far, and the message that named the team.
        if (geometry.has_geometry) team.training->add(geometry);
        team.training->on_event(event);
      }
    }
    if (event.kind == MatchEventKind::vision && event.frame->has_geometry) {
      geometry.has_geometry = true;
      geometry.field_length = event.frame->field_length;
      geometry.field_width = event.frame->field_width;
    }
    if (event.kind != learned_from) continue;
    if ((++outcome.frames & 4095) == 0) {
      const std::uint64_t offset = reader->compressed_offset();
      progress.bytes += offset - std::min(offset, reported_offset);
      progress.frames += 4096;
      reported_offset = offset;
    }
  }
  progress.bytes +=
      reader->compressed_size() - std::min(reader->compressed_size(), reported_offset);
  progress.frames += outcome.frames & 4095;
  outcome.ending = reader->ending();
  outcome.read_error = reader->error();
  outcome.counters = reader->counters();
  for (TeamOfLog& team : outcome.teams) {
    // A team named in the options that the referee never named: nothing was learned of it.
    team.found = team.training->match().opponent_ever_known();
  }
  return outcome;
}

// "'ER-Force' blue (referee), attacks -x (referee); 1 change of colour, 1 change of ends; 9000
// formations (2000 outside running play), 52000 transitions, 30000 motion instances".
std::string describe_team(const TeamOfLog& team) {
  const Training& t = *team.training;
  const SamplerCounters& c = t.sampler().counters();
  std::string out = describe(t.match().opponent(), t.sampler().attacks());
  out += fmt::format(
      "; {} changes of colour, {} changes of ends; {} formations ({} outside "
      "running play), {} transitions",
      c.opponent_switches, c.attack_switches, t.samples(), t.samples_outside_play(),
      t.table_summary().transitions);
  if (const auto motion = t.table_summary().motion) {
    out += fmt::format(", {} motion instances", motion->instances);
  }
  return out;
}

}  // namespace

int run_offline(const TrainerOptions& options) {
  check_table_option(options);
  Destination to;
  to.config = options.model.sampler_config();
  to.motion = motion_config(options);
  to.rules = match_rules(options);
  to.all_teams = options.model.opponent_team == "all";
  to.per_team = !options.table_dir.empty();
  to.tracked = options.network.tracked();
  if (to.all_teams && !to.per_team) {
    throw app::UsageError("--opponent-team all trains a table per team: give --table-dir");
  }
  if (to.all_teams && options.model.opponent_color != "referee") {
    throw app::UsageError(
        "--opponent-team all finds each team's colour by its name: leave out "
        "--opponent-color");
  }
  if (options.jobs < 0) throw app::UsageError("--jobs must be 0 (every core) or more");
  // Creates --table-dir where it is missing; no other trainer may write these tables meanwhile.
  const TableWriterLock lock = lock_tables(options);
  // The tables the logs add to, by file: --table's opened first, so that a table that cannot be
  // resumed stops the run before any log is read; --table-dir's as their teams turn up.
  std::map<std::filesystem::path, std::unique_ptr<Training>> tables;
  if (!to.per_team) {
    tables[options.table] =
        open_training(options.table, to.config, options.reset, to.motion, to.rules, to.tracked);
  }

  std::vector<LogOutcome> outcomes(options.from_logs.size());
  Progress progress;
  std::uint64_t total_bytes = 0;
  for (const std::string& file : options.from_logs) {
    std::error_code error;  // a file that cannot be read is reported by its reader
    const std::uintmax_t size = std::filesystem::file_size(file, error);
    if (!error) total_bytes += size;
  }
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t workers = std::min<std::size_t>(
      options.from_logs.size(), options.jobs > 0 ? static_cast<std::size_t>(options.jobs) : cores);
  std::vector<std::thread> threads;
  std::mutex failure_mutex;
  std::string failure;  // an exception a worker met (a bug, or memory): reported after
  for (std::size_t w = 0; w < workers; ++w) {
    threads.emplace_back([&] {
      for (std::size_t i = progress.next_file++; i < outcomes.size(); i = progress.next_file++) {
        try {
          outcomes[i] = train_log(options.from_logs[i], to, progress);
        } catch (const std::exception& error) {
          std::lock_guard lock(failure_mutex);
          failure = options.from_logs[i] + ": " + error.what();
        }
      }
    });
  }
  {
    std::optional<app::ProgressBar> bar;
    if (total_bytes > progress_bar_bytes) {
      bar.emplace(fmt::format("training from {} log{} on {} thread{}", outcomes.size(),
                              outcomes.size() == 1 ? "" : "s", workers, workers == 1 ? "" : "s"),
                  total_bytes);
    }
    while (progress.next_file < outcomes.size() + workers) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (bar) bar->update(progress.bytes, progress.frames);
    }
    for (std::thread& thread : threads) thread.join();
    if (bar) bar->finish(progress.frames);
  }
  if (!failure.empty()) throw std::runtime_error(failure);

  // The logs' counts added up in the order of the files, and a line per log.
  bool every_file_whole = true;
  std::set<std::filesystem::path> taught;
  for (LogOutcome& log : outcomes) {
    if (!log.open_error.empty()) {
      spdlog::error("{}", log.open_error);
      every_file_whole = false;
      continue;
    }
    const LogReadCounters& c = log.counters;
    spdlog::info("{}: {} {} ({} parse errors), {} referee, {} {} tracker, {} other", log.file,
                 log.frames, to.tracked ? "tracked frames" : "vision packets", c.parse_errors,
                 c.referee, to.tracked ? "of" : "skipped", c.tracker,
                 c.unknown + c.blank + c.legacy_unusable);
    if (to.all_teams && log.teams.empty()) {
      spdlog::warn("{}: no team named by a referee: nothing learned (--opponent-team all)",
                   log.file);
    }
    for (TeamOfLog& team : log.teams) {
      const Training& training = *team.training;
      if (!team.found) {
        spdlog::warn("{}: skipped, {}", log.file, training.match().opponent().unresolved);
        continue;
      }
      if (!training.match().opponent_known()) {
        spdlog::info(
            "{}: the opponent was found, then no longer named ({}): what was learned "
            "while it was is kept",
            log.file, training.match().opponent().unresolved);
      }
      spdlog::info("{}: opponent {}", log.file, describe_team(team));
      // The team's table: the one named (the file names ignore case as names do), else the
      // last opponent the referee named (--our-team), else the unnamed team's.
      const OpponentChoice& choice = training.match().choice();
      const std::string& team_name = !choice.opponent_team.empty()
                                         ? choice.opponent_team
                                         : training.match().last_named_opponent();
      const std::filesystem::path path =
          to.per_team ? std::filesystem::path(options.table_dir) / team_table_file_name(team_name)
                      : std::filesystem::path(options.table);
      std::unique_ptr<Training>& table = tables[path];
      if (!table) {
        try {
          table = open_training(path, to.config, options.reset, to.motion, to.rules, to.tracked);
        } catch (const std::runtime_error& error) {
          spdlog::error("{}; what {} taught of '{}' is not saved", error.what(), log.file,
                        training.match().opponent().name);
          tables.erase(path);
          every_file_whole = false;
          continue;
        }
      }
      table->absorb(training);
      taught.insert(path);
    }
    switch (log.ending) {
      case LogReader::Ending::none:
        break;
      case LogReader::Ending::cut_off:
        // What a recorder killed mid-write leaves: only the last message is lost.
        if (options.strict) {
          spdlog::error("{}; the {} vision packets before it were used (--strict)", log.read_error,
                        log.frames);
          every_file_whole = false;
        } else {
          spdlog::warn(
              "{}: the file ends inside its last message; the {} vision packets before "
              "it were used",
              log.read_error, log.frames);
        }
        break;
      case LogReader::Ending::damaged:
        spdlog::error("{}; the {} vision packets before it were used", log.read_error, log.frames);
        every_file_whole = false;
        break;
    }
  }
  // Only the tables some log taught are written: a run that could read no log writes nothing.
  if (taught.empty()) {
    const bool any_read = std::any_of(outcomes.begin(), outcomes.end(),
                                      [](const LogOutcome& log) { return log.open_error.empty(); });
    spdlog::warn("no table written: {}",
                 any_read ? "no log taught anything of the opponent" : "no log could be read");
    return every_file_whole ? 0 : 1;
  }
  // A run that fails writes nothing: every table stays as it was, and the logs can be fixed or
  // left out and the run made again.
  if (!every_file_whole) {
    spdlog::error(
        "no table written (every table is as it was): not every log was read whole{}",
        options.strict ? " (--strict)" : "; leave the damaged ones out to train on the rest");
    return 1;
  }
  for (auto& [path, training] : tables) {
    if (!taught.contains(path)) continue;
    if (const auto problem = training->feed_problem()) spdlog::warn("{}", *problem);
    const auto saved =
        save_training(path, *training, app::table_budget_option(options.max_table_mb));
    if (!saved) return 1;
    const TableSummary table = training->table_summary();
    spdlog::info("saved {}: {} transitions from {} formations, {} states seen ({:.2f} MB)",
                 path.string(), table.transitions, training->samples(), table.states_seen,
                 static_cast<double>(saved->bytes) / 1e6);
    if (const auto& motion = table.motion) {
      spdlog::info(
          "saved {}: motion model, {} horizons: motion_instances={} motion_held_out={} "
          "motion_rows={} (of {} learned; the others add nothing over coarser rows)",
          path.string(), motion->horizons, motion->instances, motion->held_out, saved->motion_rows,
          motion->rows);
    }
  }
  return every_file_whole ? 0 : 1;
}

}  // namespace ssl_formation::trainer
