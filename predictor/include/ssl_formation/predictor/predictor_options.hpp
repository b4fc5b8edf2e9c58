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
  int horizon = 2;
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
  // The live field view: off unless a port is given.
  int http_port = 0;
  std::string http_address = "127.0.0.1";
  int http_max_clients = 64;
  double http_status_interval_s = 0.5;
  int http_send_buffer_bytes = 0;
  // --from-log FILE... [--output PATH]: no network; "-" or empty writes to standard output.
  std::vector<std::string> from_logs;
  std::string output;
};

// The pipeline's configuration the options describe; throws app::UsageError naming the option.
PredictionConfig prediction_config(const PredictorOptions& options);

// Each returns the exit status.
int run_daemon(const PredictorOptions& options);    // predictor_daemon.cpp
int run_from_log(const PredictorOptions& options);  // log_predictions.cpp
// Prints every state of `grid`, one per line (the paper's statesList).
int list_states(const Grid& grid);  // predictor_daemon.cpp

}  // namespace ssl_formation::predictor
