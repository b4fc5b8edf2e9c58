// ssl-trainer's live mode: the vision feed through Training into the table file, saved every
// --flush-interval and on SIGINT/SIGTERM.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/net/vision_receiver.hpp"
#include "ssl_formation/trainer/opponent_tables.hpp"
#include "ssl_formation/trainer/table_store.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace ssl_formation::trainer {

namespace {

// One status line, then a warning for each kind of bad input that arrived since the last one.
void log_status(const Training& training, const net::VisionReceiver& receiver,
                const net::TrackedVisionReceiver* tracked, SamplerCounters& reported) {
  const SamplerCounters& c = training.sampler().counters();
  const auto& motion = training.motion();
  spdlog::info(
      "status: {}{} formations={} transitions={} table_transitions={} states_seen={}{} "
      "rejected_robots={} late_frames={} attacks={} {} | {}",
      app::describe_reception(receiver), app::describe_tracked(tracked), c.samples, c.transitions, training.table().transitions(),
      training.table().rows_seen(),
      motion ? fmt::format(" motion_instances={} motion_held_out={} motion_rows={}",
                           motion->instances(), motion->held_out(), motion->rows())
             : std::string(),
      c.robots_non_finite + c.robots_out_of_range + c.robots_bad_id,
      c.frames_late,
      app::describe_attacks(training.sampler().attacks(), training.match().opponent().attacks_because),
      app::describe_referee_counts(training.match()), describe_rejections(c));
  for (const std::string& line : new_rejections(reported, c)) spdlog::warn("input: {}", line);
  reported = c;
}

}  // namespace

int run_live(const TrainerOptions& options) {
  if (options.model.opponent_team == "all") {
    throw app::UsageError("--opponent-team all is for --from-log: live, name the opponent");
  }
  const SamplerConfig config = options.model.sampler_config();
  const auto group = app::parse_group_option("vision-address", options.network.vision_address);
  const auto interface = app::parse_interface_option(options.network.interface, true);
  const auto flush_period = app::seconds_option("flush-interval", options.flush_interval_s);
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);

  const std::optional<MotionConfig> motion = motion_config(options);
  const std::optional<net::MulticastEndpoint> referee_group =
      app::parse_referee_option(options.network.referee_address);
  OpponentTables tables(options);

  boost::asio::io_context io;
  app::ReadyFile ready(options.daemon.ready_file);
  net::VisionReceiver receiver(io, group, interface, options.receive_buffer_bytes);
  app::FieldSizeLog field_log(config.field, config.use_geometry);
  app::MatchLog match_log;
  match_log.update(tables.training().match(), tables.training().sampler().attacks());
  const auto on_frame = [&](const VisionFrame& frame) {
    Training& training = tables.training();
    training.add(frame);
    if (frame.has_geometry) field_log.update(training.sampler().field());
    if (training.sampler().config().infer_attacks) {
      match_log.update(training.match(), training.sampler().attacks());
    }
  };
  // Raw vision, or a tracker's frames instead (never both: they would be two clocks).
  std::optional<net::TrackedVisionReceiver> tracked;
  VisionFrame geometry;  // tracked: the raw feed's geometry alone
  if (options.network.tracked()) {
    tracked.emplace(io, app::parse_group_option("tracker-address", options.network.tracker_address),
                    interface, options.receive_buffer_bytes);
    tracked->start(on_frame);
    // The raw feed still gives the field size: the tracker's frames have none.
    receiver.start([&](const VisionFrame& frame, const net::udp::endpoint&) {
      if (app::geometry_only(frame, geometry)) on_frame(geometry);
    });
  } else {
    receiver.start([&](const VisionFrame& frame, const net::udp::endpoint&) { on_frame(frame); });
  }
  // The referee on the same thread as the vision: each command applies from the next frame.
  std::optional<net::MulticastReceiver> referee;
  if (referee_group) {
    referee.emplace(io, *referee_group, interface, options.receive_buffer_bytes);
    referee->start([&](std::span<const std::byte> datagram, const net::udp::endpoint&) {
      const RefereeChange change =
          tables.add_referee(net::as_text(datagram), app::steady_seconds());
      match_log.update(tables.training().match(), tables.training().sampler().attacks(), change);
    });
  }
  spdlog::info(
      "training: model {}; grid {}, step {} s, {} sampling; learning {}; referee {}; {} {} "
      "saved every {} s",
      motion ? fmt::format("motion ({} steps ahead)", motion->horizons) : std::string("paper"),
      config.grid.to_string(), config.step_s, to_string(config.sampling),
      tables.training().learn_during() == LearnDuring::all
          ? "in every game state"
          : "in running play once a referee is heard",
      referee_group ? referee_group->to_string() : std::string("none"),
      tables.per_opponent() ? "a table per opponent in" : "table",
      tables.per_opponent() ? options.table_dir : tables.path().string(),
      options.flush_interval_s);

  app::RepeatingTimer flush(io, flush_period, [&] {
    tables.save_if_changed();
  });
  SamplerCounters reported;
  app::RepeatingTimer status(io, status_period,
                             [&] { log_status(tables.training(), receiver, tracked ? &*tracked : nullptr, reported); });
  bool saved_on_exit = true;
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: saving and stopping (a second signal stops at once, unsaved)",
                 signal);
    receiver.stop();
    if (tracked) tracked->stop();
    if (referee) referee->stop();
    flush.cancel();
    status.cancel();
    saved_on_exit = tables.save_at_exit();
    io.stop();
  });
  ready.mark_ready("ssl-trainer", {{"vision", tracked ? "tracked " + options.network.tracker_address
                                                    : group.to_string()},
                                   {"referee", referee_group ? referee_group->to_string() : "none"},
                                   {"interface", interface.to_string()},
                                   {"table", tables.path().string()}});
  io.run();
  log_status(tables.training(), receiver, tracked ? &*tracked : nullptr, reported);
  return saved_on_exit ? 0 : 1;
}

}  // namespace ssl_formation::trainer
