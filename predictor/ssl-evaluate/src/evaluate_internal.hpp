#pragma once
// What ssl-evaluate's subcommands share, inside its library: the streams they train and test on
// (evaluate_inputs.cpp), one grid's held-out evaluation (grid_holdout.cpp), and the tables, CSV
// files and page it writes of one (text_report.cpp). Each subcommand has a file of its own:
// paper_command.cpp, holdout_command.cpp, score_command.cpp.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <exception>
#include <fstream>
#include <memory>
#include <optional>
#include <random>

#include "ssl_formation/evaluate/evaluate.hpp"
#include "ssl_formation/evaluate/html_report.hpp"
#include "ssl_formation/evaluate/log_streams.hpp"
#include "ssl_formation/evaluation/evaluation.hpp"
#include "ssl_formation/evaluation/position_evaluation.hpp"
#include "ssl_formation/files/real_log_shape.hpp"
#include "ssl_formation/files/replacing_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/playbook.hpp"
#include "ssl_formation/simulation/simulated_events.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"

namespace ssl_formation::evaluate::detail {

namespace ev = ssl_formation::evaluation;

using Streams = std::vector<ev::EventStream>;

// A simulation, kept in memory for as many replays as asked.
ev::EventStream in_memory(RecordedMatch match);

// Hands every event on to `sink`, counting the vision packets.
class VisionCount final : public MatchEventSink {
 public:
  explicit VisionCount(MatchEventSink& sink) : sink_(sink) {}
  void on_event(const MatchEvent& event) override {
    if (event.kind == MatchEventKind::vision) ++packets_;
    sink_.on_event(event);
  }
  void start_new_stream() override { sink_.start_new_stream(); }
  std::size_t packets() const { return packets_; }

 private:
  MatchEventSink& sink_;
  std::size_t packets_ = 0;
};

// The paper's simulated opponent (no referee): one formation every 2 s of data time.
RecordedMatch paper_simulation(const EvaluateOptions& options, std::uint64_t seed, int formations);

// A simulated match with its game controller: 60 frames a second of a team running a playbook.
RecordedMatch match_simulation(const EvaluateOptions& options, std::uint64_t seed, double seconds);

// The training and test streams the options describe: logs (each its own stream, split in time
// with --split), or simulations of two seeds.
std::pair<Streams, Streams> holdout_streams(const EvaluateOptions& options,
                                            const std::string& simulation);

// A CSV file in -o/--output's folder, or nowhere without one: tables are printed either way. It
// replaces an earlier file of the name only when the run gets to its end: leaving its scope
// while an exception unwinds (a failed run) leaves the earlier file as it was.
class CsvFile {
 public:
  CsvFile(const EvaluateOptions& options, const std::string& name) {
    if (options.output_dir.empty()) return;
    const std::filesystem::path path = std::filesystem::path(options.output_dir) / name;
    app::check_outputs_free({path.string()}, options.overwrite);
    std::filesystem::create_directories(path.parent_path());
    file_.emplace(path);
    spdlog::info("writing {}", path.string());
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  ~CsvFile() {
    if (!file_ || std::uncaught_exceptions() > unwinding_) return;  // discarded by file_
    try {
      file_->commit();
    } catch (const std::exception& error) {
      spdlog::error("{}", error.what());
    }
  }
  template <typename T>
  CsvFile& operator<<(const T& value) {
    if (file_) file_->stream() << value;
    return *this;
  }

 private:
  std::optional<ReplacingFile> file_;
  int unwinding_ = std::uncaught_exceptions();
};

// --write-samples: every robot as it was scored (ev::ScoredSample), a line each, for cutting the
// tables another way (by how the robot moved, by robot, by time). Positions in the feed's
// coordinates, mm. `chain` tells the sections apart: 0 for a horizon's own model (--horizons), 1
// for the chain of --step steps, whose first step may be a horizon of its own too.
class SampleFile {
 public:
  // `pooled`: the sections score the model's pooled ablation too (PositionEvaluationConfig::
  // pooled_ablation with the motion model), after the baselines.
  SampleFile(const std::string& path, bool pooled) : path_(path), pooled_(pooled) {
    if (path_.empty()) return;
    file_.emplace(path_);
    spdlog::info("writing every scored robot to {}", path_);
    out()
        << "grid,chain,step_s,horizon_steps,horizon_s,stream,time_s,robot_id,game_state,x_mm,y_mm,"
           "truth_x_mm,truth_y_mm,model_x_mm,model_y_mm";
    // The baselines every section scores (PositionEvaluationConfig's default), in their order.
    for (const ModelKind baseline : baseline_kinds) {
      out() << ',' << describe(baseline).name << "_x_mm," << describe(baseline).name << "_y_mm";
    }
    if (pooled_) out() << ",model_pooled_x_mm,model_pooled_y_mm";
    out() << ",model_radius50_mm,model_radius90_mm,model_stays\n";
  }
  bool enabled() const { return file_.has_value(); }
  void write(const std::string& grid, bool chain, const ev::ScoredSample& sample) {
    if (sample.forecasts->size() != 1 + baseline_kinds.size() + (pooled_ ? 1 : 0)) {
      throw std::logic_error("--write-samples: a section scored other methods than the header's");
    }
    out() << grid << (chain ? ",1" : ",0");
    put(",%g,%d,%g,%zu,%.3f,%u,", sample.step_s, sample.steps, sample.steps * sample.step_s,
        sample.stream, sample.time_s, sample.robot_id);
    out() << ev::state_row_name(ev::state_row_of(sample.phase));
    put(",%.1f,%.1f,%.1f,%.1f", sample.position.x, sample.position.y, sample.truth.x,
        sample.truth.y);
    for (const RobotPrediction* forecast : *sample.forecasts) {
      put(",%.1f,%.1f", forecast->feed_position.x, forecast->feed_position.y);
    }
    const RobotPrediction& model = *sample.forecasts->front();
    put(",%.1f,%.1f,%d\n", model.radius50_mm, model.radius90_mm, model.stays ? 1 : 0);
  }
  // Throws if anything failed to be written so far (a full disk): checked after each grid, so a
  // failed file stops the run rather than its end.
  void check() const {
    if (enabled() && !file_->good()) throw std::runtime_error("cannot write " + path_);
  }
  // The file in place of any earlier one: the run got to its end.
  void close() {
    if (enabled()) file_->commit();
  }

 private:
  std::ostream& out() { return file_->stream(); }
  // One field or a few, formatted in place (a stream's formatting of doubles was most of the
  // writing time). A line cut short would run into the next: that throws instead. (The format
  // attribute has the compiler check each call's values against its format.)
  [[gnu::format(printf, 2, 3)]] void put(const char* format, ...) {
    char buffer[256];
    std::va_list values;
    va_start(values, format);
    const int written = std::vsnprintf(buffer, sizeof buffer, format, values);
    va_end(values);
    if (written < 0 || written >= static_cast<int>(sizeof buffer)) {
      throw std::runtime_error("--write-samples: a field too long to write");
    }
    out().write(buffer, written);
  }

  std::string path_;
  bool pooled_ = false;
  std::optional<ReplacingFile> file_;
};

// One configuration's evaluation: its horizons, from `steps` steps of `step_s`.
struct Section {
  double step_s = 0.0;
  ev::PositionEvaluation evaluation;
};

struct GridReport {
  Grid grid{3, 2};
  std::vector<Section> sections;  // one per --horizons entry, then the chains of --step
  double prediction_us = 0.0;     // mean two-step prediction time of the chains' table
  ReportSamples chain_samples;    // the last section's robots, for --report
};

// `prior`: every team's table (--prior-table), loaded once for every grid.
GridReport holdout_for_grid(const EvaluateOptions& options, const std::string& grid,
                            const Streams& train, const Streams& test,
                            const std::shared_ptr<const MotionTable>& prior, SampleFile& samples);

// Whether a score has block-bootstrap intervals for every method.
bool has_intervals(const ev::HorizonScore& score);

// The text tables of one grid's evaluation, on standard output.
void print_holdout(const GridReport& report, const SamplerConfig& base,
                   const EvaluateOptions& options);

// One grid's evaluation as rows of the report's three CSV files.
void write_holdout_csv(CsvFile& accuracy, CsvFile& calibration, CsvFile& reliability,
                       const GridReport& report);

// The report's three CSV files (accuracy, calibration, reliability) with their headers, in
// -o/--output's folder with `prefix` ("holdout-", "grid-sweep-", "score-").
struct ReportFiles {
  ReportFiles(const EvaluateOptions& options, const std::string& prefix)
      : accuracy(options, prefix + "accuracy.csv"),
        calibration(options, prefix + "calibration.csv"),
        reliability(options, prefix + "reliability.csv") {
    accuracy << "grid,horizon_steps,horizon_s,game_state,method,state_accuracy,cell_accuracy,"
                "mean_cell_distance,mean_error_mm,median_error_mm,p90_error_mm,robots,"
                "mean_error_mm_ci_low,mean_error_mm_ci_high,best_baseline,ratio_to_best_baseline,"
                "ratio_ci_low,ratio_ci_high,model_ratio_to_method,model_ratio_ci_low,"
                "model_ratio_ci_high,bootstrap_blocks\n";
    calibration << "grid,horizon_steps,horizon_s,game_state,method,quantity,brier,ece,"
                   "predictions,within_radius_50,within_radius_90\n";
    reliability << "grid,horizon_steps,horizon_s,game_state,quantity,bin,count,mean_confidence,"
                   "observed_frequency\n";
  }
  CsvFile accuracy;
  CsvFile calibration;
  CsvFile reliability;
};

// Stops before any work if --report's path cannot be written.
void check_report_path(const EvaluateOptions& options);

// --report's page for one section (the predictor's chain, or score's file).
void write_report(const EvaluateOptions& options, const std::string& title, const Grid& grid,
                  const Section& section, const ReportSamples& samples);

}  // namespace ssl_formation::evaluate::detail
