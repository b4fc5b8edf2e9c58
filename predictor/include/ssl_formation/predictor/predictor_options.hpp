#pragma once
// ssl-predictor's options and its three modes: the live daemon (vision in, predictions out on
// multicast), --from-log (logs in, predictions out as CSV) and --list-states. main.cpp parses
// the options; the modes run the core's PredictionPipeline.

#include <string>
#include <vector>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"

namespace ssl_formation::predictor {

struct PredictorOptions {
  app::ModelOptions model;
  app::NetworkOptions network;
  app::DaemonOptions daemon;
  std::string table = app::default_table;
  // One table file per opponent team in this folder instead of --table: the current opponent's.
  std::string table_dir;
  std::string prediction_address = app::default_prediction_address;
  std::string prediction_interface;  // empty: as --interface (127.0.0.1 when that is 'all')
  int ttl = net::kDefaultMulticastTtl;
  // How far ahead to predict, in seconds (--horizons), and the steps that makes once the step is
  // known (settle_predictor_options).
  std::string horizons = "auto";
  int horizon = 2;
  // --horizon N, the old spelling in steps; app::not_given without it.
  int old_horizon_steps = app::not_given;
  double recalibration_half_life_s = OnlineCalibrationSettings{}.half_life_s;  // 0: off
  std::string prior_table;  // --prior-table: every team's table; empty: none
  double reload_interval_s = 0.5;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = net::kDefaultReceiveBufferBytes;
  bool quiet = false;              // no prediction lines on stdout at all
  bool print_predictions = false;  // every prediction's full line, not one summary a second
  // Milliseconds before the next frame is due (from the last frames' pace) at which the
  // predictor rehearses its last prediction to warm its caches; 0 = never.
  double warm_up_lead_ms = 1.5;
  bool list_states = false;
  bool verbose = false;
  // The live field view: on default_http_port, or another free port when that one is taken;
  // a port given is that port; 0: off.
  static constexpr int default_http_port = 8080;
  static constexpr int http_port_default = -1;  // default_http_port, or a free one
  int http_port = http_port_default;
  std::string http_address = "127.0.0.1";
  int http_max_clients = 64;
  double http_status_interval_s = 0.5;
  int http_send_buffer_bytes = 0;
  // --from-log FILE... [--output PATH]: no network; "-" or empty writes to standard output.
  std::vector<std::string> from_logs;
  std::string output;
  bool overwrite = false;
};

// What the options leave open once parsed: the grid, step and model from an existing --table,
// the steps --horizons makes at that step, and an output that may be written. Throws
// app::UsageError.
void settle_predictor_options(PredictorOptions& options);

// The pipeline's configuration the options describe; throws app::UsageError naming the option.
PredictionConfig prediction_config(const PredictorOptions& options);

// Each returns the exit status.
int run_daemon(const PredictorOptions& options);    // predictor_daemon.cpp
int run_from_log(const PredictorOptions& options);  // log_predictions.cpp
// Prints every state of `grid`, one per line (the paper's statesList).
int list_states(const Grid& grid);  // predictor_daemon.cpp

}  // namespace ssl_formation::predictor
