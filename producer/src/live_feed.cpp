// The live simulated feed: the paper's simulated opponent on multicast, one formation every
// --period seconds of wall time, each after the simulated game controller's referee message.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/producer/producer_options.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation::producer {

namespace {

// Sends the simulated feed on a fixed schedule (start + k * period, so no drift accumulates).
class SimulatedFeed {
 public:
  // `referee`: where the game controller's messages go; null: no game controller.
  SimulatedFeed(boost::asio::io_context& io, const ProducerOptions& options,
                net::ProtoMulticastSender<SSL_WrapperPacket>& sender,
                net::ProtoMulticastSender<Referee>* referee,
                std::optional<sim::GameControllerConfig> game)
      : io_(io),
        timer_(io),
        options_(options),
        simulation_(simulation_config(options), referee ? std::move(game) : std::nullopt),
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
  bool finished() const { return options_.count != 0 && formations_ >= options_.count; }

  void log_summary(const char* what) const {
    const double total = static_cast<double>(formations_ ? formations_ : 1);
    spdlog::info(
        "{}: {} formations ({} from plays = {:.1f}%, {} random = {:.1f}%), {} packets sent, "
        "{} dropped by --drop-rate, {} send errors{}",
        what, formations_, play_formations_, 100.0 * play_formations_ / total,
        formations_ - play_formations_, 100.0 * (formations_ - play_formations_) / total,
        sender_.sent(), dropped_, sender_.send_errors() + (referee_ ? referee_->send_errors() : 0),
        referee_ ? fmt::format("; {} referee messages sent, {}", referee_->sent(),
                               sim::describe(*simulation_.game_controller()))
                 : std::string());
  }

 private:
  void schedule() {
    if (stopped_) return;
    if (finished()) {
      io_.stop();
      return;
    }
    if (options_.period_s <= 0.0) {
      // As fast as possible, in batches, so signals and timers still get their turn.
      for (int i = 0; i < 64 && !finished(); ++i) send_one();
      boost::asio::post(io_, [this] { schedule(); });
      return;
    }
    timer_.expires_at(next_send_);
    timer_.async_wait([this](const boost::system::error_code& error) {
      if (error || stopped_) return;
      send_one();
      next_send_ += std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(options_.period_s));
      schedule();
    });
  }

  void send_one() {
    const sim::RefereedFormation step = simulation_.next();
    const sim::SimulatedFormation& formation = step.formation;
    if (step.referee) referee_->send(*step.referee);
    for (const SSL_WrapperPacket& packet : formation.packets) sender_.send(packet);
    ++formations_;
    dropped_ += static_cast<std::uint64_t>(formation.dropped_packets);
    if (formation.source == sim::FormationSource::play) ++play_formations_;
    if (formation.source == sim::FormationSource::play) {
      spdlog::debug("formation {} t={:.2f}: play {} ({}) step {}/3", formation.index,
                    formation.t_capture, formation.play + 1, sim::play_name(formation.play),
                    formation.play_step + 1);
    } else {
      spdlog::debug("formation {} t={:.2f}: random", formation.index, formation.t_capture);
    }
  }

  boost::asio::io_context& io_;
  boost::asio::steady_timer timer_;
  const ProducerOptions& options_;
  sim::RefereedSimulation simulation_;
  net::ProtoMulticastSender<SSL_WrapperPacket>& sender_;
  net::ProtoMulticastSender<Referee>* referee_;
  std::chrono::steady_clock::time_point next_send_;
  std::uint64_t formations_ = 0;
  std::uint64_t play_formations_ = 0;
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
  const auto game = game_controller_config(options, true);

  boost::asio::io_context io;
  net::ProtoMulticastSender<SSL_WrapperPacket> sender(io, group, interface.address, options.ttl);
  sender.open();
  std::optional<net::ProtoMulticastSender<Referee>> referee;
  if (referee_group && game) {
    referee.emplace(io, *referee_group, interface.address, options.ttl);
    referee->open();
  }
  SimulatedFeed feed(io, options, sender, referee ? &*referee : nullptr, game);
  spdlog::info(
      "sending simulated vision to {} (interface {}, ttl {}): period {} s, step {} s, "
      "{} camera(s), seed {}, {} formations",
      group.to_string(), interface.to_string(), options.ttl, options.period_s, options.step_s,
      options.cameras, options.seed,
      options.count ? std::to_string(options.count) : std::string("unlimited"));
  if (referee) {
    spdlog::info(
        "simulated game controller on {}: our team '{}', opponent '{}' ({} attacking {} "
        "in the first half), halves of {} s of data time",
        referee_group->to_string(), game->our_name, game->opponent_name,
        to_string(*parse_team_color(options.opponent_color)), options.opponent_attacks,
        game->half_s);
  } else {
    spdlog::info("no simulated game controller ({})",
                 options.referee ? "--referee-address none" : "--referee off");
  }
  app::RepeatingTimer status(io, status_period, [&] { feed.log_summary("status"); });
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
  feed.log_summary(feed.finished() ? "done" : "stopped");
  return 0;
}

}  // namespace ssl_formation::producer
