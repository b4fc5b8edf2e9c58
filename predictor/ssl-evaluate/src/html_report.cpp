#include "ssl_formation/evaluate/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "ssl_formation/files/replacing_file.hpp"

namespace ssl_formation::evaluate {

namespace ev = ssl_formation::evaluation;

std::string csv_number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

void ReportSamples::add(const ev::ScoredSample& sample) {
  const std::size_t methods = sample.forecasts->size();
  const auto add_to = [&](Sums& sums) {
    if (sums.errors.empty()) sums.errors.assign(methods, 0.0);
    ++sums.robots;
    for (std::size_t m = 0; m < methods; ++m) {
      const Point at = (*sample.forecasts)[m]->feed_position;
      sums.errors[m] += std::hypot(at.x - sample.truth.x, at.y - sample.truth.y);
    }
  };
  add_to(by_robot_[{sample.steps, sample.robot_id}]);
  const int cell_x = static_cast<int>(std::floor(sample.position.x / heat_cell_mm));
  const int cell_y = static_cast<int>(std::floor(sample.position.y / heat_cell_mm));
  add_to(by_cell_[{sample.steps, cell_x, cell_y}]);
}

namespace {

// Text for HTML, escaped.
std::string escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

// The colours of the methods, in their order (the model first), and of wins and losses.
const char* method_colour(std::size_t m) {
  static const char* colours[] = {"#1b6ac9", "#8c8c8c", "#e3a21a", "#d4572a",
                                  "#7a4fb5", "#2f9e6e", "#b03a7a", "#444444"};
  return colours[m % (sizeof colours / sizeof colours[0])];
}

// A method's column heading: the tables are read on a laptop, and the baselines' names are long.
std::string short_label(const std::string& label) {
  if (label == "persistence") return "P";
  if (label == "constant velocity") return "CV";
  if (label == "damped constant velocity") return "dCV";
  if (label == "constant acceleration") return "CA";
  if (label == "damped constant acceleration") return "dCA";
  if (label == "pooled model") return "pooled";
  return label;
}

// A plot's frame: maps data to SVG coordinates inside margins, and draws axes with ticks.
struct Plot {
  double width = 560, height = 320;
  double left = 64, right = 16, top = 16, bottom = 44;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  double x(double value) const { return left + (value - x0) / (x1 - x0) * (width - left - right); }
  double y(double value) const {
    return height - bottom - (value - y0) / (y1 - y0) * (height - top - bottom);
  }
  std::string axes(const std::string& x_label, const std::string& y_label, int x_ticks, int y_ticks,
                   int x_decimals, int y_decimals) const {
    std::ostringstream svg;
    svg << "<line class='axis' x1='" << left << "' y1='" << y(y0) << "' x2='" << width - right
        << "' y2='" << y(y0) << "'/>";
    svg << "<line class='axis' x1='" << left << "' y1='" << y(y0) << "' x2='" << left << "' y2='"
        << top << "'/>";
    for (int i = 0; x_ticks > 0 && i <= x_ticks; ++i) {
      const double v = x0 + (x1 - x0) * i / x_ticks;
      svg << "<text class='tick' x='" << x(v) << "' y='" << y(y0) + 16 << "' text-anchor='middle'>"
          << fixed(v, x_decimals) << "</text>";
    }
    for (int i = 0; i <= y_ticks; ++i) {
      const double v = y0 + (y1 - y0) * i / y_ticks;
      svg << "<line class='grid' x1='" << left << "' y1='" << y(v) << "' x2='" << width - right
          << "' y2='" << y(v) << "'/><text class='tick' x='" << left - 6 << "' y='" << y(v) + 4
          << "' text-anchor='end'>" << fixed(v, y_decimals) << "</text>";
    }
    svg << "<text class='label' x='" << (left + width - right) / 2 << "' y='" << height - 6
        << "' text-anchor='middle'>" << escaped(x_label) << "</text>";
    svg << "<text class='label' transform='translate(14," << (top + height - bottom) / 2
        << ") rotate(-90)' text-anchor='middle'>" << escaped(y_label) << "</text>";
    return svg.str();
  }
  std::string open(const std::string& id) const {
    std::ostringstream svg;
    svg << "<svg id='" << id << "' class='plot' viewBox='0 0 " << width << ' ' << height
        << "' width='" << width << "' height='" << height << "' role='img'>";
    return svg.str();
  }
};

double nice_ceiling(double value) {
  if (!(value > 0.0)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (const double step : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (step * power >= value) return step * power;
  }
  return 10.0 * power;
}

// The step of the section whose horizon is nearest 1 s: the one the per-robot and field views
// show.
std::size_t shown_step(const ev::PositionEvaluation& evaluation) {
  std::size_t best = 0;
  for (std::size_t h = 0; h < evaluation.all().size(); ++h) {
    if (std::abs(evaluation.all()[h].horizon_s - 1.0) <
        std::abs(evaluation.all()[best].horizon_s - 1.0)) {
      best = h;
    }
  }
  return best;
}

std::string interval_cell(const ev::HorizonScore& score, std::size_t m) {
  if (score.intervals.mean.size() != score.methods.size()) return "";
  const ev::Interval& i = score.intervals.mean[m];
  return "<span class='ci' data-low='" + csv_number(i.low) + "' data-high='" + csv_number(i.high) +
         "'>[" + fixed(i.low, 1) + ", " + fixed(i.high, 1) + "]</span>";
}

// The table by game state: every row and step, each method's mean error with its interval, and
// the model's margin below the row's best baseline.
std::string state_table(const ev::PositionEvaluation& evaluation) {
  std::ostringstream html;
  html << "<table id='by-state'><thead><tr><th>game state</th><th>horizon</th><th>robots</th>";
  for (const std::string& label : evaluation.labels) {
    html << "<th title='" << escaped(label) << "'>" << escaped(short_label(label)) << "</th>";
  }
  html << "<th>best baseline</th><th>" << escaped(evaluation.labels.front())
       << " below it</th></tr></thead><tbody>";
  for (const std::size_t row : evaluation.reported_rows()) {
    for (const ev::HorizonScore& score : evaluation.rows[row]) {
      if (score.methods.front().cells.robots == 0) continue;
      const std::string state(ev::state_row_name(row));
      html << "<tr data-state='" << state << "' data-horizon='" << csv_number(score.horizon_s)
           << "'><td>" << state << "</td><td>" << fixed(score.horizon_s, 2) << " s</td><td>"
           << score.methods.front().cells.robots << "</td>";
      const std::optional<std::size_t> best = evaluation.best_baseline(score);
      for (std::size_t m = 0; m < score.methods.size(); ++m) {
        const double mean = score.methods[m].error.mean();
        html << "<td class='mean" << (best && m == *best ? " best" : "") << "' data-method='"
             << escaped(evaluation.labels[m]) << "' data-value='" << csv_number(mean) << "'>"
             << fixed(mean, 1) << ' ' << interval_cell(score, m) << "</td>";
      }
      if (best) {
        const double ratio = score.methods[0].error.mean() / score.methods[*best].error.mean();
        std::string interval;
        if (!score.intervals.ratio.empty()) {
          const ev::Interval& i = score.intervals.ratio[0];
          interval = " [" + fixed(100.0 * (1.0 - i.high), 1) + ", " +
                     fixed(100.0 * (1.0 - i.low), 1) + "]";
        }
        html << "<td>" << escaped(short_label(evaluation.labels[*best])) << "</td><td class='margin"
             << (ratio <= 1.0 ? " win" : " loss") << "' data-value='" << csv_number(ratio) << "'>"
             << fixed(100.0 * (1.0 - ratio), 1) << "%" << interval << "</td>";
      } else {
        html << "<td></td><td></td>";
      }
      html << "</tr>";
    }
  }
  html << "</tbody></table>";
  return html.str();
}

// Mean error against the horizon, a line per method, with the intervals as whiskers.
std::string error_by_horizon(const ev::PositionEvaluation& evaluation) {
  Plot plot;
  const auto& all = evaluation.all();
  double top = 0.0;
  for (const ev::HorizonScore& score : all) {
    for (std::size_t m = 0; m < score.methods.size(); ++m) {
      top = std::max(top, score.methods[m].error.mean());
      if (score.intervals.mean.size() == score.methods.size()) {
        top = std::max(top, score.intervals.mean[m].high);
      }
    }
  }
  plot.x0 = 0.0;
  plot.x1 = all.empty() ? 1.0 : all.back().horizon_s;
  plot.y1 = nice_ceiling(top);
  std::ostringstream svg;
  svg << plot.open("error-by-horizon")
      << plot.axes("horizon (s)", "mean error (mm)", static_cast<int>(all.size()), 5, 1, 0);
  for (std::size_t m = 0; m < evaluation.methods.size(); ++m) {
    svg << "<polyline class='method' data-method='" << escaped(evaluation.labels[m]) << "' stroke='"
        << method_colour(m) << "' points='";
    for (const ev::HorizonScore& score : all) {
      svg << plot.x(score.horizon_s) << ',' << plot.y(score.methods[m].error.mean()) << ' ';
    }
    svg << "'/>";
    for (const ev::HorizonScore& score : all) {
      if (score.intervals.mean.size() != score.methods.size()) continue;
      const ev::Interval& i = score.intervals.mean[m];
      svg << "<line class='whisker' stroke='" << method_colour(m) << "' x1='"
          << plot.x(score.horizon_s) << "' x2='" << plot.x(score.horizon_s) << "' y1='"
          << plot.y(i.low) << "' y2='" << plot.y(i.high) << "'/>";
    }
  }
  svg << "</svg>";
  std::ostringstream legend;
  legend << "<p class='legend'>";
  for (std::size_t m = 0; m < evaluation.labels.size(); ++m) {
    legend << "<span><i style='background:" << method_colour(m) << "'></i>"
           << escaped(evaluation.labels[m]) << "</span> ";
  }
  legend << "</p>";
  return svg.str() + legend.str();
}

// Observed frequency against stated probability, 10 bins, one diagram per step and quantity.
std::string reliability(const ev::Calibration& calibration, const std::string& id,
                        const std::string& title) {
  Plot plot;
  plot.width = 300;
  plot.height = 260;
  std::ostringstream svg;
  svg << "<figure>" << plot.open(id) << plot.axes("stated probability", "observed", 5, 5, 1, 1);
  svg << "<line class='diagonal' x1='" << plot.x(0) << "' y1='" << plot.y(0) << "' x2='"
      << plot.x(1) << "' y2='" << plot.y(1) << "'/>";
  for (std::size_t b = 0; b < calibration.bin_count.size(); ++b) {
    const auto n = calibration.bin_count[b];
    if (n == 0) continue;
    const double confidence = calibration.bin_confidence[b] / static_cast<double>(n);
    const double observed = static_cast<double>(calibration.bin_hits[b]) / static_cast<double>(n);
    const double r =
        2.5 + 6.0 * std::sqrt(static_cast<double>(n) /
                              static_cast<double>(std::max<std::uint64_t>(1, calibration.n)));
    svg << "<circle class='bin' cx='" << plot.x(confidence) << "' cy='" << plot.y(observed)
        << "' r='" << r << "' data-count='" << n << "'/>";
  }
  svg << "</svg><figcaption>" << escaped(title) << ", ECE "
      << fixed(ev::expected_calibration_error(calibration), 3) << " over " << calibration.n
      << "</figcaption></figure>";
  return svg.str();
}

std::string radii_table(const ev::PositionEvaluation& evaluation) {
  std::ostringstream html;
  html << "<table id='radii'><thead><tr><th>game state</th><th>horizon</th><th>robots</th>"
          "<th>within r50 (aim 50%)</th><th>within r90 (aim 90%)</th></tr></thead><tbody>";
  for (const std::size_t row : evaluation.reported_rows()) {
    for (const ev::HorizonScore& score : evaluation.rows[row]) {
      if (score.radii.robots == 0) continue;
      const double r90 = score.radii.share90();
      html << "<tr><td>" << ev::state_row_name(row) << "</td><td>" << fixed(score.horizon_s, 2)
           << " s</td><td>" << score.radii.robots << "</td><td data-value='"
           << csv_number(score.radii.share50()) << "'>" << fixed(100.0 * score.radii.share50(), 1)
           << "%</td><td class='" << (r90 >= 0.85 && r90 <= 0.95 ? "win" : "loss")
           << "' data-value='" << csv_number(r90) << "'>" << fixed(100.0 * r90, 1) << "%</td></tr>";
    }
  }
  html << "</tbody></table>";
  return html.str();
}

// Mean error per robot id at one step, bars per method.
std::string robot_errors(const ev::PositionEvaluation& evaluation, const ReportSamples& samples,
                         int steps) {
  std::vector<std::pair<std::uint32_t, const ReportSamples::Sums*>> robots;
  for (const auto& [key, sums] : samples.by_robot()) {
    if (key.first == steps && sums.robots > 0) robots.emplace_back(key.second, &sums);
  }
  Plot plot;
  plot.width = 760;
  const std::size_t methods = evaluation.methods.size();
  double top = 0.0;
  for (const auto& [id, sums] : robots) {
    for (const double e : sums->errors) top = std::max(top, e / static_cast<double>(sums->robots));
  }
  plot.x0 = 0.0;
  plot.x1 = std::max<double>(1.0, static_cast<double>(robots.size()));
  plot.y1 = nice_ceiling(top);
  std::ostringstream svg;
  svg << plot.open("robot-errors") << plot.axes("robot id", "mean error (mm)", 0, 5, 0, 0);
  const double slot = (plot.x(1) - plot.x(0));
  const double bar = slot * 0.8 / static_cast<double>(std::max<std::size_t>(1, methods));
  for (std::size_t r = 0; r < robots.size(); ++r) {
    const auto& [id, sums] = robots[r];
    svg << "<text class='tick' x='" << plot.x(static_cast<double>(r) + 0.5) << "' y='"
        << plot.y(0) + 16 << "' text-anchor='middle'>" << id << "</text>";
    for (std::size_t m = 0; m < methods; ++m) {
      const double mean = sums->errors[m] / static_cast<double>(sums->robots);
      const double x = plot.x(static_cast<double>(r)) + slot * 0.1 + bar * static_cast<double>(m);
      svg << "<rect class='bar' data-robot='" << id << "' data-method='"
          << escaped(evaluation.labels[m]) << "' data-value='" << csv_number(mean) << "' x='" << x
          << "' y='" << plot.y(mean) << "' width='" << bar << "' height='"
          << plot.y(0) - plot.y(mean) << "' fill='" << method_colour(m) << "'/>";
    }
  }
  svg << "</svg>";
  return svg.str();
}

// Where on the field the model wins and loses against the best baseline of all states at one
// step: per 1 m cell of where the robot was, the model's mean error minus the baseline's.
std::string heat_map(const ev::PositionEvaluation& evaluation, const ReportSamples& samples,
                     int steps, std::size_t best) {
  constexpr std::uint64_t min_robots = 30;
  int min_x = 0, max_x = -1, min_y = 0, max_y = -1;
  double extreme = 1.0;
  bool any = false;
  for (const auto& [key, sums] : samples.by_cell()) {
    if (std::get<0>(key) != steps || sums.robots < min_robots) continue;
    const int cx = std::get<1>(key), cy = std::get<2>(key);
    if (!any) min_x = max_x = cx, min_y = max_y = cy;
    min_x = std::min(min_x, cx), max_x = std::max(max_x, cx);
    min_y = std::min(min_y, cy), max_y = std::max(max_y, cy);
    any = true;
    const double difference =
        (sums.errors[0] - sums.errors[best]) / static_cast<double>(sums.robots);
    extreme = std::max(extreme, std::abs(difference));
  }
  const double cell_px = 48.0;
  const double width = any ? (max_x - min_x + 1) * cell_px : cell_px;
  const double height = any ? (max_y - min_y + 1) * cell_px : cell_px;
  std::ostringstream svg;
  svg << "<svg id='heat-map' class='plot' viewBox='0 0 " << width << ' ' << height << "' width='"
      << width << "' height='" << height << "' role='img'>";
  for (const auto& [key, sums] : samples.by_cell()) {
    if (std::get<0>(key) != steps || sums.robots < min_robots) continue;
    const int cx = std::get<1>(key), cy = std::get<2>(key);
    const double difference =
        (sums.errors[0] - sums.errors[best]) / static_cast<double>(sums.robots);
    // Blue where the model is nearer, red where the baseline is; white for a tie.
    const double t = std::clamp(difference / extreme, -1.0, 1.0);
    const int fade = static_cast<int>(255.0 * (1.0 - std::abs(t)));
    char colour[16];
    if (t < 0) {
      std::snprintf(colour, sizeof colour, "#%02x%02xff", fade, fade);
    } else {
      std::snprintf(colour, sizeof colour, "#ff%02x%02x", fade, fade);
    }
    // y grows upwards on the field, downwards in SVG.
    svg << "<rect class='cell' data-x-mm='" << cx * ReportSamples::heat_cell_mm << "' data-y-mm='"
        << cy * ReportSamples::heat_cell_mm << "' data-robots='" << sums.robots << "' data-value='"
        << csv_number(difference) << "' x='" << (cx - min_x) * cell_px << "' y='"
        << (max_y - cy) * cell_px << "' width='" << cell_px << "' height='" << cell_px << "' fill='"
        << colour << "'><title>" << fixed(difference, 1) << " mm, " << sums.robots
        << " robots</title></rect>";
  }
  svg << "</svg>";
  std::ostringstream html;
  html << svg.str() << "<p class='legend'>Each square is 1 m of the field (the vision's "
       << "coordinates, +x to the right) where the robot was when predicted, with at least "
       << min_robots << " robots: <b style='color:#2040ff'>blue</b> where "
       << escaped(evaluation.labels.front()) << " was nearer than "
       << escaped(evaluation.labels[best]) << ", <b style='color:#e02020'>red</b> where it was "
       << "further, by up to " << fixed(extreme, 0) << " mm.</p>";
  return html.str();
}

const char* style = R"(
body { font: 14px/1.45 "DejaVu Sans", sans-serif; margin: 24px auto; max-width: 1240px;
       color: #1d1d1d; }
h1 { font-size: 22px; } h2 { font-size: 17px; margin-top: 28px; }
code { background: #f2f2f2; padding: 1px 4px; }
table { border-collapse: collapse; font-size: 12.5px; }
th, td { border-bottom: 1px solid #ddd; padding: 3px 8px; text-align: right; white-space: nowrap; }
th:first-child, td:first-child { text-align: left; }
td.best { font-weight: bold; } td.win { color: #1b6a2f; } td.loss { color: #b02020; }
.ci { color: #777; font-size: 11px; display: block; }
svg.plot { background: #fff; border: 1px solid #e4e4e4; }
.axis { stroke: #333; } .grid { stroke: #eee; } .diagonal { stroke: #bbb; stroke-dasharray: 4 3; }
.tick { font-size: 10px; fill: #555; } .label { font-size: 11px; fill: #333; }
polyline.method { fill: none; stroke-width: 2; } line.whisker { stroke-width: 1.5; }
circle.bin { fill: #1b6ac9; fill-opacity: 0.75; }
figure { display: inline-block; margin: 0 12px 12px 0; } figcaption { font-size: 12px; }
.legend span { margin-right: 14px; } .legend i { display: inline-block; width: 12px;
  height: 12px; margin-right: 4px; vertical-align: -1px; }
)";

}  // namespace

void write_html_report(const std::string& path, const ReportInput& input) {
  if (!input.evaluation) throw std::invalid_argument("a report needs an evaluation");
  const ev::PositionEvaluation& evaluation = *input.evaluation;
  std::ostringstream html;
  html << "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>"
       << escaped(input.title) << "</title><style>" << style << "</style></head><body>";
  html << "<h1>" << escaped(input.title) << "</h1>";
  html << "<p>Grid " << escaped(input.grid) << ", steps of " << fixed(input.step_s, 2) << " s; "
       << evaluation.test_formations << " test formations. Mean errors in mm per robot, "
       << "every method scored on the same robots at the same instants";
  if (input.bootstrap > 0) {
    html << "; 95% intervals from " << input.bootstrap << " resamples of "
         << fixed(input.bootstrap_block_s, 0) << " s blocks of data time (none for a row over "
         << "fewer than " << evaluation::BootstrapConfig{}.min_blocks << " blocks)";
  }
  html << ". Run again with <code>" << escaped(input.command) << "</code>.</p>";
  if (!evaluation.test_has_referee) {
    html << "<p>The test data carry no referee messages: every instant is running play.</p>";
  }
  html << "<h2>Mean error by game state</h2><p>P persistence, CV and CA constant velocity and "
          "acceleration, dCV and dCA their damped forms, pooled: the model with one fit for "
          "every robot and state (an ablation). In bold, each row's best baseline.</p>"
       << state_table(evaluation);
  html << "<h2>Error against the horizon</h2>" << error_by_horizon(evaluation);
  html << "<h2>Reliability of the probabilities</h2><p>The share of robots (and of whole "
          "formations) in their predicted cell against the probability stated, in 10 bins; "
          "a calibrated model lies on the diagonal.</p><div id='reliability'>";
  for (std::size_t h = 0; h < evaluation.all().size(); ++h) {
    const ev::HorizonScore& score = evaluation.all()[h];
    const std::string horizon = fixed(score.horizon_s, 2) + " s";
    if (score.robot.n > 0) {
      html << reliability(score.robot, "reliability-robot-" + std::to_string(h + 1),
                          "robots at " + horizon);
    }
    if (score.formation.n > 0) {
      html << reliability(score.formation, "reliability-formation-" + std::to_string(h + 1),
                          "formations at " + horizon);
    }
  }
  html << "</div>";
  html << "<h2>The radii's coverage</h2>" << radii_table(evaluation);
  if (input.samples && !evaluation.all().empty()) {
    const std::size_t h = shown_step(evaluation);
    const int steps = static_cast<int>(h + 1);
    const std::string horizon = fixed(evaluation.all()[h].horizon_s, 2) + " s";
    html << "<h2>Mean error per robot id at " << horizon << "</h2>"
         << robot_errors(evaluation, *input.samples, steps);
    if (const auto best = evaluation.best_baseline(evaluation.all()[h])) {
      html << "<h2>Where " << escaped(evaluation.labels.front()) << " wins and loses at " << horizon
           << ", against " << escaped(evaluation.labels[*best]) << "</h2>"
           << heat_map(evaluation, *input.samples, steps, *best);
    }
  }
  html << "</body></html>\n";
  ReplacingFile out(path, true);
  out.stream() << html.str();
  out.commit();
}

}  // namespace ssl_formation::evaluate
