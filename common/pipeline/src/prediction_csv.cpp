#include "ssl_formation/pipeline/prediction_csv.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

namespace ssl_formation {
inline namespace pipeline {

namespace {

template <typename Number>
void append_number(std::string& out, Number value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  out.append(text, result.ptr);
}

}  // namespace

std::string_view prediction_csv_header() {
  return "t_capture,frame,robot_id,step,horizon_s,state_index,predicted_cell_x,predicted_cell_y,"
         "predicted_x_mm,predicted_y_mm,probability,unseen,centroid_cell_x,centroid_cell_y,"
         "centroid_probability,formation_probability,confidence,model,predicted_feed_x_mm,"
         "predicted_feed_y_mm,radius_50_mm,radius_90_mm,grid,step_s\n";
}

void append_prediction_csv(const PredictedFormation& predicted, std::string& out) {
  const Formation& formation = predicted.formation();
  const PredictionContext& context = predicted.context;
  const Grid& grid = context.codec->grid();
  const std::string_view model = to_string(context.model);
  const std::string grid_text = grid.to_string();
  for (std::size_t k = 0; k < predicted.prediction.steps.size(); ++k) {
    const PredictedStep& step = predicted.prediction.steps[k];
    for (const RobotPrediction& robot : step.robots) {
      // Back to the feed's coordinates, as the message's cell_centre (the rotation is its own
      // inverse), and at the message's float precision.
      const Point centre =
          normalise(grid.centre_of(robot.position, context.field), context.opponent_attacks);
      append_number(out, formation.time_s);
      out += ',';
      append_number(out, formation.frame_number);
      out += ',';
      append_number(out, robot.robot_id);
      out += ',';
      append_number(out, k + 1);
      out += ',';
      append_number(out, static_cast<double>(k + 1) * context.step_s);
      out += ',';
      append_number(out, robot.state);
      out += ',';
      append_number(out, robot.position.x);
      out += ',';
      append_number(out, robot.position.y);
      out += ',';
      append_number(out, static_cast<float>(centre.x));
      out += ',';
      append_number(out, static_cast<float>(centre.y));
      out += ',';
      append_number(out, robot.probability);
      out += robot.unseen ? ",1," : ",0,";
      append_number(out, step.centroid.x);
      out += ',';
      append_number(out, step.centroid.y);
      out += ',';
      append_number(out, step.centroid_probability);
      out += ',';
      append_number(out, step.formation_probability);
      out += ',';
      append_number(out, step.confidence);
      out += ',';
      out += model;
      out += ',';
      // Where the model puts the robot: the motion model's estimate with its radii, or the
      // paper's cell centre again with radii 0 (it states none). As the message's floats.
      const bool stated = robot.radius90_mm > 0.0;
      const Point at = stated ? robot.feed_position : centre;
      append_number(out, static_cast<float>(at.x));
      out += ',';
      append_number(out, static_cast<float>(at.y));
      out += ',';
      append_number(out, stated ? static_cast<float>(robot.radius50_mm) : 0.0F);
      out += ',';
      append_number(out, stated ? static_cast<float>(robot.radius90_mm) : 0.0F);
      // What made it, so that a score of the file can check the grid and step it is given.
      out += ',';
      out += grid_text;
      out += ',';
      append_number(out, context.step_s);
      out += '\n';
    }
  }
}

}  // namespace pipeline
}  // namespace ssl_formation

namespace ssl_formation {
inline namespace pipeline {

namespace {

// The fields of one line, split at commas (no quoting: the predictor writes none, and names
// with commas are not among its columns).
std::vector<std::string_view> fields_of(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = line.find(',', begin);
    fields.push_back(line.substr(begin, comma == std::string_view::npos ? comma : comma - begin));
    if (comma == std::string_view::npos) return fields;
    begin = comma + 1;
  }
}

template <typename Number>
bool parse_number(std::string_view text, Number& value) {
  while (!text.empty() && (text.back() == '\r' || text.back() == ' ')) text.remove_suffix(1);
  while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size();
}

}  // namespace

Result<RecordedPredictions> parse_prediction_csv(std::string_view text, std::string_view source) {
  const std::string where(source);
  std::size_t line_end = text.find('\n');
  std::string_view header = text.substr(0, line_end);
  if (!header.empty() && header.back() == '\r') header.remove_suffix(1);
  const std::vector<std::string_view> names = fields_of(header);
  const auto column = [&](std::string_view name) -> std::optional<std::size_t> {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) return std::nullopt;
    return static_cast<std::size_t>(it - names.begin());
  };
  for (const std::string_view required :
       {"t_capture", "robot_id", "horizon_s", "predicted_feed_x_mm", "predicted_feed_y_mm"}) {
    if (!column(required)) {
      return fail(where + ": the header has no column '" + std::string(required) +
                  "' (needed: t_capture, robot_id, horizon_s, predicted_feed_x_mm, "
                  "predicted_feed_y_mm)");
    }
  }
  const std::size_t time = *column("t_capture"), robot = *column("robot_id"),
                    horizon = *column("horizon_s"), x = *column("predicted_feed_x_mm"),
                    y = *column("predicted_feed_y_mm");
  const auto step_column = column("step"), r50 = column("radius_50_mm"),
             r90 = column("radius_90_mm"), cell_x = column("predicted_cell_x"),
             cell_y = column("predicted_cell_y"), probability = column("probability"),
             state = column("state_index"), formation = column("formation_probability"),
             grid_column = column("grid");
  RecordedPredictions out;
  out.has_radii = r50 && r90;
  out.has_cells = cell_x && cell_y;
  out.has_states = state.has_value();
  out.has_probabilities = probability.has_value();
  out.has_formation_probability = formation.has_value();

  struct Line {
    double time_s, horizon_s;
    int step;  // 0: from the horizon
    double formation_probability;
    RobotPrediction robot;
  };
  std::vector<Line> lines;
  std::size_t number = 1;
  double smallest_horizon = std::numeric_limits<double>::infinity();
  while (line_end != std::string_view::npos) {
    const std::size_t begin = line_end + 1;
    line_end = text.find('\n', begin);
    std::string_view line =
        text.substr(begin, line_end == std::string_view::npos ? line_end : line_end - begin);
    ++number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) continue;
    const std::vector<std::string_view> fields = fields_of(line);
    if (fields.size() != names.size()) {
      return fail(where + ":" + std::to_string(number) + ": " + std::to_string(fields.size()) +
                  " fields where the header has " + std::to_string(names.size()));
    }
    Line l{0.0, 0.0, 0, 0.0, {}};
    const auto number_at = [&](std::size_t index, auto& value) {
      return parse_number(fields[index], value);
    };
    const auto bad = [&](std::size_t index) {
      return fail(where + ":" + std::to_string(number) + ": column '" + std::string(names[index]) +
                  "' holds '" + std::string(fields[index]) + "', not a number");
    };
    if (!number_at(time, l.time_s) || !std::isfinite(l.time_s)) return bad(time);
    if (!number_at(robot, l.robot.robot_id)) return bad(robot);
    if (!number_at(horizon, l.horizon_s) || !(l.horizon_s > 0.0)) return bad(horizon);
    if (!number_at(x, l.robot.feed_position.x) || !std::isfinite(l.robot.feed_position.x)) {
      return bad(x);
    }
    if (!number_at(y, l.robot.feed_position.y) || !std::isfinite(l.robot.feed_position.y)) {
      return bad(y);
    }
    if (step_column && (!number_at(*step_column, l.step) || l.step < 1)) return bad(*step_column);
    if (r50 && !number_at(*r50, l.robot.radius50_mm)) return bad(*r50);
    if (r90 && !number_at(*r90, l.robot.radius90_mm)) return bad(*r90);
    if (cell_x && !number_at(*cell_x, l.robot.position.x)) return bad(*cell_x);
    if (cell_y && !number_at(*cell_y, l.robot.position.y)) return bad(*cell_y);
    if (probability && !number_at(*probability, l.robot.probability)) return bad(*probability);
    if (state && !number_at(*state, l.robot.state)) return bad(*state);
    if (formation && !number_at(*formation, l.formation_probability)) return bad(*formation);
    if (grid_column) {
      const auto grid = Grid::parse(std::string(fields[*grid_column]));
      if (!grid) {
        return fail(where + ":" + std::to_string(number) + ": column 'grid' holds '" +
                    std::string(fields[*grid_column]) + "', not a grid such as 3x2");
      }
      if (out.grid && *out.grid != *grid) {
        return fail(where + ":" + std::to_string(number) + ": grid " + grid->to_string() +
                    " where the lines before say " + out.grid->to_string());
      }
      out.grid = *grid;
    }
    smallest_horizon = std::min(smallest_horizon, l.horizon_s);
    lines.push_back(l);
  }
  if (lines.empty()) return fail(where + ": no predictions after the header");
  out.step_s = smallest_horizon;
  // Lines of one instant come together, in time order, as the predictor writes them; any order
  // is taken.
  std::stable_sort(lines.begin(), lines.end(),
                   [](const Line& a, const Line& b) { return a.time_s < b.time_s; });
  for (const Line& l : lines) {
    const double steps = l.horizon_s / out.step_s;
    const int step = l.step > 0 ? l.step : static_cast<int>(std::lround(steps));
    if (std::abs(steps - step) > 1e-6 * std::max(1.0, steps)) {
      return fail(where + ": horizon " + std::to_string(l.horizon_s) +
                  " s is not a whole number of steps of the smallest horizon, " +
                  std::to_string(out.step_s) + " s");
    }
    if (out.instants.empty() || out.instants.back().time_s != l.time_s) {
      out.instants.push_back({l.time_s, {}});
    }
    Prediction& prediction = out.instants.back().prediction;
    if (prediction.steps.size() < static_cast<std::size_t>(step)) {
      prediction.steps.resize(static_cast<std::size_t>(step));
    }
    PredictedStep& predicted = prediction.steps[static_cast<std::size_t>(step - 1)];
    predicted.formation_probability = l.formation_probability;
    predicted.robots.push_back(l.robot);
    out.steps = std::max(out.steps, step);
  }
  return out;
}

Result<RecordedPredictions> read_prediction_csv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail("cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return fail("cannot read " + path);
  return parse_prediction_csv(text.str(), path);
}

}  // namespace pipeline
}  // namespace ssl_formation
