#include "ssl_formation/evaluate/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "html_parts.hpp"
#include "ssl_formation/files/replacing_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

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

using namespace detail;

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

// How often the robots were within the radii the model stated, by game state and step.
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

// The field the heat map is drawn on: the size the evaluation read (its table's, from the logs'
// geometry or the simulation), else (score keeps no table) the smaller division whose walls hold
// every robot scored.
struct MapField {
  FieldSize size;
  bool read = false;  // the evaluation's, not inferred from where the robots were
};
MapField map_field(const ev::PositionEvaluation& evaluation, const ReportSamples& samples) {
  if (evaluation.table && evaluation.table->metadata.field.valid()) {
    return {evaluation.table->metadata.field, true};
  }
  const FieldSize division_b{9000.0, 6000.0};
  const double boundary = rules_markings(division_b).boundary_width;
  const double wall_x = division_b.length_mm / 2.0 + boundary;
  const double wall_y = division_b.width_mm / 2.0 + boundary;
  constexpr double cell = ReportSamples::heat_cell_mm;
  for (const auto& [key, sums] : samples.by_cell()) {
    const double x = std::get<1>(key) * cell, y = std::get<2>(key) * cell;
    if (x >= wall_x || x + cell <= -wall_x || y >= wall_y || y + cell <= -wall_y) {
      return {FieldSize{12000.0, 9000.0}, false};
    }
  }
  return {division_b, false};
}

// The field's markings in millimetres, in a drawing whose y grows downwards (y is the field's -y):
// the outer lines, the halfway line, the centre circle, both defence areas and both goals, with
// the sizes the rules give the field's division (rules_markings: the numbers the live field view
// draws when the feed's geometry states none; the evaluation keeps only the field's size).
std::string field_markings(const FieldSize& field, const FieldMarkings& marks) {
  const double half_length = field.length_mm / 2.0, half_width = field.width_mm / 2.0;
  const double area_depth = marks.penalty_area_depth, area_width = marks.penalty_area_width;
  const double goal_depth = marks.goal_depth, goal_width = marks.goal_width;
  const auto rect = [](const std::string& what, const std::string& side, double x, double y,
                       double width, double height) {
    std::ostringstream svg;
    svg << "<rect class='" << what << "'" << (side.empty() ? "" : " data-side='" + side + "'")
        << " x='" << csv_number(x) << "' y='" << csv_number(y) << "' width='" << csv_number(width)
        << "' height='" << csv_number(height) << "'/>";
    return svg.str();
  };
  std::ostringstream svg;
  svg << "<g class='field-markings'>"
      << rect("marking outer-lines", "", -half_length, -half_width, field.length_mm, field.width_mm)
      << "<line class='marking halfway-line' x1='0' y1='" << csv_number(-half_width)
      << "' x2='0' y2='" << csv_number(half_width) << "'/><circle class='marking centre-circle' "
      << "cx='0' cy='0' r='" << marks.center_circle_radius << "'/>"
      << rect("marking defence-area", "-x", -half_length, -area_width / 2.0, area_depth, area_width)
      << rect("marking defence-area", "+x", half_length - area_depth, -area_width / 2.0, area_depth,
              area_width)
      << rect("goal", "-x", -half_length - goal_depth, -goal_width / 2.0, goal_depth, goal_width)
      << rect("goal", "+x", half_length, -goal_width / 2.0, goal_depth, goal_width) << "</g>";
  return svg.str();
}

// Where on the field the model wins and loses against the best baseline of all states at one
// step: per 1 m cell of where the robot was, the model's mean error minus the baseline's, on the
// field with its lines.
std::string heat_map(const ev::PositionEvaluation& evaluation, const ReportSamples& samples,
                     int steps, std::size_t best) {
  constexpr std::uint64_t min_robots = 30;
  constexpr double cell = ReportSamples::heat_cell_mm;
  const MapField field = map_field(evaluation, samples);
  const FieldMarkings marks = rules_markings(field.size);
  const double wall_x = field.size.length_mm / 2.0 + marks.boundary_width;
  const double wall_y = field.size.width_mm / 2.0 + marks.boundary_width;
  // The drawing spans the walls and any cell wholly outside them (robots off a field of another
  // size). A cell that crosses the walls is cut at them: its robots were inside.
  double min_x = -wall_x, max_x = wall_x, min_y = -wall_y, max_y = wall_y;
  double extreme = 1.0;
  for (const auto& [key, sums] : samples.by_cell()) {
    if (std::get<0>(key) != steps || sums.robots < min_robots) continue;
    const double x = std::get<1>(key) * cell, y = std::get<2>(key) * cell;
    if (x >= wall_x || x + cell <= -wall_x || y >= wall_y || y + cell <= -wall_y) {
      min_x = std::min(min_x, x), max_x = std::max(max_x, x + cell);
      min_y = std::min(min_y, y), max_y = std::max(max_y, y + cell);
    }
    const double difference =
        (sums.errors[0] - sums.errors[best]) / static_cast<double>(sums.robots);
    extreme = std::max(extreme, std::abs(difference));
  }
  // In the drawing, millimetres of the field with y flipped: the field's +y is up.
  const double view_x = min_x, view_y = -max_y, view_width = max_x - min_x,
               view_height = max_y - min_y;
  const double width_px = 760.0;
  const double height_px = std::round(width_px * view_height / view_width);
  std::ostringstream svg;
  svg << "<svg id='heat-map' class='plot' viewBox='" << csv_number(view_x) << ' '
      << csv_number(view_y) << ' ' << csv_number(view_width) << ' ' << csv_number(view_height)
      << "' width='" << width_px << "' height='" << height_px << "' role='img' "
      << "data-field-length-mm='" << csv_number(field.size.length_mm) << "' data-field-width-mm='"
      << csv_number(field.size.width_mm) << "'>";
  svg << "<defs><clipPath id='heat-map-area'><rect x='" << csv_number(view_x) << "' y='"
      << csv_number(view_y) << "' width='" << csv_number(view_width) << "' height='"
      << csv_number(view_height) << "'/></clipPath></defs>";
  svg << "<rect class='field-area' x='" << csv_number(-wall_x) << "' y='" << csv_number(-wall_y)
      << "' width='" << csv_number(2.0 * wall_x) << "' height='" << csv_number(2.0 * wall_y)
      << "'/><g clip-path='url(#heat-map-area)'>";
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
    svg << "<rect class='cell' data-x-mm='" << cx * cell << "' data-y-mm='" << cy * cell
        << "' data-robots='" << sums.robots << "' data-value='" << csv_number(difference) << "' x='"
        << csv_number(cx * cell) << "' y='" << csv_number(-(cy + 1) * cell) << "' width='" << cell
        << "' height='" << cell << "' fill='" << colour << "'><title>" << fixed(difference, 1)
        << " mm, " << sums.robots << " robots</title></rect>";
  }
  svg << "</g>" << field_markings(field.size, marks) << "</svg>";
  const auto metres = [](double mm) { return fixed(mm / 1000.0, 1); };
  std::ostringstream html;
  html << svg.str() << "<p class='legend'>Each square is 1 m of the field (the vision's "
       << "coordinates, +x to the right) where the robot was when predicted, with at least "
       << min_robots << " robots (grey: fewer): <b style='color:#2040ff'>blue</b> where "
       << escaped(evaluation.labels.front()) << " was nearer than "
       << escaped(evaluation.labels[best]) << ", <b style='color:#e02020'>red</b> where it was "
       << "further, by up to " << fixed(extreme, 0)
       << " mm. The lines: " << (field.read ? "the field of the evaluated data, " : "a field of ")
       << describe(field.size)
       << (field.read ? ""
                      : ", the smaller division's, which holds every robot (this evaluation "
                        "keeps no field size)")
       << ", with the rules' defence areas of " << metres(marks.penalty_area_width) << " x "
       << metres(marks.penalty_area_depth) << " m and goals " << metres(marks.goal_width)
       << " m wide.</p>";
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
#heat-map .field-area { fill: #dfe5df; }
#heat-map .marking, #heat-map .goal { fill: none; stroke: #2b2b2b; stroke-opacity: 0.8;
  stroke-width: 1.5; vector-effect: non-scaling-stroke; }
#heat-map .goal { fill: #2b2b2b; fill-opacity: 0.35; stroke-width: 2.5; }
.off-scale { font-size: 11px; } .end-label { font-size: 10px; }
figure { display: inline-block; margin: 0 12px 12px 0; vertical-align: top; }
figcaption { font-size: 12px; }
div.no-data { width: 300px; height: 260px; box-sizing: border-box; padding: 100px 24px 0;
              border: 1px dashed #ccc; color: #666; text-align: center; }
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
  html << "<h2>Reliability of the probabilities</h2>" << reliability_section(evaluation);
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
