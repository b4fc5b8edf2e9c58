// The report page's figures: the mean error by horizon and the reliability diagrams, drawn as
// SVG with axes rounded to readable ticks.
#include "html_parts.hpp"

namespace ssl_formation::evaluate::detail {

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace ssl_formation::evaluate::detail
