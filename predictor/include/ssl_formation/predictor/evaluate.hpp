#pragma once
// ssl-evaluate's work: how good the predictions are, trained and tested through the same
// Training and PredictionPipeline the daemons run.
//   paper       the paper's §6 protocol and its table, next to the paper's own numbers
//   holdout     train on one stream, test on another: model against persistence and constant
//               velocity, per horizon, and the calibration of the confidence
//   grid-sweep  the holdout report for several grids, with table memory and prediction time

#include <cstdint>
#include <string>
#include <vector>

#include "ssl_formation/app/options.hpp"

namespace ssl_formation::evaluate {

struct EvaluateOptions {
  std::string mode;
  app::ModelOptions model;
  std::uint64_t seed = 1;
  std::uint64_t test_seed = 2;
  int train_formations = 15000;
  int test_formations = 5000;
  int tests = 5000;
  double jitter_mm = 0.0;
  int cameras = 1;
  std::string train_log;
  std::string test_log;
  double split = 0.0;
  std::string output_dir = ".";
  std::vector<std::string> grids{"3x2", "6x4", "9x6", "12x9"};
};

// Each prints its report, writes its CSV files into output_dir and returns the exit status.
int run_paper(const EvaluateOptions& options);
int run_holdout(const EvaluateOptions& options, const std::vector<std::string>& grids);

}  // namespace ssl_formation::evaluate
