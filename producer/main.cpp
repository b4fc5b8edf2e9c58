// ssl-producer: SSL-Vision-style packets on multicast. By default the paper's simulated vision
// (three plays and random formations), one formation every --period seconds.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

#include "simulated_vision.hpp"
#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/proto_multicast.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

struct ProducerOptions {
  std::string vision_address = sf::app::default_vision_address;
  std::string interface = sf::app::default_interface;
  int ttl = sf::net::kDefaultMulticastTtl;
  double period_s = 2.0;
  double step_s = 2.0;
  std::uint64_t count = 0;
  std::uint64_t seed = 1;
  int cameras = 1;
  double camera_overlap_mm = 200.0;
  double jitter_mm = 0.0;
  double drop_rate = 0.0;
  std::string opponent_color = "yellow";
  std::string opponent_attacks = "+x";
  double field_length_mm = 9000.0;
  double field_width_mm = 6000.0;
  double start_time_s = 0.0;
  double status_interval_s = 5.0;
  bool verbose = false;
};

sf::sim::SimulationConfig simulation_config(const ProducerOptions& options) {
  sf::sim::SimulationConfig config;
  config.seed = options.seed;
  if (!(options.step_s > 0.0)) throw sf::app::UsageError("--step must be a positive number of seconds");
  config.step_s = options.step_s;
  config.start_time_s = options.start_time_s;
  if (options.cameras < 1 || options.cameras > 8) throw sf::app::UsageError("--cameras must be 1 to 8");
  config.cameras = options.cameras;
  if (!(options.camera_overlap_mm >= 0.0)) throw sf::app::UsageError("--camera-overlap must be >= 0 mm");
  config.camera_overlap_mm = options.camera_overlap_mm;
  if (!(options.jitter_mm >= 0.0)) throw sf::app::UsageError("--jitter-mm must be >= 0");
  config.jitter_mm = options.jitter_mm;
  if (!(options.drop_rate >= 0.0 && options.drop_rate <= 1.0)) {
    throw sf::app::UsageError("--drop-rate must be between 0 and 1");
  }
  config.drop_rate = options.drop_rate;
  const auto color = sf::parse_team_color(options.opponent_color);
  if (!color) throw sf::app::UsageError("--opponent-color must be yellow or blue");
  config.opponent_color = *color;
  const auto attacks = sf::parse_attack_direction(options.opponent_attacks);
  if (!attacks) throw sf::app::UsageError("--opponent-attacks must be +x or -x");
  config.opponent_attacks = *attacks;
  config.field = sf::FieldSize{options.field_length_mm, options.field_width_mm};
  if (!config.field.valid()) throw sf::app::UsageError("--field-length and --field-width must be positive");
  return config;
}

// Sends the simulated feed on a fixed schedule (start + k * period, so no drift accumulates).
class SimulatedFeed {
 public:
  SimulatedFeed(boost::asio::io_context& io, const ProducerOptions& options,
                sf::net::ProtoMulticastSender<SSL_WrapperPacket>& sender)
      : io_(io), timer_(io), options_(options), vision_(simulation_config(options)), sender_(sender) {}

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
    spdlog::info("{}: {} formations ({} from plays = {:.1f}%, {} random = {:.1f}%), {} packets sent, "
                 "{} dropped by --drop-rate, {} send errors",
                 what, formations_, play_formations_, 100.0 * play_formations_ / total,
                 formations_ - play_formations_, 100.0 * (formations_ - play_formations_) / total,
                 sender_.sent(), dropped_, sender_.send_errors());
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
    const sf::sim::SimulatedFormation formation = vision_.next();
    for (const SSL_WrapperPacket& packet : formation.packets) sender_.send(packet);
    ++formations_;
    dropped_ += static_cast<std::uint64_t>(formation.dropped_packets);
    if (formation.source == sf::sim::FormationSource::play) ++play_formations_;
    if (formation.source == sf::sim::FormationSource::play) {
      spdlog::debug("formation {} t={:.2f}: play {} ({}) step {}/3", formation.index,
                    formation.t_capture, formation.play + 1, sf::sim::play_name(formation.play),
                    formation.play_step + 1);
    } else {
      spdlog::debug("formation {} t={:.2f}: random", formation.index, formation.t_capture);
    }
  }

  boost::asio::io_context& io_;
  boost::asio::steady_timer timer_;
  const ProducerOptions& options_;
  sf::sim::SimulatedVision vision_;
  sf::net::ProtoMulticastSender<SSL_WrapperPacket>& sender_;
  std::chrono::steady_clock::time_point next_send_;
  std::uint64_t formations_ = 0;
  std::uint64_t play_formations_ = 0;
  std::uint64_t dropped_ = 0;
  bool stopped_ = false;
};

int run_simulation(const ProducerOptions& options) {
  const auto group = sf::app::parse_group_option("vision-address", options.vision_address);
  const auto interface = sf::app::parse_interface_option(options.interface, false);
  if (options.ttl < 0 || options.ttl > 255) throw sf::app::UsageError("--ttl must be 0 to 255");
  if (!(options.period_s >= 0.0)) throw sf::app::UsageError("--period must be >= 0 seconds");
  const auto status_period = sf::app::seconds_option("status-interval", options.status_interval_s);

  boost::asio::io_context io;
  sf::net::ProtoMulticastSender<SSL_WrapperPacket> sender(io, group, interface.address, options.ttl);
  sender.open();
  SimulatedFeed feed(io, options, sender);
  spdlog::info("sending simulated vision to {} (interface {}, ttl {}): period {} s, step {} s, "
               "{} camera(s), seed {}, {} formations",
               group.to_string(), interface.to_string(), options.ttl, options.period_s,
               options.step_s, options.cameras, options.seed,
               options.count ? std::to_string(options.count) : std::string("unlimited"));
  sf::app::RepeatingTimer status(io, status_period, [&] { feed.log_summary("status"); });
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    feed.stop();
    status.cancel();
    io.stop();
  });
  feed.start();
  io.run();
  feed.log_summary(feed.finished() ? "done" : "stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-producer", [&] {
    ProducerOptions o;
    po::options_description general("Options");
    general.add_options()
        ("vision-address", po::value(&o.vision_address)->default_value(o.vision_address),
         "multicast group:port to send to")
        ("interface", po::value(&o.interface)->default_value(o.interface),
         "IPv4 address of the interface to send from")
        ("ttl", po::value(&o.ttl)->default_value(o.ttl), "multicast TTL (1 keeps packets on the link)")
        ("period", po::value(&o.period_s)->default_value(o.period_s),
         "wall-clock seconds between formations; 0 = as fast as possible")
        ("step", po::value(&o.step_s)->default_value(o.step_s),
         "data-clock seconds (t_capture) between formations")
        ("count", po::value(&o.count)->default_value(o.count), "formations to send, then exit; 0 = no limit")
        ("seed", po::value(&o.seed)->default_value(o.seed), "random seed: the same seed sends the same packets")
        ("cameras", po::value(&o.cameras)->default_value(o.cameras),
         "cameras the field is split among (1-8); robots in overlaps are reported by both")
        ("camera-overlap", po::value(&o.camera_overlap_mm)->default_value(o.camera_overlap_mm),
         "overlap between neighbouring cameras, mm")
        ("jitter-mm", po::value(&o.jitter_mm)->default_value(o.jitter_mm),
         "standard deviation of Gaussian noise on detected positions, mm")
        ("drop-rate", po::value(&o.drop_rate)->default_value(o.drop_rate),
         "probability that a camera's packet is lost (0-1)")
        ("opponent-color", po::value(&o.opponent_color)->default_value(o.opponent_color),
         "colour of the simulated opponent: yellow or blue")
        ("opponent-attacks", po::value(&o.opponent_attacks)->default_value(o.opponent_attacks),
         "direction the simulated opponent attacks in the feed's coordinates: +x or -x")
        ("field-length", po::value(&o.field_length_mm)->default_value(o.field_length_mm),
         "field length, mm (plays are drawn for 9000 and stretched)")
        ("field-width", po::value(&o.field_width_mm)->default_value(o.field_width_mm),
         "field width, mm (plays are drawn for 6000 and stretched)")
        ("start-time", po::value(&o.start_time_s)->default_value(o.start_time_s),
         "t_capture of the first formation, seconds")
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr")
        ("verbose", po::bool_switch(&o.verbose), "log every formation sent");
    if (!sf::app::parse_command_line(argc, argv, general, "ssl-producer [options]",
                                     "Sends SSL-Vision packets of the paper's simulated opponent "
                                     "(three plays and random formations) on multicast.")) {
      return 0;
    }
    sf::app::init_logging("ssl-producer", o.verbose);
    return run_simulation(o);
  });
}
