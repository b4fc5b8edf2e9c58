#pragma once
// ssl-trainer's live mode as an object: the match's events in (from the network in the program,
// from a test's hands in-process), the table files out. It reads time only from the clock it is
// given, so a test drives it with a clock of its own and no sockets; run_live() wires it to the
// network, the timers and the signals.

#include <cstdint>
#include <optional>
#include <string>

#include "ssl_formation/app/clock.hpp"
#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/match/match_event.hpp"
#include "ssl_formation/net/live_match_events.hpp"
#include "ssl_formation/trainer/opponent_tables.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

class LiveTrainer final : public MatchEventSink {
 public:
  // Opens the table (or --table-dir's first) and logs what it trains. Throws app::UsageError for
  // bad options (a --table in a folder that does not exist among them) and std::runtime_error
  // when the table cannot be resumed.
  // Its saves while it runs are made on a thread of their own (TableSaver, with `save_hooks`
  // for tests), so that the feed is read on while a big table is written.
  LiveTrainer(const TrainerOptions& options, const app::Clock& clock, SaveHooks save_hooks = {});

  void on_event(const MatchEvent& event) override;
  void start_new_stream() override;

  // What the timers do, every 0.2 s (or --flush-interval, if shorter): saves the table when it
  // changed, the first time as soon as it has something, then at most every --flush-interval; says
  // once, in plain words, when the model cannot learn from this feed.
  void tick();
  // At exit (SIGINT, SIGTERM): saves (--table's file in any case). False if the save failed.
  bool save_at_exit();
  // One status line, then a warning for each kind of bad input that arrived since the last one.
  // `live`: the network's counters, when the events come from there. At stop, whatever did not fit
  // on the line follows it.
  void log_status(const net::LiveMatchEvents* live = nullptr,
                  app::StatusMoment moment = app::StatusMoment::periodic);

  const OpponentTables& tables() const { return tables_; }
  // Blocks until the saves handed to the saver's thread are done; false if one failed.
  bool wait_for_saves() { return saver_.wait(); }
  const Training& training() const { return tables_.training(); }
  std::uint64_t saves() const { return saves_; }

 private:
  const TrainerOptions& options_;
  const app::Clock& clock_;
  TableSaver saver_;  // before tables_, which hands it saves
  OpponentTables tables_;
  app::FieldSizeLog field_log_;
  app::MatchLog match_log_;
  SamplerCounters reported_;
  std::optional<double> last_save_s_;  // on the clock; none before the first save
  std::uint64_t saves_ = 0;
  bool feed_problem_said_ = false;
};

}  // namespace ssl_formation::trainer
