// ssl-trainer's live mode: the match's events from the network through Training into the table
// file, saved as soon as it has something, then every --flush-interval, and on SIGINT/SIGTERM.

#include "ssl_formation/trainer/live_trainer.hpp"

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>

namespace ssl_formation::trainer {

LiveTrainer::LiveTrainer(const TrainerOptions& options, const app::Clock& clock,
                         SaveHooks save_hooks)
    : options_(options),
      clock_(clock),
      saver_(std::move(save_hooks)),
      tables_((check_table_option(options), options), &saver_),
      field_log_(options.model.sampler_config().field,
                 options.model.sampler_config().use_geometry) {
  if (options.model.opponent_team == "all") {
    throw app::UsageError("--opponent-team all is for --from-log: live, name the opponent");
  }
  const Training& training = tables_.training();
  const SamplerConfig& config = training.sampler().config();
  const std::optional<TableSummary::Motion> motion = training.table_summary().motion;
  spdlog::info(
      "training: model {}; grid {}, step {} s, {} sampling; learning {}; vision {}; referee {}; "
      "{} {}, saved when it first learns, then every {} s",
      motion ? fmt::format("motion ({} steps ahead)", motion->horizons)
             : std::string(to_string(training.model())),
      config.grid.to_string(), config.step_s, to_string(config.sampling),
      training.learn_during() == LearnDuring::all ? "in every game state"
                                                  : "in running play once a referee is heard",
      options.network.tracked() ? "tracked " + options.network.tracker_address
                                : options.network.vision_address,
      options.network.referee_address, tables_.per_opponent() ? "a table per opponent in" : "table",
      tables_.per_opponent() ? options.table_dir : tables_.path().string(),
      options.flush_interval_s);
  match_log_.update(training.front_end());
}

void LiveTrainer::on_event(const MatchEvent& event) {
  const RefereeChange change = tables_.handle(event);
  const Training& training = tables_.training();
  switch (event.kind) {
    case MatchEventKind::vision:
      if (event.frame && event.frame->has_geometry) field_log_.update(training.sampler().field());
      if (training.sampler().config().infer_attacks) match_log_.update(training.front_end());
      break;
    case MatchEventKind::referee:
    case MatchEventKind::tracked_vision:
      match_log_.update(training.front_end(), change);
      break;
  }
}

void LiveTrainer::start_new_stream() { tables_.training().start_new_stream(); }

void LiveTrainer::tick() {
  const Training& training = tables_.training();
  if (!feed_problem_said_) {
    if (const auto problem = training.feed_problem()) {
      spdlog::warn("{}", *problem);
      feed_problem_said_ = true;
    }
  }
  if (!training.changed_since_save()) return;
  const double now = clock_.steady_s();
  if (last_save_s_ && now - *last_save_s_ < options_.flush_interval_s) return;
  last_save_s_ = now;
  if (tables_.save_if_changed()) ++saves_;
}

bool LiveTrainer::save_at_exit() { return tables_.save_at_exit(); }

void LiveTrainer::log_status(const net::LiveMatchEvents* live, app::StatusMoment moment) {
  const Training& training = tables_.training();
  const SamplerCounters& c = training.sampler().counters();
  const TableSummary table = training.table_summary();
  const std::optional<TableSummary::Motion>& motion = table.motion;
  app::StatusLine status;
  app::add_reception(status, live, training.front_end());
  status.figure("formations", c.samples);
  // What was learned: the motion model's instances, or the paper's transitions.
  if (motion) {
    status.figure("motion_instances", motion->instances);
  } else {
    status.figure("table_transitions", table.transitions);
  }
  app::add_match(status, training.front_end());
  status.detail("transitions", c.transitions)
      .detail("referee_messages", training.match().referee().counters().messages);
  if (motion) status.detail("table_transitions", table.transitions);
  status.detail("states_seen", table.states_seen).detail("saves", saves_);
  app::add_sampler_counters(status, c);
  if (motion) {
    status.detail("motion_rows", motion->rows).detail("motion_held_out", motion->held_out);
  }
  app::add_reception_details(status, live, training.front_end());
  status.log("status", moment);
  for (const std::string& line : new_rejections(reported_, c)) spdlog::warn("input: {}", line);
  reported_ = c;
}

int run_live(const TrainerOptions& options) {
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);
  const auto flush_period = app::seconds_option("flush-interval", options.flush_interval_s);
  const net::LiveFeeds feeds = app::live_feeds(options.network, options.receive_buffer_bytes);
  const app::SystemClock clock;
  // Before LiveTrainer reads the table to resume it (it checks --table's folder first itself).
  check_table_option(options);
  const TableWriterLock lock = lock_tables(options);
  LiveTrainer trainer(options, clock);

  boost::asio::io_context io;
  app::ReadyFile ready(options.daemon.ready_file);
  net::LiveMatchEvents events(io, feeds, [&clock] { return clock.steady_s(); });
  events.start(trainer);
  // Often enough for the first save to come as soon as there is something, and for every save
  // to come on time.
  const auto tick_period =
      std::min<std::chrono::steady_clock::duration>(flush_period, std::chrono::milliseconds(200));
  app::RepeatingTimer ticks(io, tick_period, [&] { trainer.tick(); });
  app::RepeatingTimer status(io, status_period, [&] { trainer.log_status(&events); });
  bool saved_on_exit = true;
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: saving and stopping (a second signal stops at once, unsaved)", signal);
    events.stop();
    ticks.cancel();
    status.cancel();
    saved_on_exit = trainer.save_at_exit();
    io.stop();
  });
  ready.mark_ready("ssl-trainer",
                   {{"vision", options.network.tracked() ? "tracked " + feeds.tracker->to_string()
                                                         : feeds.vision.to_string()},
                    {"referee", feeds.referee ? feeds.referee->to_string() : "none"},
                    {"interface", feeds.interface.to_string()},
                    {"table", trainer.tables().path().string()}});
  io.run();
  trainer.log_status(&events, app::StatusMoment::at_stop);
  return saved_on_exit ? 0 : 1;
}

}  // namespace ssl_formation::trainer
