#pragma once
// ssl-evaluate's work: how good the predictions are, trained and tested through the same
// Training and PredictionPipeline the daemons run.
//   paper       the paper's §6 protocol and its table, next to the paper's own numbers
//   holdout     train on some streams, test on others: every horizon in seconds, the error in
//               millimetres and the cells of the model against persistence, constant velocity
//               and damped constant velocity, and the calibration of every probability stated
//   grid-sweep  the holdout report for several grids, with table memory and prediction time
//   as-real-log a clean recording rewritten as real match logs come (half-field packets with
//               camera id 0, no geometry) with the mess chosen, to evaluate on
//   score       predictions made elsewhere (ssl-predictor --from-log's CSV, or a team's own)
//               scored against where the robots were, beside the baselines, by game state

#include <cstdint>
#include <string>
#include <vector>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/evaluation/block_bootstrap.hpp"

namespace ssl_formation::evaluate {

struct EvaluateOptions {
  std::string mode;
  app::ModelOptions model;
  app::NetworkOptions network;  // --vision-source: the logs' raw or tracked vision
  std::string learn_during = "all";
  std::uint64_t seed = 1;
  std::uint64_t test_seed = 2;
  int train_formations = 15000;
  int test_formations = 5000;
  int tests = 5000;
  // holdout without logs: the paper's simulated opponent (paper), a simulated match with its
  // referee (match: --train-seconds of seed --seed, --test-seconds of --test-seed), or auto
  // (paper for --model paper, match for the others).
  std::string simulation = "auto";
  double train_seconds = 600.0;
  double test_seconds = 300.0;
  std::string playbook = "wings";
  double jitter_mm = 0.0;
  int cameras = 1;
  // Logs, each its own stream; --split F trains on the first F of every --train-log and tests
  // on the rest of each.
  std::vector<std::string> train_logs;
  std::vector<std::string> test_logs;
  double split = 0.0;
  // With split: the inner split that tunes (docs/tuning.md), the first split x split of each log
  // against the next split x (1 - split); the last 1 - split, which reports, is not read.
  bool tune = false;
  // holdout: every horizon (seconds) is a model of its own (step = horizon, one step ahead),
  // besides the chains of up to chain_steps steps of --step.
  std::vector<double> horizons{0.2, 0.5, 1.0, 2.0};
  int chain_steps = 3;
  double velocity_window_s = 0.1;
  double recalibration_half_life_s = OnlineCalibrationSettings{}.half_life_s;  // 0: off
  // holdout: every team's table under the model's rows, for the sections of its step.
  std::string prior_table;
  // The model is scored on its table as ssl-trainer would save it within this size (0: no
  // bound).
  double max_table_mb = default_max_table_mb;
  std::string output_dir;  // -o/--output; none: no CSV files
  // Files of the names written may be replaced (--overwrite); otherwise one that exists is
  // refused before anything is written.
  bool overwrite = false;
  // holdout, grid-sweep: every scored robot as a CSV line (ev::ScoredSample); none without it.
  std::string write_samples;
  // holdout, grid-sweep: the resamples of the block bootstrap behind every interval (0: none)
  // and its blocks of data time (evaluation/block_bootstrap.hpp).
  int bootstrap = evaluation::BootstrapConfig{}.resamples;
  double bootstrap_block_s = evaluation::BootstrapConfig{}.block_s;
  std::vector<std::string> grids{"3x2", "6x4", "9x6", "12x9"};
  // as-real-log: the recording, the log written and the mess (parse_real_log_mess); `seed`
  // places its ghosts and draws its noise.
  std::string from_log;
  std::string write_log;
  std::string mess = "none";
  // holdout, score: a page to open (html_report.hpp); none without it. `command_line` is how
  // the program was run, for the page to say.
  std::string report;
  std::string command_line;
  // score: the recorded match (--from-log) and the predictions made for it (ssl-predictor
  // --from-log's CSV).
  std::string log;
  std::string predictions;
};

// "0.2,0.5,1,2" -> {0.2, 0.5, 1, 2}; throws app::UsageError naming --horizons.
std::vector<double> parse_horizons(const std::string& text);

// Each prints its report, writes its CSV files into output_dir and returns the exit status.
int run_paper(const EvaluateOptions& options);
int run_holdout(const EvaluateOptions& options, const std::vector<std::string>& grids);
int run_as_real_log(const EvaluateOptions& options);
int run_score(const EvaluateOptions& options);

}  // namespace ssl_formation::evaluate
