// ssl-predictor's daemon from its options: the prediction's configuration, --list-states, and
// run_daemon, which wires a PredictorDaemon to the network, timers and signals.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <iostream>

#include "ssl_formation/base/state.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/predictor/predictor_daemon.hpp"

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

PredictionConfig prediction_config(const PredictorOptions& options) {
  PredictionConfig config;
  config.sampler = options.model.sampler_config();
  config.model = options.model.parsed_model();
  const ModelDescription& model = describe(config.model);
  if (model.learns && !model.keeps_table) {
    throw app::UsageError("--model " + std::string(model.name) +
                          " fits its damping on a training part, which only ssl-evaluate has: "
                          "compare it there; ssl-predictor runs paper, motion, persistence, "
                          "constant-velocity and constant-acceleration");
  }
  if (options.horizon < 1 || options.horizon > PredictionConfig::max_horizon) {
    throw app::UsageError("--horizons must be 1 to " +
                          std::to_string(PredictionConfig::max_horizon) + " steps");
  }
  config.horizon = options.horizon;
  config.recalibration = app::recalibration_settings(options.recalibration_half_life_s);
  config.opponent = options.model.opponent_choice();
  config.tracked_vision = options.network.tracked();
  if (options.model.opponent_team == "all") {
    throw app::UsageError("--opponent-team all is for ssl-trainer --from-log: name the opponent");
  }
  if (!options.prior_table.empty() && !describe(config.model).takes_prior_table) {
    throw app::UsageError("--prior-table is the motion model's prior: use it with --model motion");
  }
  config.prior_table = app::loaded_prior_table(options.prior_table, config.sampler.step_s);
  return config;
}

int run_daemon(const PredictorOptions& options) {
  const PredictionConfig config = prediction_config(options);
  if (options.ttl < 0 || options.ttl > 255) throw app::UsageError("--ttl must be 0 to 255");
  const auto reload_period = app::seconds_option("reload-interval", options.reload_interval_s);
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);
  if ((options.http_port < 0 && options.http_port != PredictorOptions::http_port_default) ||
      options.http_port > 65535)
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
  const net::LiveFeeds feeds = app::live_feeds(options.network, options.receive_buffer_bytes);

  boost::asio::io_context io;
  const app::SystemClock clock;
  MulticastPredictionOutput output(io, options);
  PredictorDaemon daemon(io, options, config, clock, output);
  net::LiveMatchEvents events(io, feeds, [&clock] { return clock.steady_s(); });
  // Signals are caught from before the first log line on, so a SIGTERM right after start-up
  // stops the daemon cleanly; the handler runs inside io.run(), after everything below exists.
  std::optional<app::RepeatingTimer> reload;
  std::optional<app::RepeatingTimer> status;
  std::optional<app::RepeatingTimer> web_status;
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    events.stop();
    daemon.stop();
    reload->cancel();
    status->cancel();
    if (web_status) web_status->cancel();
    io.stop();
  });
  output.open();
  daemon.start();
  events.start(daemon);
  app::ReadyFile ready(options.daemon.ready_file);
  ready.mark_ready("ssl-predictor", daemon.ready_facts());
  reload.emplace(io, reload_period, [&] { daemon.check_table(); });
  status.emplace(io, status_period, [&] { daemon.log_status(&events); });
  if (daemon.serving_web()) {
    web_status.emplace(io, web_status_period, [&] { daemon.publish_status(&events); });
    // A page that just connected is told at once that it is watching, not up to a period later
    // by a status that still counts the viewers before it.
    daemon.when_viewer_joins([&] { daemon.publish_status(&events); });
  }
  io.run();
  daemon.log_status(&events, app::StatusMoment::at_stop);
  return 0;
}

}  // namespace ssl_formation::predictor
