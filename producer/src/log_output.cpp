// --write-log: the simulated feed written straight to an official SSL log, with no network and
// no waiting. Every packet gets the receive time its step's t_capture gives (in ns), so the file
// replays with the data clock's own timing and holds exactly what the live producer sends for
// the same options: each step's referee message (type 3), then its vision packets.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cmath>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/producer/producer_options.hpp"
#include "ssl_formation/producer/simulation_source.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation::producer {

namespace {

// Steps (formations or frames) written between two looks at signals and timers.
constexpr int kStepsPerBatch = 256;
// Receive times are int64 nanoseconds: t_capture must stay well inside that.
constexpr double kMaxDataTimeS = 9.0e9;

}  // namespace

int run_write_log(const ProducerOptions& options) {
  if (options.count == 0 && !(options.duration_s > 0.0)) {
    throw app::UsageError(
        "--write-log needs --count (formations or frames) or --duration (seconds of data time)");
  }
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);
  // Every option is checked before the file is created: a usage error writes nothing.
  std::unique_ptr<SimulationSource> simulation = make_simulation_source(options, true);
  const double seconds = options.count != 0
                             ? static_cast<double>(options.count) * simulation->step_s()
                             : options.duration_s;
  const double last_time_s = options.start_time_s + seconds;
  if (!std::isfinite(options.start_time_s) || std::abs(options.start_time_s) > kMaxDataTimeS ||
      !std::isfinite(last_time_s) || std::abs(last_time_s) > kMaxDataTimeS) {
    throw app::UsageError(
        "--start-time, --step, --count and --duration give data times beyond what a log's "
        "nanosecond receive times can hold");
  }
  const auto done = [&](std::uint64_t steps) {
    return simulation_done(options, steps, simulation->step_s());
  };

  Result<LogWriter> writer = LogWriter::create(options.write_log);
  if (!writer) throw std::runtime_error(writer.error().message);
  // The writer removes what it wrote when the run fails: the path keeps what it held.
  const auto failed = [&] {
    return std::runtime_error(writer->error() + "; " + options.write_log +
                              " not written (an earlier file there is as it was)");
  };
  const simulation::SimulatedGameController* game = simulation->game_controller();
  spdlog::info(
      "writing the {} simulation to {}: {}, {} s of data time a step, {} camera(s), "
      "seed {}, {}",
      options.simulation, options.write_log,
      options.count ? fmt::format("{} {}", options.count, simulation->steps_name())
                    : fmt::format("{} s", options.duration_s),
      simulation->step_s(), options.cameras, options.seed,
      game ? fmt::format("referee messages of our team '{}' against '{}', halves of {} s",
                         game->config().our_name, game->config().opponent_name,
                         game->config().half_s)
           : std::string("no referee messages (--referee off)"));

  std::uint64_t steps = 0;
  std::uint64_t packets = 0;
  std::uint64_t referee_messages = 0;
  std::uint64_t dropped = 0;
  bool stopped = false;
  const auto started = std::chrono::steady_clock::now();
  const auto log_status = [&](const char* what, app::StatusMoment moment) {
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    app::StatusLine line;
    simulation->describe(steps, line);
    line.figure("packets", packets)
        .figure("bytes", writer->offset())
        .figure("seconds", fmt::format("{:.2f}", wall_s));
    if (game) describe_game_controller(*game, line);
    line.detail("referee_written", referee_messages).detail("drop_rate_dropped", dropped);
    line.log(what, moment);
  };

  // Signals and status lines through the same io_context as the other modes, polled between
  // batches: the loop itself never waits.
  boost::asio::io_context io;
  app::RepeatingTimer status(io, status_period,
                             [&] { log_status("status", app::StatusMoment::periodic); });
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: closing {} and stopping", signal, options.write_log);
    stopped = true;
  });

  while (!stopped && !done(steps)) {
    for (int i = 0; i < kStepsPerBatch && !done(steps); ++i) {
      const SimulatedStep step = simulation->next();
      const auto receive_time_ns = static_cast<std::int64_t>(std::llround(step.t_capture * 1e9));
      if (step.referee) {
        if (!writer->write(static_cast<std::int32_t>(LogMessageType::referee), receive_time_ns,
                           step.referee->SerializeAsString())) {
          throw failed();
        }
        ++referee_messages;
      }
      for (const SSL_WrapperPacket& packet : step.packets) {
        if (!writer->write_vision(packet, receive_time_ns)) {
          throw failed();
        }
        ++packets;
      }
      dropped += static_cast<std::uint64_t>(step.dropped_packets);
      ++steps;
    }
    io.poll();
  }
  status.cancel();
  if (!writer->close()) throw failed();
  log_status(stopped ? "stopped" : "done", app::StatusMoment::at_stop);
  return 0;
}

}  // namespace ssl_formation::producer
