#include "ssl_formation/pipeline/prediction_message.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace ssl_formation {
inline namespace pipeline {

namespace {

void set_cell(proto::GridCell& out, Cell cell) {
  out.set_x(static_cast<std::uint32_t>(cell.x));
  out.set_y(static_cast<std::uint32_t>(cell.y));
}

// The motion model states a position and radii for its robots; the paper's model states none,
// and its messages carry nothing beyond the cell.
bool states_position(const RobotPrediction& robot) { return robot.radius90_mm > 0.0; }

// How far ahead step k (0 = the next) is, in seconds: the same double everywhere.
double horizon_seconds(std::size_t k, double step_s) { return static_cast<double>(k + 1) * step_s; }

void append_cell(std::string& out, Cell cell) {
  out += '(';
  out += std::to_string(cell.x);
  out += ',';
  out += std::to_string(cell.y);
  out += ')';
}

// The protobuf wire format (proto2, fields in number order, as protoc's generated code writes
// them) for the few types FormationPrediction uses.
namespace wire {

// Writes into memory reserved beforehand: no capacity check per byte.
struct Writer {
  char* p;
};

std::size_t varint_size(std::uint64_t value) {
  std::size_t size = 1;
  while (value >= 0x80) {
    value >>= 7;
    ++size;
  }
  return size;
}
void varint(Writer& out, std::uint64_t value) {
  while (value >= 0x80) {
    *out.p++ = (static_cast<char>((value & 0x7F) | 0x80));
    value >>= 7;
  }
  *out.p++ = (static_cast<char>(value));
}
void tag(Writer& out, int field, int type) {
  varint(out, static_cast<std::uint64_t>(field << 3 | type));
}
void uint(Writer& out, int field, std::uint64_t value) {
  tag(out, field, 0);
  varint(out, value);
}
void fixed(Writer& out, std::uint64_t bits, int bytes) {
  for (int i = 0; i < bytes; ++i) *out.p++ = (static_cast<char>((bits >> (8 * i)) & 0xFF));
}
void float64(Writer& out, int field, double value) {
  tag(out, field, 1);
  fixed(out, std::bit_cast<std::uint64_t>(value), 8);
}
void float32(Writer& out, int field, float value) {
  tag(out, field, 5);
  fixed(out, std::bit_cast<std::uint32_t>(value), 4);
}
void length(Writer& out, int field, std::size_t size) {
  tag(out, field, 2);
  varint(out, size);
}

// Sizes of the nested messages (every tag here is one byte).
std::size_t cell_size(Cell c) {
  return 2 + varint_size(static_cast<std::uint32_t>(c.x)) +
         varint_size(static_cast<std::uint32_t>(c.y));
}
constexpr std::size_t point_size = 10;
void cell(Writer& out, int field, Cell c) {
  length(out, field, cell_size(c));
  uint(out, 1, static_cast<std::uint32_t>(c.x));
  uint(out, 2, static_cast<std::uint32_t>(c.y));
}
void point(Writer& out, int field, Point p) {
  length(out, field, point_size);
  float32(out, 1, static_cast<float>(p.x));
  float32(out, 2, static_cast<float>(p.y));
}
std::size_t current_robot_size(const FormationRobot& r) {
  return 1 + varint_size(r.robot_id) + 1 + varint_size(r.state) + 2 + cell_size(r.cell) + 2 +
         cell_size(r.previous_cell) + 2 + point_size;
}
std::size_t predicted_robot_size(const RobotPrediction& r) {
  const std::size_t size = 1 + varint_size(r.robot_id) + 1 + varint_size(r.state) + 2 +
                           cell_size(r.position) + 2 + cell_size(r.previous) + 2 + point_size + 9 +
                           2;
  // position (8), radius_50_mm (9), radius_90_mm (10)
  return states_position(r) ? size + 2 + point_size + 5 + 5 : size;
}
std::size_t step_size(std::size_t k, const PredictedStep& step) {
  // ... and horizon_seconds (8)
  std::size_t size = 1 + varint_size(k + 1) + 2 + cell_size(step.centroid) + 9 + 2 + 9 + 9 + 9;
  for (const RobotPrediction& r : step.robots) {
    const std::size_t robot = predicted_robot_size(r);
    size += 1 + varint_size(robot) + robot;
  }
  return size;
}

}  // namespace wire

}  // namespace

void encode_prediction(const Formation& current, const Prediction& prediction,
                       const PredictionContext& context, std::string& buffer) {
  // An upper bound of the encoded size: every varint at its longest.
  std::size_t bound = 192 + 64 * current.robots.size();
  for (const PredictedStep& step : prediction.steps) bound += 80 + 112 * step.robots.size();
  if (buffer.size() < bound) buffer.resize(bound);
  wire::Writer out{buffer.data()};
  wire::uint(out, 1, current.frame_number);
  wire::float64(out, 2, current.time_s);
  wire::cell(out, 3, current.centroid_cell);
  for (const FormationRobot& robot : current.robots) {
    wire::length(out, 4, wire::current_robot_size(robot));
    wire::uint(out, 1, robot.robot_id);
    wire::uint(out, 2, robot.state);
    wire::cell(out, 3, robot.cell);
    wire::cell(out, 4, robot.previous_cell);
    wire::point(out, 5, robot.feed_position);
  }
  const Grid& grid = context.codec->grid();
  for (std::size_t k = 0; k < prediction.steps.size(); ++k) {
    const PredictedStep& step = prediction.steps[k];
    wire::length(out, 5, wire::step_size(k, step));
    wire::uint(out, 1, k + 1);
    wire::cell(out, 2, step.centroid);
    wire::float64(out, 3, step.centroid_probability);
    wire::uint(out, 4, step.centroid_unseen ? 1 : 0);
    for (const RobotPrediction& robot : step.robots) {
      wire::length(out, 5, wire::predicted_robot_size(robot));
      wire::uint(out, 1, robot.robot_id);
      wire::uint(out, 2, robot.state);
      wire::cell(out, 3, robot.position);
      wire::cell(out, 4, robot.previous);
      wire::point(
          out, 5,
          normalise(grid.centre_of(robot.position, context.field), context.opponent_attacks));
      wire::float64(out, 6, robot.probability);
      wire::uint(out, 7, robot.unseen ? 1 : 0);
      if (states_position(robot)) {
        wire::point(out, 8, robot.feed_position);
        wire::float32(out, 9, static_cast<float>(robot.radius50_mm));
        wire::float32(out, 10, static_cast<float>(robot.radius90_mm));
      }
    }
    wire::float64(out, 6, step.formation_probability);
    wire::float64(out, 7, step.confidence);
    wire::float64(out, 8, horizon_seconds(k, context.step_s));
  }
  wire::uint(out, 6, static_cast<std::uint32_t>(grid.length()));
  wire::uint(out, 7, static_cast<std::uint32_t>(grid.width()));
  wire::uint(out, 8, context.table_transitions);
  wire::float64(out, 9, context.step_s);
  const std::string_view color = to_string(context.opponent_color);
  wire::length(out, 10, color.size());
  std::memcpy(out.p, color.data(), color.size());
  out.p += color.size();
  const std::string_view model = to_string(context.model);
  wire::length(out, 11, model.size());
  std::memcpy(out.p, model.data(), model.size());
  out.p += model.size();
  const std::string_view game_state = to_string(context.game_state);
  wire::length(out, 12, game_state.size());
  std::memcpy(out.p, game_state.data(), game_state.size());
  out.p += game_state.size();
  buffer.resize(static_cast<std::size_t>(out.p - buffer.data()));
}

void fill_prediction_message(const Formation& current, const Prediction& prediction,
                             const PredictionContext& context, proto::FormationPrediction& out) {
  out.Clear();
  out.set_frame_number(current.frame_number);
  out.set_t_capture(current.time_s);
  set_cell(*out.mutable_centroid_cell(), current.centroid_cell);
  for (const FormationRobot& robot : current.robots) {
    proto::CurrentRobot& r = *out.add_robots();
    r.set_robot_id(robot.robot_id);
    r.set_state_index(robot.state);
    set_cell(*r.mutable_position_cell(), robot.cell);
    set_cell(*r.mutable_previous_cell(), robot.previous_cell);
    r.mutable_position()->set_x(static_cast<float>(robot.feed_position.x));
    r.mutable_position()->set_y(static_cast<float>(robot.feed_position.y));
  }
  const Grid& grid = context.codec->grid();
  for (std::size_t k = 0; k < prediction.steps.size(); ++k) {
    const PredictedStep& step = prediction.steps[k];
    proto::PredictedStep& s = *out.add_steps();
    s.set_step(static_cast<std::uint32_t>(k + 1));
    set_cell(*s.mutable_centroid_cell(), step.centroid);
    s.set_centroid_probability(step.centroid_probability);
    s.set_centroid_unseen(step.centroid_unseen);
    for (const RobotPrediction& robot : step.robots) {
      proto::PredictedRobot& r = *s.add_robots();
      r.set_robot_id(robot.robot_id);
      r.set_state_index(robot.state);
      set_cell(*r.mutable_position_cell(), robot.position);
      set_cell(*r.mutable_previous_cell(), robot.previous);
      // Back to the feed's own coordinates: the rotation is its own inverse.
      const Point centre =
          normalise(grid.centre_of(robot.position, context.field), context.opponent_attacks);
      r.mutable_cell_centre()->set_x(static_cast<float>(centre.x));
      r.mutable_cell_centre()->set_y(static_cast<float>(centre.y));
      r.set_probability(robot.probability);
      r.set_unseen(robot.unseen);
      if (states_position(robot)) {
        r.mutable_position()->set_x(static_cast<float>(robot.feed_position.x));
        r.mutable_position()->set_y(static_cast<float>(robot.feed_position.y));
        r.set_radius_50_mm(static_cast<float>(robot.radius50_mm));
        r.set_radius_90_mm(static_cast<float>(robot.radius90_mm));
      }
    }
    s.set_formation_probability(step.formation_probability);
    s.set_confidence(step.confidence);
    s.set_horizon_seconds(horizon_seconds(k, context.step_s));
  }
  out.set_grid_length(static_cast<std::uint32_t>(grid.length()));
  out.set_grid_width(static_cast<std::uint32_t>(grid.width()));
  out.set_table_transitions(context.table_transitions);
  out.set_step_seconds(context.step_s);
  out.set_opponent_color(std::string(to_string(context.opponent_color)));
  out.set_model(std::string(to_string(context.model)));
  out.set_game_state(std::string(to_string(context.game_state)));
}

namespace {

// "+2.0s", "+0.25s": one decimal unless the horizon needs more (up to three).
void append_horizon(std::string& line, double seconds) {
  int digits = 1;
  while (digits < 3) {
    const double scale = std::pow(10.0, digits);
    if (std::abs(std::round(seconds * scale) / scale - seconds) < 1e-9) break;
    ++digits;
  }
  char text[48];
  std::snprintf(text, sizeof text, " | +%.*fs C", digits, seconds);
  line += text;
}

// Rounded to whole millimetres, without a "-0".
double whole(double mm) {
  const double rounded = std::round(mm);
  return rounded == 0.0 ? 0.0 : rounded;
}

std::string describe(const Formation& current, const Prediction& prediction,
                     const PredictionContext* context) {
  // The models that state positions in mm are shown by them; the paper's by its cells.
  const bool motion = context && describe(context->model).states_positions;
  std::string line;
  char number[96];
  std::snprintf(number, sizeof number, "t=%.2f frame=%u now C", current.time_s,
                current.frame_number);
  line += number;
  append_cell(line, current.centroid_cell);
  line += " [";
  for (std::size_t i = 0; i < current.robots.size(); ++i) {
    if (i) line += ' ';
    line += std::to_string(current.robots[i].robot_id);
    line += ':';
    append_cell(line, current.robots[i].cell);
  }
  line += ']';
  for (std::size_t k = 0; k < prediction.steps.size(); ++k) {
    const PredictedStep& step = prediction.steps[k];
    if (motion) {
      append_horizon(line, horizon_seconds(k, context->step_s));
    } else {
      line += " | +" + std::to_string(k + 1) + " C";
    }
    append_cell(line, step.centroid);
    std::snprintf(number, sizeof number, " p=%.3f%s [", step.centroid_probability,
                  step.centroid_unseen ? " unseen" : "");
    line += number;
    for (std::size_t i = 0; i < step.robots.size(); ++i) {
      const RobotPrediction& robot = step.robots[i];
      if (motion) {
        // "r3 (1234,-567) r90=420mm p=0.62": where in the feed's mm, the 90% radius and the
        // probability of the predicted cell; '?' after the position when no counts backed it.
        std::snprintf(number, sizeof number, "%sr%u (%.0f,%.0f)%s r90=%.0fmm p=%.2f", i ? ", " : "",
                      robot.robot_id, whole(robot.feed_position.x), whole(robot.feed_position.y),
                      robot.unseen ? "?" : "", robot.radius90_mm, robot.probability);
        line += number;
        continue;
      }
      if (i) line += ' ';
      line += std::to_string(robot.robot_id);
      line += ':';
      append_cell(line, robot.position);
      if (robot.unseen) line += '?';
    }
    std::snprintf(number, sizeof number, "] conf=%.4g", step.confidence);
    line += number;
  }
  return line;
}

}  // namespace

std::string describe_prediction(const Formation& current, const Prediction& prediction) {
  return describe(current, prediction, nullptr);
}

std::string summarize_prediction(const Formation& current, const Prediction& prediction,
                                 const PredictionContext& context) {
  char text[256];
  int used = std::snprintf(text, sizeof text, "t=%.2f frame %u, %s, %zu robots:", current.time_s,
                           current.frame_number, std::string(to_string(context.model)).c_str(),
                           current.robots.size());
  for (std::size_t k = 0; k < prediction.steps.size() && k < 4 && used > 0 &&
                          used < static_cast<int>(sizeof text) - 48;
       ++k) {
    const PredictedStep& step = prediction.steps[k];
    double radius = 0.0;
    for (const RobotPrediction& robot : step.robots) radius += robot.radius90_mm;
    if (!step.robots.empty()) radius /= static_cast<double>(step.robots.size());
    used += radius > 0.0
                ? std::snprintf(text + used, sizeof text - static_cast<std::size_t>(used),
                                " +%.1fs r90 %.0f mm p %.2f",
                                static_cast<double>(k + 1) * context.step_s, radius,
                                step.formation_probability)
                : std::snprintf(text + used, sizeof text - static_cast<std::size_t>(used),
                                " +%.1fs p %.2f", static_cast<double>(k + 1) * context.step_s,
                                step.formation_probability);
  }
  return used > 0 ? std::string(text, std::min<std::size_t>(static_cast<std::size_t>(used),
                                                            sizeof text - 1))
                  : std::string();
}

std::string describe_prediction(const Formation& current, const Prediction& prediction,
                                const PredictionContext& context) {
  return describe(current, prediction, &context);
}

}  // namespace pipeline
}  // namespace ssl_formation
