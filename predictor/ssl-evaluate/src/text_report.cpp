// What ssl-evaluate prints and writes of an evaluation: the text tables, the CSV files, the page.
#include "evaluate_internal.hpp"

namespace ssl_formation::evaluate::detail {

namespace {

const char* quantity_name(bool robot) { return robot ? "robot" : "formation"; }

// How a method is named in the tables: the model as "model", the baselines by their labels.
std::string method_label(const ev::PositionEvaluation& evaluation, std::size_t m) {
  return evaluation.labels.at(m);
}

// Every row of game state and step of every section that scored a robot, in the report's order:
// visit(evaluation, row, step index, score).
template <typename Visit>
void for_each_scored_row(const GridReport& report, Visit&& visit) {
  for (const Section& section : report.sections) {
    const ev::PositionEvaluation& evaluation = section.evaluation;
    for (const std::size_t row : evaluation.reported_rows()) {
      for (std::size_t h = 0; h < evaluation.rows[row].size(); ++h) {
        const ev::HorizonScore& score = evaluation.rows[row][h];
        if (score.methods.front().cells.robots > 0) visit(evaluation, row, h, score);
      }
    }
  }
}

// "6.1% [4.2, 9.0]": how far below 1 a ratio of mean errors is, in percent, with the interval
// of the ratio (low and high swap) when there is one.
std::string margin_text(double ratio, const ev::Interval* interval) {
  char text[64];
  if (interval) {
    std::snprintf(text, sizeof text, "%.1f%% [%.1f, %.1f]", 100.0 * (1.0 - ratio),
                  100.0 * (1.0 - interval->high), 100.0 * (1.0 - interval->low));
  } else {
    std::snprintf(text, sizeof text, "%.1f%%", 100.0 * (1.0 - ratio));
  }
  return text;
}

}  // namespace

bool has_intervals(const ev::HorizonScore& score) {
  return score.intervals.mean.size() == score.methods.size();
}

namespace {

// "[145.2, 151.0]"; a row over too few blocks for one, "(3 blocks)"; "" without the bootstrap.
std::string interval_text(const ev::HorizonScore& score, std::size_t m, bool bootstrap) {
  if (!bootstrap) return "";
  char text[64];
  if (!has_intervals(score)) {
    std::snprintf(text, sizeof text, "(%zu block%s)", score.intervals.blocks,
                  score.intervals.blocks == 1 ? "" : "s");
  } else {
    const ev::Interval& i = score.intervals.mean[m];
    std::snprintf(text, sizeof text, "[%.1f, %.1f]", i.low, i.high);
  }
  return text;
}

// The model (or the scored predictions) against the best baseline of each row, with the
// intervals of their ratio.
void print_ratios(const GridReport& report, const EvaluateOptions& options) {
  const ev::PositionEvaluation& first = report.sections.front().evaluation;
  const std::string scored = method_label(first, 0);  // "model" or "predictions"
  std::printf(
      "The %s against the best baseline of each row: mean error over the best's, 95%% "
      "intervals from %d resamples of %.0f s blocks (none for a row over fewer than %zu "
      "blocks):\n",
      scored.c_str(), options.bootstrap, options.bootstrap_block_s,
      ev::BootstrapConfig{}.min_blocks);
  // The model's first ablation (the pooled model), if the evaluation ran one.
  const bool has_ablation = first.baselines_end < first.methods.size();
  const std::size_t ablation = first.baselines_end;
  std::printf("%9s %5s %-24s %7s %-30s %12s %18s %20s", "horizon", "steps", "game state", "blocks",
              "best baseline", (scored + "/best").c_str(), "95% interval",
              (scored + " below best").c_str());
  if (has_ablation) {
    std::printf(" %26s", ("model below '" + method_label(first, ablation) + "'").c_str());
  }
  std::printf("\n");
  for_each_scored_row(report, [&](const ev::PositionEvaluation& evaluation, std::size_t row,
                                  std::size_t h, const ev::HorizonScore& score) {
    const std::optional<std::size_t> best = evaluation.best_baseline(score);
    if (!best) return;
    const double ratio = score.methods[0].error.mean() / score.methods[*best].error.mean();
    char range[64] = "";
    const ev::Interval* interval = nullptr;
    if (!score.intervals.ratio.empty()) {
      interval = &score.intervals.ratio[0];
      std::snprintf(range, sizeof range, "[%.3f, %.3f]", interval->low, interval->high);
    }
    std::printf("%7.2f s %5zu %-24s %7zu %-30s %12.3f %18s %20s", score.horizon_s, h + 1,
                std::string(ev::state_row_name(row)).c_str(), score.intervals.blocks,
                method_label(evaluation, *best).c_str(), ratio, range,
                margin_text(ratio, interval).c_str());
    if (has_ablation && ablation < score.methods.size()) {
      const double over = score.methods[0].error.mean() / score.methods[ablation].error.mean();
      const bool drawn = score.intervals.model_ratio.size() >= ablation;
      std::printf(
          " %26s",
          margin_text(over, drawn ? &score.intervals.model_ratio[ablation - 1] : nullptr).c_str());
    }
    std::printf("\n");
  });
}

void print_calibration(const GridReport& report);
void print_radii(const GridReport& report);

}  // namespace

void print_holdout(const GridReport& report, const SamplerConfig& base,
                   const EvaluateOptions& options) {
  const ev::PositionEvaluation& chains = report.sections.back().evaluation;
  if (chains.labels.front() == "predictions") {
    std::printf(
        "Scored predictions from %s against %s, grid %s: %llu formations of the log; "
        "the damped baselines fitted on %llu formations\n",
        options.predictions.c_str(), options.log.c_str(), report.grid.to_string().c_str(),
        static_cast<unsigned long long>(chains.test_formations),
        static_cast<unsigned long long>(chains.train_formations));
  } else {
    std::printf(
        "Held-out evaluation, grid %s, %s sampling: %llu test formations; the chains' table: "
        "%llu transitions from %llu formations\n",
        report.grid.to_string().c_str(), std::string(to_string(base.sampling)).c_str(),
        static_cast<unsigned long long>(chains.test_formations),
        static_cast<unsigned long long>(chains.transitions),
        static_cast<unsigned long long>(chains.train_formations));
  }
  if (chains.feed_problem) std::printf("warning: %s\n", chains.feed_problem->c_str());
  if (!chains.test_has_referee) {
    std::printf(
        "The test streams carry no referee messages: every instant counts as running "
        "play, and only the rows 'all' and 'running' are given.\n");
  }
  const bool intervals = options.bootstrap > 0;
  std::printf("%9s %5s %-30s %11s %11s %9s %9s %s%9s %9s %9s\n", "horizon", "steps", "method",
              "exact state", "exact cell", "cells off", "mean mm",
              intervals ? "     95% interval " : "", "median mm", "p90 mm", "robots");
  for (const Section& section : report.sections) {
    const ev::PositionEvaluation& evaluation = section.evaluation;
    for (std::size_t h = 0; h < evaluation.all().size(); ++h) {
      const ev::HorizonScore& score = evaluation.all()[h];
      for (std::size_t m = 0; m < score.methods.size(); ++m) {
        const ev::Accuracy& a = score.methods[m].cells;
        const ev::ErrorStats& e = score.methods[m].error;
        char interval[64] = "";
        if (intervals) {
          std::snprintf(interval, sizeof interval, " %18s",
                        interval_text(score, m, intervals).c_str());
        }
        // What the scored file does not state (its states, its cells) is shown as '-'.
        char state[32] = "          -";
        char cell[32] = "          -";
        char cells_off[32] = "        -";
        if (m != 0 || evaluation.model_states_states) {
          std::snprintf(state, sizeof state, "%10.2f%%", 100.0 * a.state_accuracy());
        }
        if (m != 0 || evaluation.model_states_cells) {
          std::snprintf(cell, sizeof cell, "%10.2f%%", 100.0 * a.cell_accuracy());
          std::snprintf(cells_off, sizeof cells_off, "%9.3f", a.mean_distance());
        }
        std::printf("%7.2f s %5zu %-30s %s %s %s %9.1f%s %9.1f %9.1f %9llu\n", score.horizon_s,
                    h + 1, method_label(evaluation, m).c_str(), state, cell, cells_off, e.mean(),
                    interval, e.median(), e.percentile(90),
                    static_cast<unsigned long long>(a.robots));
      }
    }
  }
  // By phase of the game: the mean error of every method, for the rows with anything in them.
  std::printf("Mean error (mm) by phase of the game%s:\n%9s %5s %-24s %9s",
              intervals ? ", with its 95% interval" : "", "horizon", "steps", "game state",
              "robots");
  const int width = intervals ? 28 : 12;
  for (std::size_t m = 0; m < chains.methods.size(); ++m) {
    std::printf(" %*.*s", width, width, method_label(chains, m).c_str());
  }
  std::printf("\n");
  for_each_scored_row(report, [&](const ev::PositionEvaluation&, std::size_t row, std::size_t h,
                                  const ev::HorizonScore& score) {
    std::printf("%7.2f s %5zu %-24s %9llu", score.horizon_s, h + 1,
                std::string(ev::state_row_name(row)).c_str(),
                static_cast<unsigned long long>(score.methods.front().cells.robots));
    for (std::size_t m = 0; m < score.methods.size(); ++m) {
      char cell[96];
      std::snprintf(cell, sizeof cell, "%.1f%s%s", score.methods[m].error.mean(),
                    intervals ? " " : "", interval_text(score, m, intervals).c_str());
      std::printf(" %*s", width, cell);
    }
    std::printf("\n");
  });
  if (intervals) print_ratios(report, options);
  print_calibration(report);
  print_radii(report);
}

namespace {

// The calibration of the probabilities stated (none: nothing printed, as for a file of
// predictions without them).
void print_calibration(const GridReport& report) {
  const bool stated =
      std::any_of(report.sections.begin(), report.sections.end(), [](const Section& section) {
        return std::any_of(section.evaluation.all().begin(), section.evaluation.all().end(),
                           [](const ev::HorizonScore& score) { return score.robot.n > 0; });
      });
  if (!stated) return;
  const bool file = method_label(report.sections.front().evaluation, 0) == "predictions";
  std::printf("Calibration of the %s probabilities (10 equal bins):\n",
              file ? "file's" : "model's");
  std::printf("%9s %5s %-10s %9s %9s %12s\n", "horizon", "steps", "quantity", "Brier", "ECE",
              "predictions");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.all().size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.all()[h];
      for (const bool robot : {true, false}) {
        const ev::Calibration& c = robot ? score.robot : score.formation;
        std::printf("%7.2f s %5zu %-10s %9.4f %9.4f %12llu\n", score.horizon_s, h + 1,
                    quantity_name(robot), c.brier(), ev::expected_calibration_error(c),
                    static_cast<unsigned long long>(c.n));
      }
    }
  }
}

// How often the robots were within the radii stated (none: nothing printed).
void print_radii(const GridReport& report) {
  if (report.sections.front().evaluation.all().front().radii.robots == 0) return;
  std::printf("The model's radii: how often the robot was within them (aim: 50%% and 90%%):\n");
  std::printf("%9s %5s %12s %12s %12s\n", "horizon", "steps", "within r50", "within r90", "robots");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.all().size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.all()[h];
      std::printf("%7.2f s %5zu %11.1f%% %11.1f%% %12llu\n", score.horizon_s, h + 1,
                  100.0 * score.radii.share50(), 100.0 * score.radii.share90(),
                  static_cast<unsigned long long>(score.radii.robots));
    }
  }
}

}  // namespace

void write_holdout_csv(CsvFile& accuracy, CsvFile& calibration, CsvFile& reliability,
                       const GridReport& report) {
  const std::string grid = report.grid.to_string();
  for (const Section& section : report.sections) {
    const ev::PositionEvaluation& evaluation = section.evaluation;
    for (const std::size_t row : evaluation.reported_rows()) {
      const std::string state(ev::state_row_name(row));
      for (std::size_t h = 0; h < evaluation.rows[row].size(); ++h) {
        const ev::HorizonScore& score = evaluation.rows[row][h];
        for (std::size_t m = 0; m < score.methods.size(); ++m) {
          const ev::Accuracy& a = score.methods[m].cells;
          const ev::ErrorStats& e = score.methods[m].error;
          accuracy << grid << ',' << h + 1 << ',' << score.horizon_s << ',' << state << ','
                   << method_label(evaluation, m) << ',';
          // Empty where the scored file states no states or cells.
          if (m != 0 || evaluation.model_states_states) accuracy << a.state_accuracy();
          accuracy << ',';
          if (m != 0 || evaluation.model_states_cells) {
            accuracy << a.cell_accuracy() << ',' << a.mean_distance();
          } else {
            accuracy << ',';
          }
          accuracy << ',' << e.mean() << ',' << e.median() << ',' << e.percentile(90) << ','
                   << a.robots;
          // The intervals, empty without --bootstrap; the ratio is this method's mean over the
          // best baseline's (1 for the best baseline itself).
          const ev::RowIntervals& intervals = score.intervals;
          if (has_intervals(score)) {
            accuracy << ',' << intervals.mean[m].low << ',' << intervals.mean[m].high;
          } else {
            accuracy << ",,";
          }
          const std::optional<std::size_t> best = evaluation.best_baseline(score);
          if (best && a.robots > 0) {
            accuracy << ',' << method_label(evaluation, *best) << ','
                     << e.mean() / score.methods[*best].error.mean();
          } else {
            accuracy << ",,";
          }
          if (!intervals.ratio.empty()) {
            accuracy << ',' << intervals.ratio[m].low << ',' << intervals.ratio[m].high;
          } else {
            accuracy << ",,";
          }
          // The model's mean over this method's (1 on the model's own row).
          if (a.robots > 0 && e.mean() > 0.0) {
            accuracy << ',' << score.methods[0].error.mean() / e.mean();
          } else {
            accuracy << ',';
          }
          if (m == 0 && has_intervals(score)) {
            accuracy << ",1,1";
          } else if (m > 0 && intervals.model_ratio.size() >= m) {
            accuracy << ',' << intervals.model_ratio[m - 1].low << ','
                     << intervals.model_ratio[m - 1].high;
          } else {
            accuracy << ",,";
          }
          accuracy << ',' << intervals.blocks << '\n';
        }
        for (const bool robot : {true, false}) {
          const ev::Calibration& c = robot ? score.robot : score.formation;
          calibration << grid << ',' << h + 1 << ',' << score.horizon_s << ',' << state << ",model,"
                      << quantity_name(robot) << ',' << c.brier() << ','
                      << ev::expected_calibration_error(c) << ',' << c.n << ','
                      << score.radii.share50() << ',' << score.radii.share90() << '\n';
          for (std::size_t b = 0; b < c.bin_count.size(); ++b) {
            const auto n = static_cast<double>(c.bin_count[b]);
            reliability << grid << ',' << h + 1 << ',' << score.horizon_s << ',' << state << ','
                        << quantity_name(robot) << ',' << b << ',' << c.bin_count[b] << ','
                        << (n > 0 ? c.bin_confidence[b] / n : 0.0) << ','
                        << (n > 0 ? static_cast<double>(c.bin_hits[b]) / n : 0.0) << '\n';
          }
        }
      }
    }
  }
}

void check_report_path(const EvaluateOptions& options) {
  if (options.report.empty()) return;
  const bool existed = std::filesystem::exists(options.report);
  {
    std::ofstream probe(options.report, std::ios::app);
    if (!probe) throw std::runtime_error("cannot write the report " + options.report);
  }
  if (!existed) std::filesystem::remove(options.report);  // the probe leaves nothing behind
}

void write_report(const EvaluateOptions& options, const std::string& title, const Grid& grid,
                  const Section& section, const ReportSamples& samples) {
  if (options.report.empty()) return;
  ReportInput input;
  input.title = title;
  input.command = options.command_line;
  input.grid = grid.to_string();
  input.step_s = section.step_s;
  input.evaluation = &section.evaluation;
  input.samples = &samples;
  input.bootstrap = options.bootstrap;
  input.bootstrap_block_s = options.bootstrap_block_s;
  write_html_report(options.report, input);
  spdlog::info("wrote the report {}", options.report);
}

}  // namespace ssl_formation::evaluate::detail
