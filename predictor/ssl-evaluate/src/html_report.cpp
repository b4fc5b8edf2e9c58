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
  // `attributes`: more of the svg element's, each with a space before it.
  std::string open(const std::string& id, const std::string& attributes = "") const {
    std::ostringstream svg;
    svg << "<svg id='" << id << "' class='plot' viewBox='0 0 " << width << ' ' << height
        << "' width='" << width << "' height='" << height << "' role='img'" << attributes << ">";
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

// A whole number of millimetres with its thousands grouped: "2,630".
std::string grouped_mm(double value) {
  const long long whole = std::llround(value);
  std::string digits = std::to_string(whole < 0 ? -whole : whole);
  for (auto at = static_cast<std::ptrdiff_t>(digits.size()) - 3; at > 0; at -= 3) {
    digits.insert(static_cast<std::size_t>(at), 1, ',');
  }
  return (whole < 0 ? "-" : "") + digits;
}

// An axis from 0 to a round value at or above `value`, in at most `max_ticks` steps of 1, 2, 2.5
// or 5 times a power of ten.
struct RoundAxis {
  double top = 1.0;
  int ticks = 5;
  int decimals = 0;
};
RoundAxis round_axis(double value, int max_ticks) {
  if (!(value > 0.0) || !std::isfinite(value)) return {};
  const double power = std::pow(10.0, std::floor(std::log10(value / max_ticks)));
  for (const double multiple : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    const double step = multiple * power;
    const int ticks = static_cast<int>(std::ceil(value / step - 1e-9));
    if (ticks > max_ticks) continue;
    // Ticks of 2.5 x a power of ten need one digit more than the power shows.
    const int decimals = std::max(
        0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)) + (multiple == 2.5 ? 1 : 0));
    return {step * ticks, std::max(ticks, 1), decimals};
  }
  return {};
}

// The methods whose errors set the error plot's scale: the model and the two baselines of lowest
// mean error at the longest horizon. A baseline far worse than those (constant acceleration's
// error grows with the square of the horizon) would otherwise squeeze them into one line.
std::vector<std::size_t> scale_setting_methods(const ev::PositionEvaluation& evaluation) {
  std::vector<std::size_t> methods{0};
  if (evaluation.all().empty()) return methods;
  const ev::HorizonScore& longest = evaluation.all().back();
  std::vector<std::size_t> baselines;
  for (std::size_t m = 1; m < evaluation.baselines_end && m < longest.methods.size(); ++m) {
    if (longest.methods[m].error.count() > 0) baselines.push_back(m);
  }
  std::sort(baselines.begin(), baselines.end(), [&](std::size_t a, std::size_t b) {
    return longest.methods[a].error.mean() < longest.methods[b].error.mean();
  });
  if (baselines.size() > 2) baselines.resize(2);
  methods.insert(methods.end(), baselines.begin(), baselines.end());
  return methods;
}

// Mean error against the horizon, a line per method, with the intervals as whiskers. The scale
// goes to half as much again as the largest error of the model and the two best baselines, so
// those can be told apart; a method beyond it is drawn clipped at the top, where a triangle in its
// colour marks where it leaves the scale and a line above the plot gives its largest error.
std::string error_by_horizon(const ev::PositionEvaluation& evaluation) {
  constexpr double headroom = 1.5;
  const auto& all = evaluation.all();
  const std::size_t methods = evaluation.methods.size();
  double scale = 0.0;
  const std::vector<std::size_t> scale_setters = scale_setting_methods(evaluation);
  for (const std::size_t m : scale_setters) {
    for (const ev::HorizonScore& score : all) {
      scale = std::max(scale, headroom * score.methods[m].error.mean());
    }
  }
  const RoundAxis axis = round_axis(scale, 8);

  // Each method's largest mean error and its horizon, to say how far off the scale it went.
  struct OffScale {
    std::size_t method;
    double error_mm;
    double horizon_s;
  };
  std::vector<OffScale> off_scale;
  for (std::size_t m = 0; m < methods; ++m) {
    OffScale worst{m, 0.0, 0.0};
    for (const ev::HorizonScore& score : all) {
      if (score.methods[m].error.mean() > worst.error_mm) {
        worst = {m, score.methods[m].error.mean(), score.horizon_s};
      }
    }
    if (worst.error_mm > axis.top) off_scale.push_back(worst);
  }

  Plot plot;
  plot.width = 760;
  plot.height = 420;
  plot.right = 64;  // the labels at the lines' ends
  plot.top = 16 + 16.0 * static_cast<double>(off_scale.size());
  plot.x0 = 0.0;
  plot.x1 = all.empty() ? 1.0 : all.back().horizon_s;
  plot.y1 = axis.top;
  const double area_top = plot.y(plot.y1), area_bottom = plot.y(plot.y0);
  std::ostringstream svg;
  // The scale in data-y-max, for whoever reads the page's numbers.
  svg << plot.open("error-by-horizon", " data-y-max='" + csv_number(axis.top) + "'");
  svg << "<defs><clipPath id='error-by-horizon-area'><rect x='" << plot.left << "' y='" << area_top
      << "' width='" << plot.x(plot.x1) - plot.left << "' height='" << area_bottom - area_top
      << "'/></clipPath></defs>";
  svg << plot.axes("horizon (s)", "mean error (mm)", static_cast<int>(all.size()), axis.ticks, 1,
                   axis.decimals);
  // The model last, over the others; each method's whiskers a little to the side of the
  // others', which would hide them.
  const auto whisker_offset = [methods](std::size_t m) {
    return 3.0 * (static_cast<double>(m) - static_cast<double>(methods - 1) / 2.0);
  };
  for (std::size_t m = methods; m-- > 0;) {
    const bool off = std::any_of(off_scale.begin(), off_scale.end(),
                                 [m](const OffScale& o) { return o.method == m; });
    svg << "<polyline class='method' data-method='" << escaped(evaluation.labels[m])
        << (off ? "' data-off-scale='true" : "") << "' stroke='" << method_colour(m)
        << "' clip-path='url(#error-by-horizon-area)' points='";
    for (const ev::HorizonScore& score : all) {
      svg << plot.x(score.horizon_s) << ',' << plot.y(score.methods[m].error.mean()) << ' ';
    }
    svg << "'/>";
    for (const ev::HorizonScore& score : all) {
      if (score.intervals.mean.size() != score.methods.size()) continue;
      const ev::Interval& i = score.intervals.mean[m];
      const double x = plot.x(score.horizon_s) + whisker_offset(m);
      svg << "<line class='whisker' stroke='" << method_colour(m)
          << "' clip-path='url(#error-by-horizon-area)' x1='" << x << "' x2='" << x << "' y1='"
          << plot.y(i.low) << "' y2='" << plot.y(i.high) << "'/>";
    }
  }

  // Where each line off the scale leaves it: the first horizon above it, or the crossing before.
  for (std::size_t o = 0; o < off_scale.size(); ++o) {
    const std::size_t m = off_scale[o].method;
    double leaves_x = plot.x(plot.x1);
    double previous_s = 0.0, previous_mm = 0.0;
    bool has_previous = false;
    for (const ev::HorizonScore& score : all) {
      const double mm = score.methods[m].error.mean();
      if (mm > axis.top) {
        const double s = has_previous
                             ? previous_s + (score.horizon_s - previous_s) *
                                                (axis.top - previous_mm) / (mm - previous_mm)
                             : score.horizon_s;
        leaves_x = plot.x(s);
        break;
      }
      previous_s = score.horizon_s;
      previous_mm = mm;
      has_previous = true;
    }
    const std::string name = escaped(evaluation.labels[m]);
    svg << "<polygon class='off-scale-mark' data-method='" << name << "' fill='" << method_colour(m)
        << "' points='" << leaves_x - 5 << ',' << area_top + 9 << ' ' << leaves_x + 5 << ','
        << area_top + 9 << ' ' << leaves_x << ',' << area_top << "'/>";
    svg << "<text class='off-scale' data-method='" << name << "' x='" << plot.left + 4 << "' y='"
        << 14 + 16.0 * static_cast<double>(o) << "' fill='" << method_colour(m)
        << "'>&#9650; off scale: " << name << ' ' << grouped_mm(off_scale[o].error_mm) << " mm at "
        << fixed(off_scale[o].horizon_s, 2) << " s</text>";
  }

  // The short name of every line still on the scale at the longest horizon, beside its end,
  // moved apart where lines end close together.
  if (!all.empty()) {
    std::vector<std::pair<double, std::size_t>> ends;
    for (std::size_t m = 0; m < methods; ++m) {
      const double mm = all.back().methods[m].error.mean();
      if (mm <= axis.top) ends.emplace_back(plot.y(mm), m);
    }
    std::sort(ends.begin(), ends.end());
    constexpr double line_px = 11.0;
    for (std::size_t i = 1; i < ends.size(); ++i) {
      ends[i].first = std::max(ends[i].first, ends[i - 1].first + line_px);
    }
    const double overflow = ends.empty() ? 0.0 : ends.back().first - (area_bottom - 2.0);
    for (auto& [y, m] : ends) {
      if (overflow > 0.0) y -= overflow;
      svg << "<text class='end-label' data-method='" << escaped(evaluation.labels[m]) << "' x='"
          << plot.x(plot.x1) + 6 << "' y='" << y + 4 << "' fill='" << method_colour(m) << "'>"
          << escaped(short_label(evaluation.labels[m])) << "</text>";
    }
  }
  svg << "</svg>";
  std::ostringstream legend;
  legend << "<p class='legend'>";
  for (std::size_t m = 0; m < evaluation.labels.size(); ++m) {
    legend << "<span><i style='background:" << method_colour(m) << "'></i>"
           << escaped(evaluation.labels[m]) << "</span> ";
  }
  legend << "<br>The scale goes to " << grouped_mm(axis.top) << " mm, half as much again as the "
         << "largest error of ";
  for (std::size_t i = 0; i < scale_setters.size(); ++i) {
    legend << (i == 0                          ? ""
               : i + 1 == scale_setters.size() ? " and "
                                               : ", ")
           << escaped(evaluation.labels[scale_setters[i]]);
  }
  if (scale_setters.size() > 1) {
    legend << " (the best baselines at the longest horizon), so that these can be told apart";
  }
  legend << '.';
  if (!off_scale.empty()) legend << " Lines beyond it are cut at the top (&#9650;).";
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

// Whether a reliability diagram of `calibration` would show anything: some prediction stated a
// probability above 0. A method that states none writes 0 (a baseline's file of predictions), and
// its diagram would be one dot at 0 with an ECE of 0, as if it were perfectly calibrated.
bool states_probabilities(const ev::Calibration& calibration) {
  return calibration.n > 0 &&
         std::any_of(calibration.bin_confidence.begin(), calibration.bin_confidence.end(),
                     [](double sum) { return sum > 0.0; });
}

// In a diagram's place, where one horizon has no probabilities of a quantity that others have:
// a panel of the same size that says so, with no ECE.
std::string empty_reliability(const ev::Calibration& calibration, const std::string& quantity,
                              const std::string& horizon) {
  std::ostringstream html;
  html << "<figure class='no-data' data-quantity='" << quantity << "'><div class='no-data'>";
  if (calibration.n == 0) {
    html << "No probability of " << quantity << " was stated at " << horizon << '.';
  } else {
    html << "All " << calibration.n << " probabilities of " << quantity << " stated at " << horizon
         << " were 0: nothing to calibrate.";
  }
  html << "</div><figcaption>" << quantity << " at " << horizon
       << ", no probabilities</figcaption></figure>";
  return html.str();
}

// The reliability diagrams of the robots' and the formations' probabilities, at every horizon.
std::string reliability_section(const ev::PositionEvaluation& evaluation) {
  const auto& all = evaluation.all();
  const auto stated_anywhere = [&](const ev::Calibration ev::HorizonScore::*quantity) {
    return std::any_of(all.begin(), all.end(), [&](const ev::HorizonScore& score) {
      return states_probabilities(score.*quantity);
    });
  };
  const bool robots = stated_anywhere(&ev::HorizonScore::robot);
  const bool formations = stated_anywhere(&ev::HorizonScore::formation);
  std::ostringstream html;
  if (!robots && !formations) {
    html << "<p id='reliability' class='no-data'>The predictions state no probabilities: there "
            "is nothing to calibrate.</p>";
    return html.str();
  }
  html << "<p>The share of robots (and of whole formations) in their predicted cell against the "
          "probability stated, in 10 bins; a calibrated model lies on the diagonal.";
  if (!robots) html << " No probability of a robot's cell was stated.";
  if (!formations) html << " No probability of a whole formation was stated.";
  html << "</p><div id='reliability'>";
  for (std::size_t h = 0; h < all.size(); ++h) {
    const ev::HorizonScore& score = all[h];
    const std::string horizon = fixed(score.horizon_s, 2) + " s";
    const std::string number = std::to_string(h + 1);
    if (robots) {
      html << (states_probabilities(score.robot)
                   ? reliability(score.robot, "reliability-robot-" + number, "robots at " + horizon)
                   : empty_reliability(score.robot, "robots", horizon));
    }
    if (formations) {
      html << (states_probabilities(score.formation)
                   ? reliability(score.formation, "reliability-formation-" + number,
                                 "formations at " + horizon)
                   : empty_reliability(score.formation, "formations", horizon));
    }
  }
  html << "</div>";
  return html.str();
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
