#include "ssl_formation/pipeline/prediction_csv.hpp"

#include <charconv>

namespace ssl_formation {

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
         "predicted_feed_y_mm,radius_50_mm,radius_90_mm\n";
}

void append_prediction_csv(const PredictedFormation& predicted, std::string& out) {
  const Formation& formation = predicted.formation();
  const PredictionContext& context = predicted.context;
  const Grid& grid = context.codec->grid();
  const std::string_view model = to_string(context.model);
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
      out += '\n';
    }
  }
}

}  // namespace ssl_formation
