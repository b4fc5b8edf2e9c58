#include "ssl_formation/prediction_message.hpp"

#include <cstdio>

namespace ssl_formation {

namespace {

void set_cell(proto::GridCell& out, Cell cell) {
  out.set_x(static_cast<std::uint32_t>(cell.x));
  out.set_y(static_cast<std::uint32_t>(cell.y));
}

void append_cell(std::string& out, Cell cell) {
  out += '(';
  out += std::to_string(cell.x);
  out += ',';
  out += std::to_string(cell.y);
  out += ')';
}

}  // namespace

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
      const Point centre = normalise(grid.centre_of(robot.position, context.field), context.opponent_attacks);
      r.mutable_cell_centre()->set_x(static_cast<float>(centre.x));
      r.mutable_cell_centre()->set_y(static_cast<float>(centre.y));
      r.set_probability(robot.probability);
      r.set_unseen(robot.unseen);
    }
    s.set_formation_probability(step.formation_probability);
    s.set_confidence(step.confidence);
  }
  out.set_grid_length(static_cast<std::uint32_t>(grid.length()));
  out.set_grid_width(static_cast<std::uint32_t>(grid.width()));
  out.set_table_transitions(context.table_transitions);
  out.set_step_seconds(context.step_s);
  out.set_opponent_color(std::string(to_string(context.opponent_color)));
}

std::string describe_prediction(const Formation& current, const Prediction& prediction) {
  std::string line;
  char number[64];
  std::snprintf(number, sizeof number, "t=%.2f frame=%u now C", current.time_s, current.frame_number);
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
    line += " | +" + std::to_string(k + 1) + " C";
    append_cell(line, step.centroid);
    std::snprintf(number, sizeof number, " p=%.3f%s [", step.centroid_probability,
                  step.centroid_unseen ? " unseen" : "");
    line += number;
    for (std::size_t i = 0; i < step.robots.size(); ++i) {
      if (i) line += ' ';
      line += std::to_string(step.robots[i].robot_id);
      line += ':';
      append_cell(line, step.robots[i].position);
      if (step.robots[i].unseen) line += '?';
    }
    std::snprintf(number, sizeof number, "] conf=%.4g", step.confidence);
    line += number;
  }
  return line;
}

}  // namespace ssl_formation
