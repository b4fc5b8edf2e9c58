// ssl-predictor: samples the opponent's formations from the vision feed, predicts the next ones
// from the trainer's table and multicasts them as FormationPrediction messages, with one
// readable line per prediction on stdout. --list-states prints the state space (the paper's
// statesList).

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <iostream>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/prediction_message.hpp"
#include "ssl_formation/sampler.hpp"
#include "ssl_formation/state.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "table_watcher.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

struct PredictorOptions {
  sf::app::ModelOptions model;
  sf::app::NetworkOptions network;
  std::string table = sf::app::default_table;
  std::string prediction_address = sf::app::default_prediction_address;
  std::string prediction_interface;  // empty: as --interface (127.0.0.1 when that is 'all')
  int ttl = sf::net::kDefaultMulticastTtl;
  int horizon = 2;
  double reload_interval_s = 0.5;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = sf::net::kDefaultReceiveBufferBytes;
  bool quiet = false;
  bool list_states = false;
  bool verbose = false;
};

int list_states(const sf::Grid& grid) {
  const sf::StateCodec codec(grid);
  std::string out;
  for (sf::StateIndex index = 0; index < codec.state_count(); ++index) {
    out += codec.describe(index);
    out += '\n';
    if (out.size() > (1 << 20)) {
      std::cout << out;
      out.clear();
    }
  }
  std::cout << out << std::flush;
  return std::cout ? 0 : 1;
}

std::string prediction_interface(const PredictorOptions& options) {
  if (!options.prediction_interface.empty()) return options.prediction_interface;
  return options.network.interface == "all" ? std::string(sf::app::default_interface)
                                            : options.network.interface;
}

// The daemon: vision in, predictions out.
class PredictorDaemon {
 public:
  PredictorDaemon(boost::asio::io_context& io, const PredictorOptions& options,
                  const sf::SamplerConfig& config)
      : options_(options),
        config_(config),
        watcher_(options.table, config.grid),
        sampler_(config, [this](const sf::FormationSample& sample) { on_sample(sample); }),
        receiver_(io, sf::app::parse_group_option("vision-address", options.network.vision_address),
                  sf::app::parse_interface_option(options.network.interface, true),
                  options.receive_buffer_bytes),
        sender_(io, sf::app::parse_group_option("prediction-address", options.prediction_address),
                sf::app::parse_interface_option(prediction_interface(options), false).address,
                options.ttl) {}

  void start() {
    sender_.open();
    receiver_.start([this](const SSL_WrapperPacket& packet, const sf::net::udp::endpoint&) {
      sampler_.add(packet);
    });
    spdlog::info("predicting {} steps ahead; opponent {} attacking {}; grid {}, step {} s",
                 options_.horizon, sf::to_string(config_.opponent_color),
                 sf::to_string(config_.opponent_attacks), config_.grid.to_string(), config_.step_s);
    check_table();
    if (!watcher_.table()) {
      spdlog::info("waiting for the table {}: start ssl-trainer with --table {} (or give --table)",
                   options_.table, options_.table);
    }
  }

  void stop() { receiver_.stop(); }

  void check_table() {
    switch (watcher_.poll()) {
      case sf::predictor::TableWatcher::Change::loaded: {
        const sf::StoredTable& stored = *watcher_.table();
        spdlog::info("loaded table {} (reload {}): {} transitions from {} formations, {} states seen",
                     options_.table, watcher_.reloads(), stored.table.transitions(),
                     stored.metadata.samples, stored.table.rows_seen());
        if (stored.metadata.step_s != config_.step_s) {
          spdlog::warn("the table was trained with --step {} but this predictor samples every {} s",
                       stored.metadata.step_s, config_.step_s);
        }
        break;
      }
      case sf::predictor::TableWatcher::Change::failed:
        spdlog::error("{}; {}", watcher_.last_error(),
                      watcher_.table() ? "keeping the table loaded before" : "still waiting for a valid table");
        break;
      case sf::predictor::TableWatcher::Change::none:
        break;
    }
  }

  void log_status() const {
    const auto& net = receiver_.counters();
    const auto& c = sampler_.counters();
    spdlog::info("status: packets={} parse_errors={} kernel_drops={} formations={} predictions={} "
                 "sent={} table_reloads={}",
                 net.datagrams.load(), net.parse_errors.load(), net.kernel_drops.load(), c.samples,
                 predictions_, sender_.sent(), watcher_.reloads());
  }

 private:
  void on_sample(const sf::FormationSample& sample) {
    if (!watcher_.table()) {
      ++samples_without_table_;
      return;
    }
    const sf::StoredTable& stored = *watcher_.table();
    sf::predict(stored.table, sf::robot_states(sample.formation), options_.horizon, prediction_);
    sf::PredictionContext context;
    context.codec = &stored.table.codec();
    context.field = sampler_.field();
    context.opponent_attacks = config_.opponent_attacks;
    context.opponent_color = config_.opponent_color;
    context.step_s = config_.step_s;
    context.table_transitions = stored.table.transitions();
    sf::fill_prediction_message(sample.formation, prediction_, context, message_);
    sender_.send(message_);
    ++predictions_;
    if (!options_.quiet) std::cout << sf::describe_prediction(sample.formation, prediction_) << '\n' << std::flush;
  }

  const PredictorOptions& options_;
  sf::SamplerConfig config_;
  sf::predictor::TableWatcher watcher_;
  sf::FormationSampler sampler_;
  sf::net::ProtoMulticastReceiver<SSL_WrapperPacket> receiver_;
  sf::net::ProtoMulticastSender<sf::proto::FormationPrediction> sender_;
  sf::Prediction prediction_;
  sf::proto::FormationPrediction message_;
  std::uint64_t predictions_ = 0;
  std::uint64_t samples_without_table_ = 0;
};

int run_daemon(const PredictorOptions& options) {
  const sf::SamplerConfig config = options.model.sampler_config();
  if (options.horizon < 1 || options.horizon > 100) throw sf::app::UsageError("--horizon must be 1 to 100");
  if (options.ttl < 0 || options.ttl > 255) throw sf::app::UsageError("--ttl must be 0 to 255");
  const auto reload_period = sf::app::seconds_option("reload-interval", options.reload_interval_s);
  const auto status_period = sf::app::seconds_option("status-interval", options.status_interval_s);

  boost::asio::io_context io;
  PredictorDaemon daemon(io, options, config);
  daemon.start();
  sf::app::RepeatingTimer reload(io, reload_period, [&] { daemon.check_table(); });
  sf::app::RepeatingTimer status(io, status_period, [&] { daemon.log_status(); });
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    daemon.stop();
    reload.cancel();
    status.cancel();
    io.stop();
  });
  io.run();
  daemon.log_status();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-predictor", [&] {
    PredictorOptions o;
    po::options_description general("Options");
    general.add_options()
        ("list-states", po::bool_switch(&o.list_states),
         "print every state of --grid, one per line, and exit")
        ("table", po::value(&o.table)->default_value(o.table),
         "table file written by ssl-trainer; reloaded whenever it is replaced")
        ("prediction-address", po::value(&o.prediction_address)->default_value(o.prediction_address),
         "multicast group:port the FormationPrediction messages go to")
        ("prediction-interface", po::value(&o.prediction_interface)->default_value("", "as --interface"),
         "IPv4 address of the interface to send predictions from (127.0.0.1 when --interface all)")
        ("ttl", po::value(&o.ttl)->default_value(o.ttl), "multicast TTL of the predictions")
        ("horizon", po::value(&o.horizon)->default_value(o.horizon), "formations to predict ahead")
        ("reload-interval", po::value(&o.reload_interval_s)->default_value(o.reload_interval_s),
         "seconds between checks of the table file")
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr")
        ("receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
         "socket receive buffer (SO_RCVBUF) to request, bytes")
        ("quiet", po::bool_switch(&o.quiet), "no prediction lines on stdout")
        ("verbose", po::bool_switch(&o.verbose), "more log lines");
    sf::app::add_vision_options(general, o.network);
    sf::app::add_model_options(general, o.model);
    if (!sf::app::parse_command_line(argc, argv, general, "ssl-predictor [options]",
                                     "Predicts the opponent's next formations from the table "
                                     "ssl-trainer writes, and multicasts them.")) {
      return 0;
    }
    if (o.list_states) return list_states(o.model.parsed_grid());
    sf::app::init_logging("ssl-predictor", o.verbose);
    return run_daemon(o);
  });
}
