#pragma once
// What the report page's two files share (html_report.cpp: the tables, the map and the page;
// html_figures.cpp: the figures): the small helpers of its HTML, and the figures' sections.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "ssl_formation/evaluate/html_report.hpp"
#include "ssl_formation/files/replacing_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::evaluate::detail {

namespace ev = ssl_formation::evaluation;

// Text for HTML, escaped.
inline std::string escaped(const std::string& text) {
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

// A number with `decimals` digits after the point.
inline std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

// The colours of the methods, in their order (the model first), and of wins and losses.
inline const char* method_colour(std::size_t m) {
  static const char* colours[] = {"#1b6ac9", "#8c8c8c", "#e3a21a", "#d4572a",
                                  "#7a4fb5", "#2f9e6e", "#b03a7a", "#444444"};
  return colours[m % (sizeof colours / sizeof colours[0])];
}

// A method's column heading: the tables are read on a laptop, and the baselines' names are long.
inline std::string short_label(const std::string& label) {
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

// A round number (1, 2, 2.5 or 5 times a power of ten) at or above `value`.
inline double nice_ceiling(double value) {
  if (!(value > 0.0)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (const double step : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (step * power >= value) return step * power;
  }
  return 10.0 * power;
}

// The step of the section whose horizon is nearest 1 s: the one the per-robot and field views
// show.
inline std::size_t shown_step(const ev::PositionEvaluation& evaluation) {
  std::size_t best = 0;
  for (std::size_t h = 0; h < evaluation.all().size(); ++h) {
    if (std::abs(evaluation.all()[h].horizon_s - 1.0) <
        std::abs(evaluation.all()[best].horizon_s - 1.0)) {
      best = h;
    }
  }
  return best;
}

// A method's interval of the mean error, for a table cell (empty without intervals).
inline std::string interval_cell(const ev::HorizonScore& score, std::size_t m) {
  if (score.intervals.mean.size() != score.methods.size()) return "";
  const ev::Interval& i = score.intervals.mean[m];
  return "<span class='ci' data-low='" + csv_number(i.low) + "' data-high='" + csv_number(i.high) +
         "'>[" + fixed(i.low, 1) + ", " + fixed(i.high, 1) + "]</span>";
}

// The mean error against the horizon, a figure per game state group (SVG).
std::string error_by_horizon(const ev::PositionEvaluation& evaluation);
// The reliability diagrams of every probability the model states, and their calibration.
std::string reliability_section(const ev::PositionEvaluation& evaluation);

}  // namespace ssl_formation::evaluate::detail
