// ssl-predictor: samples the opponent's formations from the vision feed, predicts the next ones
// from the trainer's table and multicasts them as FormationPrediction messages, with one
// readable line per prediction on stdout. --list-states prints the state space (the paper's
// statesList). --http-port serves a live view of the field, the robots and the predictions.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <iostream>
#include <optional>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/net/vision_receiver.hpp"
#include "ssl_formation/prediction_message.hpp"
#include "ssl_formation/sampler.hpp"
#include "ssl_formation/state.hpp"
#include "table_watcher.hpp"
#include "web/field_view_json.hpp"
#include "web/field_view_server.hpp"
#include "web/team_robots.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;
namespace web = ssl_formation::predictor::web;

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
  // The live field view: off unless a port is given.
  int http_port = 0;
  std::string http_address = "127.0.0.1";
  int http_max_clients = 64;
  double http_status_interval_s = 0.5;
  int http_send_buffer_bytes = 0;
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
                options.ttl),
        // Our robots are kept as long as the sampler keeps a camera live.
        ours_(other_team(config.opponent_color),
              std::max(config.camera_timeout_s, 1.5 * config.step_s),
              config.clock_reset_s > 0.0 ? config.clock_reset_s : 2.0 * config.step_s) {
    // The per-packet buffers, allocated together now rather than wherever the first packet
    // leaves them: every page the hot path touches costs after 16 ms asleep.
    robot_states_.reserve(16);
    prediction_.steps.resize(static_cast<std::size_t>(options.horizon));
    for (sf::PredictedStep& step : prediction_.steps) step.robots.reserve(16);
    datagram_.reserve(2048);
    if (options.http_port != 0) {
      web::FieldViewOptions web_options;
      web_options.address = options.http_address;
      web_options.port = static_cast<std::uint16_t>(options.http_port);
      web_options.max_clients = static_cast<std::size_t>(options.http_max_clients);
      web_options.send_buffer_bytes = options.http_send_buffer_bytes;
      web_.emplace(io, web_options);
    }
  }

  void start() {
    sender_.open();
    if (web_) {
      web_->start();  // before the receiver, so a busy port fails before anything else runs
      spdlog::info("field view: open {}", web_->url());
    }
    receiver_.start([this](const sf::VisionFrame& frame, const sf::net::udp::endpoint&) {
      if (web_) {
        // Only the field view shows these; a clock read is not free in a cold process either.
        last_packet_ = std::chrono::steady_clock::now();
        // Ours first, so that a prediction this packet completes shows them as of this packet.
        if (frame.has_detection) ours_.add(frame.detection);
      }
      sampler_.add(frame);
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

  void stop() {
    receiver_.stop();
    if (web_) web_->stop();
  }

  bool serving_web() const { return web_.has_value(); }

  // The field view's status message: stream rates, the table and the viewers.
  void publish_status() {
    if (!web_) return;
    const auto now = std::chrono::steady_clock::now();
    const auto& net = receiver_.counters();
    const std::uint64_t packets = net.datagrams.load();
    web::FieldViewStatus status;
    status.setup = view_setup();
    status.packets = packets;
    if (last_rate_time_) {
      const double elapsed = std::chrono::duration<double>(now - *last_rate_time_).count();
      if (elapsed > 0.0)
        status.packets_per_s = static_cast<double>(packets - last_rate_packets_) / elapsed;
    }
    last_rate_time_ = now;
    last_rate_packets_ = packets;
    if (last_packet_)
      status.since_packet_s = std::chrono::duration<double>(now - *last_packet_).count();
    status.parse_errors = net.parse_errors.load();
    status.kernel_drops = net.kernel_drops.load();
    status.formations = sampler_.counters().samples;
    status.predictions = predictions_;
    if (watcher_.table()) {
      const sf::StoredTable& stored = *watcher_.table();
      status.table_loaded = true;
      status.table_transitions = stored.table.transitions();
      status.table_formations = stored.metadata.samples;
      status.table_states_seen = stored.table.rows_seen();
    }
    status.table_reloads = watcher_.reloads();
    status.table_loaded_unix_ms = table_loaded_unix_ms_;
    status.table_error = table_error_;
    const web::FieldViewCounters counters = web_->counters();
    status.clients = counters.live_clients;
    status.dropped_frames = counters.dropped_frames;
    status.ours = ours_.current();
    web_->broadcast(web::MessageKind::status, web::status_json(status));
  }

  void check_table() {
    switch (watcher_.poll()) {
      case sf::predictor::TableWatcher::Change::loaded: {
        const sf::StoredTable& stored = *watcher_.table();
        spdlog::info(
            "loaded table {} (reload {}): {} transitions from {} formations, {} states seen",
            options_.table, watcher_.reloads(), stored.table.transitions(), stored.metadata.samples,
            stored.table.rows_seen());
        table_loaded_unix_ms_ = std::chrono::duration_cast<std::chrono::milliseconds>(
                                    std::chrono::system_clock::now().time_since_epoch())
                                    .count();
        table_error_.clear();
        if (stored.metadata.step_s != config_.step_s) {
          spdlog::warn("the table was trained with --step {} but this predictor samples every {} s",
                       stored.metadata.step_s, config_.step_s);
        }
        break;
      }
      case sf::predictor::TableWatcher::Change::failed:
        table_error_ = watcher_.last_error();
        spdlog::error("{}; {}", watcher_.last_error(),
                      watcher_.table() ? "keeping the table loaded before"
                                       : "still waiting for a valid table");
        break;
      case sf::predictor::TableWatcher::Change::none:
        break;
    }
  }

  void log_status() {
    const auto& net = receiver_.counters();
    const auto& c = sampler_.counters();
    spdlog::info(
        "status: packets={} parse_errors={} kernel_drops={} formations={} predictions={} "
        "sent={} table_reloads={} | {}",
        net.datagrams.load(), net.parse_errors.load(), net.kernel_drops.load(), c.samples,
        predictions_, sender_.sent(), watcher_.reloads(), sf::describe_rejections(c));
    // One warning per kind of bad input as it appears, so a hostile or broken feed is visible.
    for (const std::string& line : sf::new_rejections(reported_, c))
      spdlog::warn("input: {}", line);
    reported_ = c;
    if (web_) {
      const web::FieldViewCounters w = web_->counters();
      spdlog::info(
          "field view: viewers={} connections={} refused={} dropped_frames={} stalled={} "
          "bad_requests={}",
          w.live_clients, w.connections, w.refused, w.dropped_frames, w.stalled_clients,
          w.bad_requests);
    }
  }

 private:
  void on_sample(const sf::FormationSample& sample) {
    if (!watcher_.table()) {
      ++samples_without_table_;
      return;
    }
    const sf::StoredTable& stored = *watcher_.table();
    // The hot path, from the sample to the datagram: no allocation once warmed up, and the wire
    // format written directly (see encode_prediction).
    robot_states_.clear();
    for (const sf::FormationRobot& robot : sample.formation.robots) {
      robot_states_.push_back({robot.robot_id, robot.state});
    }
    sf::predict(stored.table, robot_states_, options_.horizon, prediction_);
    const sf::PredictionContext context =
        sf::prediction_context(stored.table, config_, sampler_.field());
    sf::encode_prediction(sample.formation, prediction_, context, datagram_);
    sender_.send(std::as_bytes(std::span(datagram_.data(), datagram_.size())));
    ++predictions_;
    if (!options_.quiet)
      std::cout << sf::describe_prediction(sample.formation, prediction_) << '\n' << std::flush;
    // After the multicast: the view never delays the predictions.
    if (web_) {
      sf::fill_prediction_message(sample.formation, prediction_, context, message_);
      web_->broadcast(web::MessageKind::prediction,
                      web::prediction_json(message_, view_setup(), ours_.current()));
    }
  }

  static sf::TeamColor other_team(sf::TeamColor color) {
    return color == sf::TeamColor::yellow ? sf::TeamColor::blue : sf::TeamColor::yellow;
  }

  web::FieldViewSetup view_setup() const {
    return web::FieldViewSetup{sampler_.field(), config_.grid, config_.opponent_attacks,
                               config_.opponent_color};
  }

  const PredictorOptions& options_;
  sf::SamplerConfig config_;
  sf::predictor::TableWatcher watcher_;
  sf::FormationSampler sampler_;
  sf::net::VisionReceiver receiver_;
  sf::net::MulticastSender sender_;  // FormationPrediction datagrams, encoded by encode_prediction
  sf::Prediction prediction_;
  std::vector<sf::RobotStateById> robot_states_;
  std::string datagram_;
  sf::proto::FormationPrediction message_;  // for the field view only
  std::uint64_t predictions_ = 0;
  sf::SamplerCounters reported_;  // counters at the last status line
  std::uint64_t samples_without_table_ = 0;
  // The field view (--http-port), and what only it needs.
  web::TeamRobots ours_;
  std::optional<web::FieldViewServer> web_;
  std::optional<std::chrono::steady_clock::time_point> last_packet_;
  std::optional<std::chrono::steady_clock::time_point> last_rate_time_;
  std::uint64_t last_rate_packets_ = 0;
  std::optional<std::int64_t> table_loaded_unix_ms_;
  std::string table_error_;
};

int run_daemon(const PredictorOptions& options) {
  const sf::SamplerConfig config = options.model.sampler_config();
  if (options.horizon < 1 || options.horizon > 100)
    throw sf::app::UsageError("--horizon must be 1 to 100");
  if (options.ttl < 0 || options.ttl > 255) throw sf::app::UsageError("--ttl must be 0 to 255");
  const auto reload_period = sf::app::seconds_option("reload-interval", options.reload_interval_s);
  const auto status_period = sf::app::seconds_option("status-interval", options.status_interval_s);
  if (options.http_port < 0 || options.http_port > 65535)
    throw sf::app::UsageError("--http-port must be 0 to 65535");
  if (options.http_max_clients < 1 || options.http_max_clients > 10000) {
    throw sf::app::UsageError("--http-max-clients must be 1 to 10000");
  }
  if (options.http_send_buffer_bytes < 0)
    throw sf::app::UsageError("--http-send-buffer must be 0 or more");
  const auto web_status_period =
      sf::app::seconds_option("http-status-interval", options.http_status_interval_s);

  boost::asio::io_context io;
  PredictorDaemon daemon(io, options, config);
  // Signals are caught from before the first log line on, so a SIGTERM right after start-up
  // stops the daemon cleanly; the handler runs inside io.run(), after everything below exists.
  std::optional<sf::app::RepeatingTimer> reload;
  std::optional<sf::app::RepeatingTimer> status;
  std::optional<sf::app::RepeatingTimer> web_status;
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    daemon.stop();
    reload->cancel();
    status->cancel();
    if (web_status) web_status->cancel();
    io.stop();
  });
  daemon.start();
  reload.emplace(io, reload_period, [&] { daemon.check_table(); });
  status.emplace(io, status_period, [&] { daemon.log_status(); });
  if (daemon.serving_web())
    web_status.emplace(io, web_status_period, [&] { daemon.publish_status(); });
  io.run();
  daemon.log_status();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-predictor", [&] {
    PredictorOptions o;
    po::options_description general("Options");
    general.add_options()("list-states", po::bool_switch(&o.list_states),
                          "print every state of --grid, one per line, and exit")(
        "table", po::value(&o.table)->default_value(o.table),
        "table file written by ssl-trainer; reloaded whenever it is replaced")(
        "prediction-address", po::value(&o.prediction_address)->default_value(o.prediction_address),
        "multicast group:port the FormationPrediction messages go to")(
        "prediction-interface",
        po::value(&o.prediction_interface)->default_value("", "as --interface"),
        "IPv4 address of the interface to send predictions from (127.0.0.1 when --interface all)")(
        "ttl", po::value(&o.ttl)->default_value(o.ttl), "multicast TTL of the predictions")(
        "horizon", po::value(&o.horizon)->default_value(o.horizon), "formations to predict ahead")(
        "reload-interval", po::value(&o.reload_interval_s)->default_value(o.reload_interval_s),
        "seconds between checks of the table file")(
        "status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
        "seconds between status lines on stderr")(
        "receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
        "socket receive buffer (SO_RCVBUF) to request, bytes")("quiet", po::bool_switch(&o.quiet),
                                                               "no prediction lines on stdout")(
        "http-port", po::value(&o.http_port)->default_value(o.http_port),
        "TCP port of the live field view (http://ADDRESS:PORT/); 0 = off")(
        "http-address", po::value(&o.http_address)->default_value(o.http_address),
        "address the field view listens on (keep 127.0.0.1 unless others must see it)")(
        "http-max-clients", po::value(&o.http_max_clients)->default_value(o.http_max_clients),
        "connections the field view serves at once (page loads and live views); more are refused")(
        "http-status-interval",
        po::value(&o.http_status_interval_s)->default_value(o.http_status_interval_s),
        "seconds between status messages to the field view")(
        "http-send-buffer",
        po::value(&o.http_send_buffer_bytes)->default_value(o.http_send_buffer_bytes),
        "socket send buffer (SO_SNDBUF) per field view connection, bytes; 0 = the system's")(
        "verbose", po::bool_switch(&o.verbose), "more log lines");
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
