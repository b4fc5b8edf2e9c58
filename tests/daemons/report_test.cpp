// ssl-evaluate --report's page as a team reads it, checked in its SVG: the error against the
// horizon on a scale the model and the best baselines can be told apart on, with the methods
// beyond it marked; no reliability diagram (nor ECE) where no probability was stated; and the heat
// map on the field with its lines, defence areas and goals at the division's sizes. Each on a
// report of short logs the test writes: a simulated Division A match (ssl-producer), and robots
// moving on a Division B field whose predictions ssl-predictor writes and `score` reads.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <vector>

#include "child_process.hpp"
#include "moving_robots.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

const std::filesystem::path evaluate_program = SSLF_EVALUATE_PATH;
const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The element `<svg id='id' ...>...</svg>` of the page (no figure nests an svg).
std::string svg_of(const std::string& page, const std::string& id) {
  const std::size_t begin = page.find("<svg id='" + id + "'");
  if (begin == std::string::npos) return "";
  const std::size_t end = page.find("</svg>", begin);
  return page.substr(begin, end == std::string::npos ? std::string::npos : end + 6 - begin);
}

// Every element `<tag ... class='classes' ...>` of `text`, as its opening tag.
std::vector<std::string> elements(const std::string& text, const std::string& tag,
                                  const std::string& classes) {
  std::vector<std::string> found;
  const std::regex element("<" + tag + " class='" + classes + "'[^>]*>");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), element);
       it != std::sregex_iterator(); ++it) {
    found.push_back(it->str());
  }
  return found;
}

// An attribute's value in an opening tag; empty when it has none.
std::string attribute(const std::string& tag, const std::string& name) {
  std::smatch match;
  if (!std::regex_search(tag, match, std::regex(" " + name + "='([^']*)'"))) return "";
  return match[1];
}
double number(const std::string& tag, const std::string& name) {
  return std::stod(attribute(tag, name));
}

// The element with data-side='side' among `tags`.
std::string on_side(const std::vector<std::string>& tags, const std::string& side) {
  for (const std::string& tag : tags) {
    if (attribute(tag, "data-side") == side) return tag;
  }
  return "";
}

// The heat map's field: its size, the outer lines, the halfway line, the centre circle, both
// defence areas and both goals, in the field's millimetres (the drawing's y is the field's -y,
// and every marking is symmetric about y = 0).
void expect_field_markings(const std::string& heat_map, double length, double width,
                           double area_depth, double area_width, double goal_width) {
  ASSERT_FALSE(heat_map.empty());
  EXPECT_EQ(number(heat_map, "data-field-length-mm"), length);
  EXPECT_EQ(number(heat_map, "data-field-width-mm"), width);
  // The drawing holds the field and its 300 mm boundary, in the field's proportions.
  std::istringstream view(attribute(heat_map, "viewBox"));
  double x = 0, y = 0, view_width = 0, view_height = 0;
  view >> x >> y >> view_width >> view_height;
  EXPECT_LE(x, -length / 2 - 300);
  EXPECT_LE(y, -width / 2 - 300);
  EXPECT_GE(view_width, length + 600);
  EXPECT_GE(view_height, width + 600);
  EXPECT_NEAR(number(heat_map, "width") / number(heat_map, "height"), view_width / view_height,
              0.01);

  const auto outer = elements(heat_map, "rect", "marking outer-lines");
  ASSERT_EQ(outer.size(), 1u);
  EXPECT_EQ(number(outer[0], "x"), -length / 2);
  EXPECT_EQ(number(outer[0], "y"), -width / 2);
  EXPECT_EQ(number(outer[0], "width"), length);
  EXPECT_EQ(number(outer[0], "height"), width);
  const auto halfway = elements(heat_map, "line", "marking halfway-line");
  ASSERT_EQ(halfway.size(), 1u);
  EXPECT_EQ(number(halfway[0], "x1"), 0.0);
  EXPECT_EQ(number(halfway[0], "y1"), -width / 2);
  EXPECT_EQ(number(halfway[0], "y2"), width / 2);
  const auto circle = elements(heat_map, "circle", "marking centre-circle");
  ASSERT_EQ(circle.size(), 1u);
  EXPECT_EQ(number(circle[0], "r"), 500.0);

  const auto areas = elements(heat_map, "rect", "marking defence-area");
  const auto goals = elements(heat_map, "rect", "goal");
  ASSERT_EQ(areas.size(), 2u);
  ASSERT_EQ(goals.size(), 2u);
  for (const std::string side : {"-x", "+x"}) {
    SCOPED_TRACE(side);
    const double sign = side == "+x" ? 1.0 : -1.0;
    const std::string area = on_side(areas, side);
    ASSERT_FALSE(area.empty());
    EXPECT_EQ(number(area, "width"), area_depth);
    EXPECT_EQ(number(area, "height"), area_width);
    EXPECT_EQ(number(area, "y"), -area_width / 2);
    // Against its goal line.
    EXPECT_EQ(number(area, "x") + (sign > 0 ? area_depth : 0.0), sign * length / 2);
    const std::string goal = on_side(goals, side);
    ASSERT_FALSE(goal.empty());
    EXPECT_EQ(number(goal, "height"), goal_width);
    EXPECT_EQ(number(goal, "width"), 180.0);
    EXPECT_EQ(number(goal, "y"), -goal_width / 2);
    // Behind its goal line.
    EXPECT_EQ(number(goal, "x") + (sign > 0 ? 0.0 : 180.0), sign * length / 2);
  }
  // The cells under the lines.
  EXPECT_FALSE(elements(heat_map, "rect", "cell").empty());
  EXPECT_LT(heat_map.find("class='cell'"), heat_map.find("class='field-markings'"));
}

// The page's mean error of each method in the table's row of every instant at `horizon`.
std::map<std::string, double> means_at(const std::string& page, const std::string& horizon) {
  std::map<std::string, double> means;
  const std::size_t row = page.find("<tr data-state='all' data-horizon='" + horizon + "'>");
  if (row == std::string::npos) return means;
  const std::string cells = page.substr(row, page.find("</tr>", row) - row);
  for (const std::string& cell : elements(cells, "td", "mean[^']*")) {
    means[attribute(cell, "data-method")] = number(cell, "data-value");
  }
  return means;
}

// A simulated Division A match, its error at 2 s running from about 0.1 m (the model) to about
// 0.7 m (constant acceleration).
TEST(Report, ScalesTheErrorToTheBestMethodsAndDrawsTheDivisionAField) {
  TempDir dir;
  for (const std::string seed : {"1", "2"}) {
    const auto written =
        testing::run_to_end(producer_program,
                            {"--write-log", (dir / ("match" + seed + ".log")).string(),
                             "--duration", "30", "--seed", seed},
                            dir.path(), "producer" + seed, 60s);
    ASSERT_EQ(written.exit_code, 0) << written.err;
  }
  const auto report = dir / "report.html";
  const auto evaluated =
      testing::run_to_end(evaluate_program,
                          {"holdout", "--train-log", (dir / "match1.log").string(), "--test-log",
                           (dir / "match2.log").string(), "--our-team", "ssl-formation",
                           "--horizons", "0.5", "--chain-steps", "4", "--report", report.string()},
                          dir.path(), "evaluate", 120s);
  ASSERT_EQ(evaluated.exit_code, 0) << evaluated.err;
  const std::string page = read(report);

  // The scale: from the model and the two best baselines at the longest horizon (the chain's
  // 4 x 0.5 s), half as much again as their largest error, rounded up to a tick.
  const std::map<std::string, double> longest = means_at(page, "2");
  ASSERT_EQ(longest.size(), 7u) << page;
  std::vector<double> baselines;
  for (const std::string baseline : {"persistence", "constant velocity", "damped constant velocity",
                                     "constant acceleration", "damped constant acceleration"}) {
    ASSERT_TRUE(longest.contains(baseline)) << baseline;
    baselines.push_back(longest.at(baseline));
  }
  std::sort(baselines.begin(), baselines.end());
  const double best = std::max({longest.at("model"), baselines[0], baselines[1]});
  const std::string plot = svg_of(page, "error-by-horizon");
  ASSERT_FALSE(plot.empty());
  const double y_max = number(plot, "data-y-max");
  EXPECT_GE(y_max, 1.5 * best);
  EXPECT_LT(y_max, 2.0 * best);
  // Its top tick says so.
  EXPECT_NE(plot.find("text-anchor='end'>" + std::to_string(static_cast<int>(y_max)) + "</text>"),
            std::string::npos)
      << plot;

  // Constant acceleration's error grows with the horizon's square: beyond the scale, its line
  // cut at the top and marked, its error named above the plot. Every method beyond the scale is
  // marked, and none within it.
  ASSERT_GT(longest.at("constant acceleration"), y_max);
  const auto off_scale = elements(plot, "text", "off-scale");
  for (const auto& [method, error] : longest) {
    SCOPED_TRACE(method);
    const auto label = std::find_if(off_scale.begin(), off_scale.end(), [&](const auto& tag) {
      return attribute(tag, "data-method") == method;
    });
    const auto line = elements(plot, "polyline", "method");
    const auto drawn = std::find_if(line.begin(), line.end(), [&](const auto& tag) {
      return attribute(tag, "data-method") == method;
    });
    ASSERT_NE(drawn, line.end());
    EXPECT_EQ(attribute(*drawn, "clip-path"), "url(#error-by-horizon-area)");
    if (error > y_max) {
      ASSERT_NE(label, off_scale.end());
      EXPECT_EQ(attribute(*drawn, "data-off-scale"), "true");
    } else {
      EXPECT_EQ(label, off_scale.end());
      EXPECT_EQ(attribute(*drawn, "data-off-scale"), "");
    }
  }
  const std::size_t text = plot.find("data-method='constant acceleration' x=");
  ASSERT_NE(text, std::string::npos);
  EXPECT_TRUE(
      std::regex_search(plot.substr(text, plot.find("</text>", text) - text),
                        std::regex(R"(off scale: constant acceleration [\d,]+ mm at 2\.00 s$)")))
      << plot.substr(text, 200);
  EXPECT_EQ(elements(plot, "polygon", "off-scale-mark").size(), off_scale.size());

  expect_field_markings(svg_of(page, "heat-map"), 12000, 9000, 1800, 3600, 1800);
  EXPECT_NE(page.find("the field of the evaluated data, 12000 x 9000 mm (Division A)"),
            std::string::npos);
}

// The CSV of ssl-predictor --from-log with its formation probability edited: `keep(horizon_s)`
// says at which horizons it stays, the others' set to 0 (as a method that states none writes it);
// without `keep` the column is left out.
void write_edited_predictions(const std::filesystem::path& from, const std::filesystem::path& to,
                              const std::function<bool(const std::string&)>& keep) {
  std::istringstream in(read(from));
  std::ofstream out(to);
  std::size_t horizon = 0, formation = 0;
  bool header = true;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
    if (header) {
      horizon = static_cast<std::size_t>(std::find(fields.begin(), fields.end(), "horizon_s") -
                                         fields.begin());
      formation = static_cast<std::size_t>(
          std::find(fields.begin(), fields.end(), "formation_probability") - fields.begin());
      ASSERT_LT(horizon, fields.size());
      ASSERT_LT(formation, fields.size());
    } else if (keep && !keep(fields[horizon])) {
      fields[formation] = "0";
    }
    if (!keep) fields.erase(fields.begin() + static_cast<std::ptrdiff_t>(formation));
    for (std::size_t f = 0; f < fields.size(); ++f) out << (f ? "," : "") << fields[f];
    out << '\n';
    header = false;
  }
}

// Robots moving on a Division B field, their predictions made by the daemon's pipeline.
TEST(Report, DrawsNoReliabilityWhereNoProbabilityWasStatedAndTheDivisionBField) {
  TempDir dir;
  const auto train_log = dir / "train.log";
  const auto test_log = dir / "test.log";
  ASSERT_EQ(testing::write_train_and_test_logs(train_log, test_log, 20.0), "");
  const auto table = dir / "table.bin";
  const auto csv = dir / "predictions.csv";
  const auto trained = testing::run_to_end(
      trainer_program, {"--from-log", train_log.string(), "--table", table.string()}, dir.path(),
      "trainer", 60s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  const auto predicted = testing::run_to_end(
      predictor_program,
      {"--from-log", test_log.string(), "--table", table.string(), "--output", csv.string()},
      dir.path(), "predictor", 60s);
  ASSERT_EQ(predicted.exit_code, 0) << predicted.err;
  const auto score = [&](const std::filesystem::path& predictions, const std::string& name) {
    const auto report = dir / (name + ".html");
    const auto scored =
        testing::run_to_end(evaluate_program,
                            {"score", "--log", test_log.string(), "--predictions",
                             predictions.string(), "--report", report.string(), "--bootstrap", "0"},
                            dir.path(), name, 120s);
    EXPECT_EQ(scored.exit_code, 0) << scored.err;
    return read(report);
  };

  // Formations' probabilities stated at the first step (0.5 s) only: at the second, a panel that
  // says so in the diagram's place, with no ECE; the robots' diagrams at both.
  write_edited_predictions(csv, dir / "first-step.csv",
                           [](const std::string& horizon) { return std::stod(horizon) < 0.75; });
  const std::string page = score(dir / "first-step.csv", "first-step");
  EXPECT_NE(page.find("<svg id='reliability-robot-1'"), std::string::npos);
  EXPECT_NE(page.find("<svg id='reliability-robot-2'"), std::string::npos);
  EXPECT_NE(page.find("<svg id='reliability-formation-1'"), std::string::npos);
  EXPECT_EQ(page.find("<svg id='reliability-formation-2'"), std::string::npos);
  const std::size_t empty = page.find("<figure class='no-data' data-quantity='formations'>");
  ASSERT_NE(empty, std::string::npos) << page;
  const std::string panel = page.substr(empty, page.find("</figure>", empty) - empty);
  EXPECT_NE(panel.find("formations stated at 1.00 s were 0: nothing to calibrate"),
            std::string::npos)
      << panel;
  EXPECT_EQ(panel.find("ECE"), std::string::npos) << panel;
  EXPECT_EQ(panel.find("class='bin'"), std::string::npos) << panel;
  EXPECT_EQ(page.find("<figure class='no-data'", empty + 1), std::string::npos)
      << "the only panel without data";

  // A file without the column: no formations' panel at all, and a word why.
  write_edited_predictions(csv, dir / "no-formations.csv", nullptr);
  const std::string without = score(dir / "no-formations.csv", "no-formations");
  EXPECT_EQ(without.find("reliability-formation-"), std::string::npos);
  EXPECT_EQ(without.find("formations at"), std::string::npos);
  EXPECT_NE(without.find("No probability of a whole formation was stated."), std::string::npos);
  EXPECT_NE(without.find("<svg id='reliability-robot-2'"), std::string::npos);

  // score keeps no field size: the robots, all within Division B's walls, are drawn on its field.
  expect_field_markings(svg_of(page, "heat-map"), 9000, 6000, 1000, 2000, 1000);
  EXPECT_NE(page.find("a field of 9000 x 6000 mm (Division B), the smaller division's"),
            std::string::npos);
}

}  // namespace
}  // namespace ssl_formation
