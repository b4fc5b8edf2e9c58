// ssl-predictor's daemon: the vision feed through the core's PredictionPipeline, each prediction
// multicast as a FormationPrediction and printed as one readable line, the table followed as the
// trainer replaces it, and the live field view (--http-port).

#include <spdlog/spdlog.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <iostream>
#include <optional>

#include "field_view_json.hpp"
#include "field_view_server.hpp"
#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/net/vision_receiver.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/predictor/predictor_options.hpp"
#include "ssl_formation/predictor/table_watcher.hpp"
#include "ssl_formation/base/state.hpp"
#include "team_robots.hpp"

namespace ssl_formation::predictor {

int list_states(const Grid& grid) {
  const StateCodec codec(grid);
  std::string out;
  for (StateIndex index = 0; index < codec.state_count(); ++index) {
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

namespace {

std::string prediction_interface(const PredictorOptions& options) {
  if (!options.prediction_interface.empty()) return options.prediction_interface;
  return options.network.interface == "all" ? std::string(app::default_interface)
                                            : options.network.interface;
}

// The daemon: vision in, predictions out.
class PredictorDaemon {
 public:
  PredictorDaemon(boost::asio::io_context& io, const PredictorOptions& options,
                  const PredictionConfig& config)
      : io_(io),
        options_(options),
        config_(config.sampler),
        watcher_(table_path(options, config.opponent ? config.opponent->opponent_team : ""),
                 config.sampler.grid),
        pipeline_(config,
                  [this](const PredictedFormation& predicted) { on_prediction(predicted); }),
        receiver_(io, app::parse_group_option("vision-address", options.network.vision_address),
                  app::parse_interface_option(options.network.interface, true),
                  options.receive_buffer_bytes),
        referee_group_(app::parse_referee_option(options.network.referee_address)),
        sender_(io, app::parse_group_option("prediction-address", options.prediction_address),
                app::parse_interface_option(prediction_interface(options), false).address,
                options.ttl),
        // Our robots are kept as long as the sampler keeps a camera live.
        ours_(other_team(config.sampler.opponent_color), config.sampler.camera_live_window_s(),
              config.sampler.clock_reset_window_s()),
        field_log_(config.sampler.field, config.sampler.use_geometry),
        warm_up_timer_(io) {
    // Allocated now rather than wherever the first packet leaves it: every page the hot path
    // touches costs after 16 ms asleep.
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
    // Raw vision, or a tracker's frames instead (never both: they would be two clocks).
    if (options_.network.tracked()) {
      tracked_.emplace(io_,
                       app::parse_group_option("tracker-address", options_.network.tracker_address),
                       app::parse_interface_option(options_.network.interface, true),
                       options_.receive_buffer_bytes);
      tracked_->start([this](const VisionFrame& frame) { on_frame(frame); });
      // The raw feed still gives the field size: the tracker's frames have none.
      receiver_.start([this](const VisionFrame& frame, const net::udp::endpoint&) {
        if (app::geometry_only(frame, geometry_)) on_frame(geometry_);
      });
    } else {
      receiver_.start(
          [this](const VisionFrame& frame, const net::udp::endpoint&) { on_frame(frame); });
    }
    match_log_.update(pipeline_.match(), pipeline_.sampler().attacks());
    // The referee on the same thread as the vision: each command applies from the next frame.
    if (referee_group_) {
      referee_.emplace(io_, *referee_group_,
                       app::parse_interface_option(options_.network.interface, true),
                       options_.receive_buffer_bytes);
      referee_->start([this](std::span<const std::byte> datagram, const net::udp::endpoint&) {
        const RefereeChange change =
            pipeline_.add_referee(net::as_text(datagram), app::steady_seconds());
        if (change.any()) ours_.set_color(other_team(pipeline_.sampler().config().opponent_color));
        if (change.teams) follow_opponent_table();
        match_log_.update(pipeline_.match(), pipeline_.sampler().attacks(), change);
      });
    }
    spdlog::info("predicting {} steps ahead; grid {}, step {} s, {} sampling; referee {}",
                 options_.horizon, config_.grid.to_string(), config_.step_s,
                 to_string(config_.sampling),
                 referee_group_ ? referee_group_->to_string() : std::string("none"));
    check_table();
    if (!watcher_.table() && options_.table_dir.empty()) {
      spdlog::info("waiting for the table {}: start ssl-trainer with --table {} (or give --table)",
                   options_.table, options_.table);
    } else if (!watcher_.table()) {
      spdlog::info("waiting for the table {}: start ssl-trainer with --table-dir {}",
                   watcher_.path().string(), options_.table_dir);
    }
  }

  void stop() {
    warm_up_timer_.cancel();
    receiver_.stop();
    if (tracked_) tracked_->stop();
    if (referee_) referee_->stop();
    if (web_) web_->stop();
  }

  bool serving_web() const { return web_.has_value(); }

  // What the ready file says once the sockets are joined and the table there at start loaded.
  std::vector<std::pair<std::string, std::string>> ready_facts() const {
    std::vector<std::pair<std::string, std::string>> facts{
        {"vision", options_.network.tracked() ? "tracked " + options_.network.tracker_address
                                              : options_.network.vision_address},
        {"interface", options_.network.interface},
        {"referee", referee_group_ ? referee_group_->to_string() : "none"},
        {"predictions", options_.prediction_address},
        {"table", watcher_.path().string()},
        // The table predictions come from: a table the model refused is not loaded.
        {"table_loaded", pipeline_.table() ? "1" : "0"}};
    if (web_) facts.emplace_back("http", web_->url());
    return facts;
  }

  // The field view's status message: stream rates, the table and the viewers.
  void publish_status() {
    if (!web_) return;
    const auto now = std::chrono::steady_clock::now();
    // The socket the vision comes in on: raw, or the tracker's.
    const auto& net =
        tracked_ ? tracked_->bytes_receiver().counters() : receiver_.counters();
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
    // The age of the last datagram on this process's own clocks: steady for the age, the wall
    // clock only to date it (never the feed's t_capture, which is the simulator's or camera's).
    const auto wall_now = std::chrono::system_clock::now();
    const auto unix_ms = [](std::chrono::system_clock::time_point t) {
      return std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count();
    };
    status.server_unix_ms = unix_ms(wall_now);
    if (last_packet_) {
      const auto age = std::max(now - *last_packet_, std::chrono::steady_clock::duration::zero());
      status.since_packet_s = std::chrono::duration<double>(age).count();
      status.last_packet_unix_ms =
          unix_ms(wall_now - std::chrono::duration_cast<std::chrono::system_clock::duration>(age));
    }
    status.parse_errors = net.parse_errors.load();
    status.kernel_drops = net.kernel_drops.load();
    status.formations = pipeline_.sampler().counters().samples;
    status.predictions = pipeline_.predictions();
    if (const auto& table = pipeline_.table()) {
      const StoredTable& stored = *table;
      status.table_loaded = true;
      status.table_transitions = stored.table.transitions();
      status.table_formations = stored.metadata.samples;
      if (stored.motion) status.table_motion_instances = stored.motion->instances();
      status.table_states_seen = stored.table.rows_seen();
    }
    status.table_reloads = watcher_.reloads();
    status.table_loaded_unix_ms = table_loaded_unix_ms_;
    status.table_error = table_error_;
    const web::FieldViewCounters counters = web_->counters();
    status.clients = counters.live_clients;
    status.dropped_frames = counters.dropped_frames;
    status.ours = ours_.current();
    status.opponent = describe(pipeline_.match().opponent(), pipeline_.sampler().attacks());
    status.game_state = std::string(to_string(pipeline_.match().game_state()));
    status.referee = describe(pipeline_.match().referee());
    status.live_score = pipeline_.live_score().horizons();
    web_->broadcast(web::MessageKind::status, web::status_json(status));
  }

  void check_table() {
    switch (watcher_.poll()) {
      case TableWatcher::Change::loaded: {
        const StoredTable& stored = *watcher_.table();
        try {
          pipeline_.set_table(watcher_.table());
        } catch (const std::invalid_argument& error) {
          // A table this model cannot use (a version-1 table for --model motion): keep
          // predicting with the one we have, and say why.
          table_error_ = watcher_.path().string() + ": " + error.what();
          spdlog::error("{}", table_error_);
          break;
        }
        spdlog::info(
            "loaded table {} (reload {}): {} transitions from {} formations, {} states seen",
            watcher_.path().string(), watcher_.reloads(), stored.table.transitions(),
            stored.metadata.samples,
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
      case TableWatcher::Change::failed:
        table_error_ = watcher_.last_error();
        spdlog::error("{}; {}", watcher_.last_error(),
                      watcher_.table() ? "keeping the table loaded before"
                                       : "still waiting for a valid table");
        break;
      case TableWatcher::Change::none:
        break;
    }
  }

  // --table-dir: the current opponent's table, loaded as soon as the referee names another.
  void follow_opponent_table() {
    const std::filesystem::path wanted = table_path(options_, pipeline_.match().opponent().name);
    if (wanted == watcher_.path()) return;
    spdlog::info("opponent '{}': predicting from {}", pipeline_.match().opponent().name,
                 wanted.string());
    watcher_ = TableWatcher(wanted, config_.grid);
    pipeline_.set_table(nullptr);
    table_error_.clear();
    check_table();
    if (!watcher_.table()) spdlog::info("no table for this opponent yet: waiting for {}", wanted.string());
  }

  static std::filesystem::path table_path(const PredictorOptions& options,
                                          const std::string& opponent) {
    if (options.table_dir.empty()) return options.table;
    return std::filesystem::path(options.table_dir) / team_table_file_name(opponent);
  }

  void log_status() {
    const auto& c = pipeline_.sampler().counters();
    spdlog::info(
        "status: {}{} formations={} predictions={} sent={} warm_ups={} table_reloads={}{} "
        "attacks={} {} | {}",
        app::describe_reception(receiver_), app::describe_tracked(tracked_ ? &*tracked_ : nullptr),
        c.samples, pipeline_.predictions(), sender_.sent(), warm_ups_, watcher_.reloads(),
        describe_for_status(pipeline_.live_score()),
        app::describe_attacks(pipeline_.sampler().attacks(),
                              pipeline_.match().opponent().attacks_because),
        app::describe_referee_counts(pipeline_.match()), describe_rejections(c));
    // One warning per kind of bad input as it appears, so a hostile or broken feed is visible.
    for (const std::string& line : new_rejections(reported_, c)) spdlog::warn("input: {}", line);
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
  void on_frame(const VisionFrame& frame) {
    if (web_) {
      // Only the field view shows these; a clock read is not free in a cold process either.
      last_packet_ = std::chrono::steady_clock::now();
      // Ours first, so that a prediction this packet completes shows them as of this packet.
      if (frame.has_detection) ours_.add(frame.detection);
    }
    pipeline_.add(frame);
    if (frame.has_geometry) field_log_.update(pipeline_.sampler().field());
    if (pipeline_.sampler().config().infer_attacks) {
      match_log_.update(pipeline_.match(), pipeline_.sampler().attacks());
    }
  }

  // The hot path, from the prediction to the datagram: no allocation once warmed up, and the
  // wire format written directly (see encode_prediction).
  void on_prediction(const PredictedFormation& predicted) {
    encode_prediction(predicted.formation(), predicted.prediction, predicted.context, datagram_);
    sender_.send(std::as_bytes(std::span(datagram_.data(), datagram_.size())));
    schedule_warm_up();
    if (!options_.quiet) {
      std::cout << describe_prediction(predicted.formation(), predicted.prediction,
                                       predicted.context)
                << '\n'
                << std::flush;
    }
    // After the multicast: the view never delays the predictions.
    if (web_) {
      fill_prediction_message(predicted.formation(), predicted.prediction, predicted.context,
                              message_);
      web_->broadcast(web::MessageKind::prediction,
                      web::prediction_json(message_, view_setup(), ours_.current()));
    }
  }

  // A feed of one frame every ~16 ms leaves the predictor asleep long enough for other work to
  // push its table, histories and code out of the caches, which cost more than the prediction
  // itself (bench-e2e: 3 us warm, about 38 us cold). So shortly before the next frame is due, at
  // the pace of the last ones, the last prediction is run and encoded again, sending nothing.
  // Faster feeds keep the caches warm by themselves and are left alone.
  void schedule_warm_up() {
    if (!(options_.warm_up_lead_ms > 0.0)) return;
    const auto now = std::chrono::steady_clock::now();
    if (last_prediction_at_) {
      const double gap_ms =
          std::chrono::duration<double, std::milli>(now - *last_prediction_at_).count();
      // A gap of seconds (a pause in the feed) says nothing about the pace.
      if (gap_ms < 1000.0) {
        frame_period_ms_ = frame_period_ms_ ? 0.9 * *frame_period_ms_ + 0.1 * gap_ms : gap_ms;
      }
    }
    last_prediction_at_ = now;
    if (!frame_period_ms_ || *frame_period_ms_ < 3.0 * options_.warm_up_lead_ms) return;
    warm_up_timer_.expires_at(now + std::chrono::microseconds(static_cast<std::int64_t>(
                                        (*frame_period_ms_ - options_.warm_up_lead_ms) * 1000.0)));
    warm_up_timer_.async_wait([this](const boost::system::error_code& error) {
      if (error) return;  // cancelled: a frame came first, or the daemon stops
      pipeline_.rehearse([this](const PredictedFormation& predicted) {
        encode_prediction(predicted.formation(), predicted.prediction, predicted.context,
                          datagram_);
      });
      ++warm_ups_;
    });
  }

  static TeamColor other_team(TeamColor color) {
    return color == TeamColor::yellow ? TeamColor::blue : TeamColor::yellow;
  }

  web::FieldViewSetup view_setup() const {
    // The opponent in use: the referee's or inferred side (the configured one until then).
    const SamplerConfig& now = pipeline_.sampler().config();
    return web::FieldViewSetup{pipeline_.sampler().field(), config_.grid,
                               pipeline_.sampler().attacks().value_or(now.opponent_attacks),
                               now.opponent_color};
  }

  boost::asio::io_context& io_;
  const PredictorOptions& options_;
  SamplerConfig config_;
  TableWatcher watcher_;
  PredictionPipeline pipeline_;
  net::VisionReceiver receiver_;
  std::optional<net::TrackedVisionReceiver> tracked_;  // --vision-source tracked
  VisionFrame geometry_;  // tracked: the raw feed's geometry alone
  std::optional<net::MulticastEndpoint> referee_group_;  // none: --referee-address none
  std::optional<net::MulticastReceiver> referee_;
  net::MulticastSender sender_;  // FormationPrediction datagrams, encoded by encode_prediction
  std::string datagram_;
  proto::FormationPrediction message_;  // for the field view only
  SamplerCounters reported_;            // counters at the last status line
  // The field view (--http-port), and what only it needs.
  web::TeamRobots ours_;
  app::FieldSizeLog field_log_;
  app::MatchLog match_log_;
  std::optional<web::FieldViewServer> web_;
  std::optional<std::chrono::steady_clock::time_point> last_packet_;
  std::optional<std::chrono::steady_clock::time_point> last_rate_time_;
  std::uint64_t last_rate_packets_ = 0;
  std::optional<std::int64_t> table_loaded_unix_ms_;
  // The warm-up before each expected frame (schedule_warm_up).
  boost::asio::steady_timer warm_up_timer_;
  std::optional<std::chrono::steady_clock::time_point> last_prediction_at_;
  std::optional<double> frame_period_ms_;
  std::uint64_t warm_ups_ = 0;
  std::string table_error_;
};

}  // namespace

PredictionConfig prediction_config(const PredictorOptions& options) {
  PredictionConfig config;
  config.sampler = options.model.sampler_config();
  config.model = options.model.parsed_model();
  if (options.horizon < 1 || options.horizon > PredictionConfig::max_horizon) {
    throw app::UsageError("--horizon must be 1 to " +
                          std::to_string(PredictionConfig::max_horizon));
  }
  config.horizon = options.horizon;
  config.recalibration = app::recalibration_settings(options.recalibration_half_life_s);
  config.opponent = options.model.opponent_choice();
  if (options.model.opponent_team == "all") {
    throw app::UsageError("--opponent-team all is for ssl-trainer --from-log: name the opponent");
  }
  return config;
}

int run_daemon(const PredictorOptions& options) {
  const PredictionConfig config = prediction_config(options);
  if (options.ttl < 0 || options.ttl > 255) throw app::UsageError("--ttl must be 0 to 255");
  const auto reload_period = app::seconds_option("reload-interval", options.reload_interval_s);
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);
  if (options.http_port < 0 || options.http_port > 65535)
    throw app::UsageError("--http-port must be 0 to 65535");
  if (options.http_max_clients < 1 || options.http_max_clients > 10000) {
    throw app::UsageError("--http-max-clients must be 1 to 10000");
  }
  if (options.http_send_buffer_bytes < 0)
    throw app::UsageError("--http-send-buffer must be 0 or more");
  if (!(options.warm_up_lead_ms >= 0.0 && options.warm_up_lead_ms <= 100.0))
    throw app::UsageError("--warm-up-lead must be 0 to 100 milliseconds");
  const auto web_status_period =
      app::seconds_option("http-status-interval", options.http_status_interval_s);

  boost::asio::io_context io;
  PredictorDaemon daemon(io, options, config);
  // Signals are caught from before the first log line on, so a SIGTERM right after start-up
  // stops the daemon cleanly; the handler runs inside io.run(), after everything below exists.
  std::optional<app::RepeatingTimer> reload;
  std::optional<app::RepeatingTimer> status;
  std::optional<app::RepeatingTimer> web_status;
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    daemon.stop();
    reload->cancel();
    status->cancel();
    if (web_status) web_status->cancel();
    io.stop();
  });
  daemon.start();
  app::ReadyFile ready(options.daemon.ready_file);
  ready.mark_ready("ssl-predictor", daemon.ready_facts());
  reload.emplace(io, reload_period, [&] { daemon.check_table(); });
  status.emplace(io, status_period, [&] { daemon.log_status(); });
  if (daemon.serving_web())
    web_status.emplace(io, web_status_period, [&] { daemon.publish_status(); });
  io.run();
  daemon.log_status();
  return 0;
}

}  // namespace ssl_formation::predictor
