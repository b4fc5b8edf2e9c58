// ssl-evaluate score (a predictions CSV against the log) and as-real-log (a log's shape).
#include "evaluate_internal.hpp"

namespace ssl_formation::evaluate {

using namespace detail;

// A predictor's first step puts most robots in their cell (the paper's 3x2 grid: above 90% at
// 0.5 s; persistence alone does as well): below this share the cells are not the log's.
constexpr double low_cell_share = 0.05;

int run_score(const EvaluateOptions& options) {
  if (options.log.empty() || options.predictions.empty()) {
    throw app::UsageError(
        "score needs --from-log (the recorded match) and --predictions (a CSV of "
        "ssl-predictor --from-log's columns for that log)");
  }
  if (!options.test_logs.empty() || options.split > 0.0) {
    throw app::UsageError("score takes one --from-log; --test-log and --split are for holdout");
  }
  check_report_path(options);
  Result<RecordedPredictions> read = read_prediction_csv(options.predictions);
  if (!read) throw std::runtime_error(read.error().message);
  auto recorded = std::make_shared<const RecordedPredictions>(std::move(*read));
  app::ModelOptions model = options.model;
  // The file says its grid (a predictor's since the grid column): taken when --grid is left on
  // auto, and a --grid that disagrees is refused rather than scored as cells of another grid.
  if (recorded->grid) {
    if (model.grid == "auto") {
      model.grid = recorded->grid->to_string();
    } else if (model.parsed_grid() != *recorded->grid) {
      throw app::UsageError("the predictions were made on a " + recorded->grid->to_string() +
                            " grid (their grid column), not --grid " +
                            model.parsed_grid().to_string() + ": give --grid " +
                            recorded->grid->to_string() + " or leave --grid out");
    }
  }
  SamplerConfig sampler = model.sampler_config();
  if (recorded->has_cells) {
    for (const RecordedPrediction& instant : recorded->instants) {
      for (const PredictedStep& step : instant.prediction.steps) {
        for (const RobotPrediction& robot : step.robots) {
          if (robot.position.x < 0 || robot.position.y < 0 ||
              robot.position.x >= sampler.grid.length() ||
              robot.position.y >= sampler.grid.width()) {
            throw app::UsageError("the predictions' cells do not fit --grid " +
                                  sampler.grid.to_string() +
                                  ": give the grid the predictor ran with");
          }
        }
      }
    }
  }
  sampler.step_s = recorded->step_s;
  sampler.sampling = Sampling::frame;
  Streams test;
  test.push_back(LogFile(options.log).stream());
  Streams train;
  for (const std::string& log : options.train_logs) train.push_back(LogFile(log).stream());
  if (train.empty()) {
    std::printf(
        "No --train-log: the damped baselines' factors are fitted on the scored log "
        "itself, which favours them.\n");
    train.push_back(test.front());
  }
  ev::PositionEvaluationConfig config;
  config.sampler = sampler;
  config.steps = recorded->steps;
  config.model = ModelKind::persistence;  // samples the instants; the file predicts
  config.velocity_window_s = options.velocity_window_s;
  config.rules =
      MatchRules{model.opponent_choice(), app::parsed_learn_during(options.learn_during)};
  config.tracked_vision = options.network.tracked();
  config.bootstrap.resamples = options.bootstrap;
  config.bootstrap.block_s = options.bootstrap_block_s;
  config.recorded_predictions = recorded;
  GridReport report;
  report.grid = sampler.grid;
  if (!options.report.empty()) {
    config.on_sample = [&report](const ev::ScoredSample& s) { report.chain_samples.add(s); };
  }
  report.sections.push_back(
      {sampler.step_s, std::move(ev::evaluate_positions({config}, train, test).front())});
  std::uint64_t scored = 0;
  for (const ev::HorizonScore& score : report.sections.back().evaluation.all()) {
    scored += score.methods.front().cells.robots;
  }
  const ev::PositionEvaluation& evaluation = report.sections.back().evaluation;
  std::printf(
      "%zu of the file's %zu instants are frames of the log (within %.0f ms), which has "
      "%llu frames: a frame without a prediction is not scored, nor is a robot the file "
      "leaves out.\n",
      static_cast<std::size_t>(evaluation.recorded_matched), recorded->instants.size(),
      1000.0 * ev::recorded_time_tolerance_s,
      static_cast<unsigned long long>(evaluation.test_formations));
  if (scored == 0) {
    throw std::runtime_error("none of the " + std::to_string(recorded->instants.size()) +
                             " instants of " + options.predictions + " is a frame of " +
                             options.log +
                             " with its robots there at every horizon: is it that "
                             "log's CSV?");
  }
  // Almost no robot in its predicted cell a step later: cells of another grid, field or frame
  // than the predictor's, which the numbers alone would not show.
  if (recorded->has_cells) {
    const ev::HorizonScore& first = evaluation.all().front();
    const double in_cell = first.methods.front().cells.cell_accuracy();
    if (first.methods.front().cells.robots > 0 && in_cell < low_cell_share) {
      spdlog::warn(
          "only {:.1f}% of the robots are in their predicted cell {} s later (persistence: "
          "{:.1f}%): were the predictions made with --grid {}, this field size and this log?",
          100.0 * in_cell, first.horizon_s, 100.0 * first.methods[1].cells.cell_accuracy(),
          sampler.grid.to_string());
    }
  }
  ReportFiles files(options, "score-");
  print_holdout(report, sampler, options);
  write_holdout_csv(files.accuracy, files.calibration, files.reliability, report);
  write_report(options, "ssl-formation: predictions from " + options.predictions + " scored",
               report.grid, report.sections.back(), report.chain_samples);
  return 0;
}

// ---- as-real-log

int run_as_real_log(const EvaluateOptions& options) {
  if (options.from_log.empty() || options.write_log.empty()) {
    throw app::UsageError("as-real-log needs --from-log FILE and -o/--output FILE");
  }
  std::optional<RealLogMess> mess = parse_real_log_mess(options.mess);
  if (!mess) {
    throw app::UsageError("--mess must be none, all or a comma-separated list of " +
                          std::string(real_log_mess_names) +
                          " (noise=MM for another noise, 0 to 1000 mm), not '" + options.mess +
                          "'");
  }
  mess->seed = options.seed;
  const Result<RealLogCounts> counts =
      write_as_real_log(options.from_log, options.write_log, *mess);
  if (!counts) {
    spdlog::error("{}", counts.error().message);
    return 1;
  }
  std::printf(
      "%s: %llu vision packets over %.1f s rewritten as %llu half-field packets (camera "
      "id 0, no geometry), mess: %s, %llu ghost detections\n",
      options.write_log.c_str(), static_cast<unsigned long long>(counts->packets_read),
      counts->recording_s, static_cast<unsigned long long>(counts->packets_written),
      options.mess.c_str(), static_cast<unsigned long long>(counts->ghost_detections));
  if (counts->referee_messages > 0 && !counts->sides_given) {
    std::printf(
        "its referee does not say which half each team defends (the recording's did not): "
        "evaluate it with --opponent-attacks auto (else the opponent is taken to attack +x "
        "throughout%s)\n",
        mess->change_of_ends ? ", which is wrong after the change of ends" : "");
  }
  return 0;
}

}  // namespace ssl_formation::evaluate
