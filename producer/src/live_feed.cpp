// The live simulated feed on multicast: the paper's simulated opponent (a formation every
// --period seconds of wall time) or the match (a frame every 1/--frame-rate seconds), each
// step after the simulated game controller's referee message.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/producer/producer_options.hpp"
#include "ssl_formation/producer/simulation_source.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation::producer {

namespace {

// Sends the simulated feed on a fixed schedule (start + k * period, so no drift accumulates).
class SimulatedFeed {
 public:
  // `referee`: where the game controller's messages go; null: no game controller.
  SimulatedFeed(boost::asio::io_context& io, const ProducerOptions& options,
                std::unique_ptr<SimulationSource> simulation,
                net::ProtoMulticastSender<SSL_WrapperPacket>& sender,
                net::ProtoMulticastSender<Referee>* referee)
      : io_(io),
        timer_(io),
        options_(options),
        simulation_(std::move(simulation)),
        sender_(sender),
        referee_(referee) {}

  void start() {
    next_send_ = std::chrono::steady_clock::now();
    schedule();
  }
  void stop() {
    stopped_ = true;
    timer_.cancel();
  }
  bool finished() const { return simulation_done(options_, steps_, simulation_->step_s()); }

  void log_summary(const char* what, app::StatusMoment moment) const {
    app::StatusLine line;
    simulation_->describe(steps_, line);
    line.figure("packets", sender_.sent());
    if (referee_) line.detail("referee_sent", referee_->sent());
    line.detail("drop_rate_dropped", dropped_)
        .problem("send_errors", sender_.send_errors() + (referee_ ? referee_->send_errors() : 0));
    const simulation::SimulatedGameController* game = simulation_->game_controller();
    if (referee_ && game) describe_game_controller(*game, line);
    line.log(what, moment);
  }

 private:
  void schedule() {
    if (stopped_) return;
    if (finished()) {
      io_.stop();
      return;
    }
    const double period_s = simulation_->live_period_s();
    if (period_s <= 0.0) {
      // As fast as possible, in batches, so signals and timers still get their turn.
      for (int i = 0; i < 64 && !finished(); ++i) send_one();
      boost::asio::post(io_, [this] { schedule(); });
      return;
    }
    timer_.expires_at(next_send_);
    timer_.async_wait([this, period_s](const boost::system::error_code& error) {
      if (error || stopped_) return;
      send_one();
      next_send_ += std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(period_s));
      schedule();
    });
  }

  void send_one() {
    const SimulatedStep step = simulation_->next();
    if (step.referee && referee_) referee_->send(*step.referee);
    for (const SSL_WrapperPacket& packet : step.packets) sender_.send(packet);
    ++steps_;
    dropped_ += static_cast<std::uint64_t>(step.dropped_packets);
    spdlog::debug("{} {} t={:.3f}: {} packets", simulation_->steps_name(), step.index,
                  step.t_capture, step.packets.size());
  }

  boost::asio::io_context& io_;
  boost::asio::steady_timer timer_;
  const ProducerOptions& options_;
  std::unique_ptr<SimulationSource> simulation_;
  net::ProtoMulticastSender<SSL_WrapperPacket>& sender_;
  net::ProtoMulticastSender<Referee>* referee_;
  std::chrono::steady_clock::time_point next_send_;
  std::uint64_t steps_ = 0;
  std::uint64_t dropped_ = 0;
  bool stopped_ = false;
};

}  // namespace

int run_simulation(const ProducerOptions& options) {
  const auto group = app::parse_group_option("vision-address", options.vision_address);
  const auto interface = app::parse_interface_option(options.interface, false);
  if (options.ttl < 0 || options.ttl > 255) throw app::UsageError("--ttl must be 0 to 255");
  if (!(options.period_s >= 0.0)) throw app::UsageError("--period must be >= 0 seconds");
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);

  const std::optional<net::MulticastEndpoint> referee_group =
      options.referee ? app::parse_referee_option(options.referee_address) : std::nullopt;
  // Checked before any socket opens, so a bad option is a usage error and nothing else.
  // The game controller runs whatever --referee-address says: the simulation is the same as
  // --write-log's for the same options, and `none` only keeps its messages off the network.
  std::unique_ptr<SimulationSource> simulation = make_simulation_source(options, true);
  const simulation::SimulatedGameController* game = simulation->game_controller();

  boost::asio::io_context io;
  net::ProtoMulticastSender<SSL_WrapperPacket> sender(io, group, interface.address, options.ttl);
  sender.open();
  std::optional<net::ProtoMulticastSender<Referee>> referee;
  if (referee_group && game) {
    referee.emplace(io, *referee_group, interface.address, options.ttl);
    referee->open();
  }
  spdlog::info(
      "sending the {} simulation to {} (interface {}, ttl {}): a step every {} s of wall time "
      "and {} s of data time, {} camera(s), seed {}, {}",
      options.simulation, group.to_string(), interface.to_string(), options.ttl,
      simulation->live_period_s(), simulation->step_s(), options.cameras, options.seed,
      options.count            ? fmt::format("{} {}", options.count, simulation->steps_name())
      : options.duration_s > 0 ? fmt::format("{} s", options.duration_s)
                               : std::string("no end"));
  if (referee) {
    spdlog::info(
        "simulated game controller on {}: our team '{}', opponent '{}' ({} attacking {} "
        "in the first half), halves of {} s of data time",
        referee_group->to_string(), game->config().our_name, game->config().opponent_name,
        to_string(game->config().opponent_color), to_string(game->config().opponent_attacks),
        game->config().half_s);
  } else {
    spdlog::info("no simulated game controller ({})",
                 options.referee ? "--referee-address none" : "--referee off");
  }
  SimulatedFeed feed(io, options, std::move(simulation), sender, referee ? &*referee : nullptr);
  app::RepeatingTimer status(io, status_period,
                             [&] { feed.log_summary("status", app::StatusMoment::periodic); });
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    feed.stop();
    status.cancel();
    io.stop();
  });
  app::ReadyFile ready(options.daemon.ready_file);
  ready.mark_ready("ssl-producer", {{"mode", "simulation"},
                                    {"vision", group.to_string()},
                                    {"referee", referee ? referee_group->to_string() : "none"},
                                    {"interface", interface.to_string()}});
  feed.start();
  io.run();
  feed.log_summary(feed.finished() ? "done" : "stopped", app::StatusMoment::at_stop);
  return 0;
}

}  // namespace ssl_formation::producer
