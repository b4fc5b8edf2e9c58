#pragma once
// ssl-evaluate --report FILE.html: one page a team can open to decide whether to run the model,
// self-contained (inline CSS and SVG, no script, nothing fetched): the mean error by game state
// with its intervals, the error against the horizon per method, the reliability diagrams, the
// radii's coverage, the error per robot id and a field heat map of where the model wins and
// loses against the best baseline. Its numbers are the CSV files' (each table cell carries the
// CSV's text in data-value, which the browser test compares).

#include <cstdint>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "ssl_formation/evaluation/position_evaluation.hpp"

namespace ssl_formation::evaluate {

// What the report draws beyond the evaluation's tables, gathered robot by robot as the section
// it describes is scored (PositionEvaluationConfig::on_sample).
class ReportSamples {
 public:
  static constexpr double heat_cell_mm = 1000.0;
  // Summed errors per method and the robots they count.
  struct Sums {
    std::uint64_t robots = 0;
    std::vector<double> errors;  // by method, as PositionEvaluation::methods
  };
  void add(const evaluation::ScoredSample& sample);
  // By (steps, robot id), and by (steps, cell x, cell y) of where the robot was (feed
  // coordinates, cells of heat_cell_mm from the origin).
  const std::map<std::pair<int, std::uint32_t>, Sums>& by_robot() const { return by_robot_; }
  const std::map<std::tuple<int, int, int>, Sums>& by_cell() const { return by_cell_; }

 private:
  std::map<std::pair<int, std::uint32_t>, Sums> by_robot_;
  std::map<std::tuple<int, int, int>, Sums> by_cell_;
};

struct ReportInput {
  std::string title;    // what was evaluated, for the page's heading
  std::string command;  // how to run it again
  std::string grid;     // "12x9"
  double step_s = 0.5;  // the section's step
  // The section drawn (the predictor's chain of steps, or score's file) and its samples.
  const evaluation::PositionEvaluation* evaluation = nullptr;
  const ReportSamples* samples = nullptr;
  int bootstrap = 0;  // resamples behind the intervals (0: none)
  double bootstrap_block_s = 10.0;
};

// Writes the page to `path`; throws std::runtime_error naming the path if it cannot.
void write_html_report(const std::string& path, const ReportInput& input);

// A number as the CSV files write it (an ostream's default format): the page's data-value.
std::string csv_number(double value);

}  // namespace ssl_formation::evaluate
