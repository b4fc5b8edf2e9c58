// --write-log: the simulated feed written straight to an official SSL log, with no network and
// no waiting. Every packet gets the receive time its formation's t_capture gives (in ns), so the
// file replays with the data clock's own timing and holds exactly what the live producer sends
// for the same options: each formation's referee message (type 3), then its vision packets.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cmath>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/log_file.hpp"
#include "ssl_formation/producer/producer_options.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation::producer {

namespace {

// Formations written between two looks at signals and timers.
constexpr int kFormationsPerBatch = 256;
// Receive times are int64 nanoseconds: t_capture must stay well inside that.
constexpr double kMaxDataTimeS = 9.0e9;

}  // namespace

int run_write_log(const ProducerOptions& options) {
  const sim::SimulationConfig config = simulation_config(options);
  if (options.count == 0) {
    throw app::UsageError("--write-log needs --count: the number of formations to write");
  }
  const double last_time_s =
      options.start_time_s + static_cast<double>(options.count) * options.step_s;
  if (!std::isfinite(options.start_time_s) || std::abs(options.start_time_s) > kMaxDataTimeS ||
      std::abs(last_time_s) > kMaxDataTimeS) {
    throw app::UsageError(
        "--start-time, --step and --count give data times beyond what a log's "
        "nanosecond receive times can hold");
  }
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);

  // Checked before the file is created, as the options above: a usage error writes nothing.
  const std::optional<sim::GameControllerConfig> game = game_controller_config(options, false);

  Result<LogWriter> writer = LogWriter::create(options.write_log);
  if (!writer) throw std::runtime_error(writer.error().message);
  spdlog::info(
      "writing simulated vision to {}: {} formations, step {} s, {} camera(s), seed {}, {}",
      options.write_log, options.count, options.step_s, options.cameras, options.seed,
      game ? fmt::format("referee messages of our team '{}' against '{}', halves of {} s",
                         game->our_name, game->opponent_name, game->half_s)
           : std::string("no referee messages (--referee off)"));

  sim::RefereedSimulation simulation(config, game);
  std::uint64_t formations = 0;
  std::uint64_t packets = 0;
  std::uint64_t referee_messages = 0;
  std::uint64_t dropped = 0;
  bool stopped = false;
  const auto started = std::chrono::steady_clock::now();
  const auto log_status = [&](const char* what) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    spdlog::info(
        "{}: {} formations, {} packets and {} referee messages written ({} bytes, {} dropped by "
        "--drop-rate) to {} in {:.2f} s{}",
        what, formations, packets, referee_messages, writer->offset(), dropped, options.write_log,
        seconds,
        simulation.game_controller() ? "; " + sim::describe(*simulation.game_controller())
                                     : std::string());
  };

  // Signals and status lines through the same io_context as the other modes, polled between
  // batches: the loop itself never waits.
  boost::asio::io_context io;
  app::RepeatingTimer status(io, status_period, [&] { log_status("status"); });
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: closing {} and stopping", signal, options.write_log);
    stopped = true;
  });

  while (!stopped && formations < options.count) {
    for (int i = 0; i < kFormationsPerBatch && formations < options.count; ++i) {
      const sim::RefereedFormation step = simulation.next();
      const sim::SimulatedFormation& formation = step.formation;
      const auto receive_time_ns =
          static_cast<std::int64_t>(std::llround(formation.t_capture * 1e9));
      if (step.referee) {
        if (!writer->write(static_cast<std::int32_t>(LogMessageType::referee), receive_time_ns,
                           step.referee->SerializeAsString())) {
          throw std::runtime_error(writer->error());
        }
        ++referee_messages;
      }
      for (const SSL_WrapperPacket& packet : formation.packets) {
        if (!writer->write_vision(packet, receive_time_ns)) {
          throw std::runtime_error(writer->error());
        }
        ++packets;
      }
      dropped += static_cast<std::uint64_t>(formation.dropped_packets);
      ++formations;
    }
    io.poll();
  }
  status.cancel();
  if (!writer->close()) throw std::runtime_error(writer->error());
  log_status(stopped ? "stopped" : "done");
  return 0;
}

}  // namespace ssl_formation::producer
