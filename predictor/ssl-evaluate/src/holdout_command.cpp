// ssl-evaluate holdout and grid-sweep: train on one part, test on another, against the baselines.
#include "evaluate_internal.hpp"

namespace ssl_formation::evaluate {

using namespace detail;

std::vector<double> parse_horizons(const std::string& text) {
  std::vector<double> horizons;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    double value = 0.0;
    const auto [rest, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || error != std::errc() || rest != item.data() + item.size() ||
        !(value > 0.0) || value > 600.0) {
      throw app::UsageError(
          "--horizons takes positive seconds separated by commas (e.g. "
          "0.2,0.5,1,2), not '" +
          text + "'");
    }
    horizons.push_back(value);
    begin = end + 1;
  }
  return horizons;
}

int run_holdout(const EvaluateOptions& options, const std::vector<std::string>& grids) {
  if (options.chain_steps < 1 || options.chain_steps > 10) {
    throw app::UsageError("--chain-steps must be 1 to 10");
  }
  if (!(options.velocity_window_s > 0.0)) {
    throw app::UsageError("--velocity-window must be a positive number of seconds");
  }
  if (!(options.train_seconds > 0.0) || !(options.test_seconds > 0.0)) {
    throw app::UsageError("--train-seconds and --test-seconds must be positive");
  }
  const SamplerConfig base = options.model.sampler_config();
  (void)app::parsed_learn_during(options.learn_during);
  std::string simulation = options.simulation;
  if (simulation == "auto") {
    simulation = describe(options.model.parsed_model()).needs_every_frame ? "match" : "paper";
  }
  if (simulation != "paper" && simulation != "match") {
    throw app::UsageError("--simulation must be auto, paper or match, not '" + options.simulation +
                          "'");
  }
  // Before any work: a path it cannot write stops it.
  SampleFile samples(options.write_samples,
                     describe(options.model.parsed_model()).has_pooled_ablation);
  check_report_path(options);
  if (!options.report.empty() && grids.size() > 1) {
    throw app::UsageError("--report is for holdout (one grid), not grid-sweep");
  }
  const auto [train, test] = holdout_streams(options, simulation);
  const std::string prefix = grids.size() > 1 ? "grid-sweep-" : "holdout-";
  ReportFiles files(options, prefix);
  CsvFile& accuracy = files.accuracy;
  CsvFile& calibration = files.calibration;
  CsvFile& reliability = files.reliability;
  const std::shared_ptr<const MotionTable> prior =
      app::loaded_prior_table(options.prior_table, options.model.step());
  std::vector<GridReport> reports;
  for (const std::string& grid : grids) {
    reports.push_back(holdout_for_grid(options, grid, train, test, prior, samples));
    print_holdout(reports.back(), base, options);
    write_holdout_csv(accuracy, calibration, reliability, reports.back());
    write_report(options, "ssl-formation: held-out evaluation, the predictor's steps",
                 reports.back().grid, reports.back().sections.back(), reports.back().chain_samples);
    samples.check();
    std::printf("\n");
  }
  if (grids.size() > 1) {
    CsvFile sweep(options, "grid-sweep.csv");
    sweep << "grid,states,transitions,table_memory_bytes,prediction_us,model_cell_accuracy_h1,"
             "persistence_cell_accuracy_h1,constant_velocity_cell_accuracy_h1,"
             "damped_constant_velocity_cell_accuracy_h1,model_mean_error_mm_h1,"
             "model_mean_error_mm_h1_ci_low,model_mean_error_mm_h1_ci_high\n";
    std::printf("Grid sweep (one step of --step)\n%-6s %12s %12s %14s %14s %12s %12s %12s\n",
                "grid", "states", "transitions", "table memory", "predict 2 (us)", "model cell",
                "persist cell", "const-v cell");
    for (const GridReport& r : reports) {
      const ev::PositionEvaluation& chains = r.sections.back().evaluation;
      const ev::HorizonScore& h1 = chains.all().front();
      const auto cell = [&](ModelKind kind) {
        const auto it = std::find(chains.methods.begin() + 1, chains.methods.end(), kind);
        if (it == chains.methods.end()) return 0.0;
        return h1.methods[static_cast<std::size_t>(it - chains.methods.begin())]
            .cells.cell_accuracy();
      };
      const StateCodec codec(r.grid);
      std::printf("%-6s %12u %12llu %11.1f KiB %14.3f %11.2f%% %11.2f%% %11.2f%%\n",
                  r.grid.to_string().c_str(), codec.state_count(),
                  static_cast<unsigned long long>(chains.transitions),
                  static_cast<double>(chains.table_memory_bytes) / 1024.0, r.prediction_us,
                  100 * h1.methods[0].cells.cell_accuracy(), 100 * cell(ModelKind::persistence),
                  100 * cell(ModelKind::constant_velocity));
      sweep << r.grid.to_string() << ',' << codec.state_count() << ',' << chains.transitions << ','
            << chains.table_memory_bytes << ',' << r.prediction_us << ','
            << h1.methods[0].cells.cell_accuracy() << ',' << cell(ModelKind::persistence) << ','
            << cell(ModelKind::constant_velocity) << ','
            << cell(ModelKind::damped_constant_velocity) << ',' << h1.methods[0].error.mean();
      if (has_intervals(h1)) {
        sweep << ',' << h1.intervals.mean[0].low << ',' << h1.intervals.mean[0].high << '\n';
      } else {
        sweep << ",,\n";
      }
    }
  }
  samples.close();
  return 0;
}

}  // namespace ssl_formation::evaluate
