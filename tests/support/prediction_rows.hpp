#pragma once
// The CSV of `ssl-predictor --from-log` as the process tests read it, and what it must say for a
// multicast FormationPrediction, written here from the message's fields: so a test can hold the
// daemon's messages to the CSV line for line and number for number.

#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "formation_prediction.pb.h"

namespace ssl_formation::testing {

inline std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(text);
  while (std::getline(in, field, separator)) out.push_back(field);
  return out;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A number as the CSV must hold it: the shortest text that reads back as the same value.
template <typename Number>
std::string exact(Number value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

// The CSV's header and its columns.
inline constexpr const char* prediction_csv_header =
    "t_capture,frame,robot_id,step,horizon_s,state_index,predicted_cell_x,predicted_cell_y,"
    "predicted_x_mm,predicted_y_mm,probability,unseen,centroid_cell_x,centroid_cell_y,"
    "centroid_probability,formation_probability,confidence,model,predicted_feed_x_mm,"
    "predicted_feed_y_mm,radius_50_mm,radius_90_mm,grid,step_s";
enum PredictionColumn : std::size_t {
  column_t_capture = 0,
  column_horizon_s = 4,
  column_cell_centre_x = 8,
  column_cell_centre_y = 9,
  column_model = 17,
  column_feed_x = 18,
  column_feed_y = 19,
  column_radius_50 = 20,
  column_radius_90 = 21,
  column_grid = 22,
  column_step_s = 23,
  prediction_columns = 24,
};

// The CSV rows of one multicast prediction: the paper's 17 columns, then the model, where the
// robot is predicted to be in the feed's coordinates (the motion model's position, or the cell
// centre again for the paper's model, which states none), the 50%/90% radii (0 for the paper),
// and the grid and step that made them.
inline std::vector<std::string> rows_of(const proto::FormationPrediction& message) {
  std::vector<std::string> rows;
  for (const proto::PredictedStep& step : message.steps()) {
    for (const proto::PredictedRobot& robot : step.robots()) {
      rows.push_back(exact(message.t_capture()) + ',' + exact(message.frame_number()) + ',' +
                     exact(robot.robot_id()) + ',' + exact(step.step()) + ',' +
                     exact(static_cast<double>(step.step()) * message.step_seconds()) + ',' +
                     exact(robot.state_index()) + ',' + exact(robot.position_cell().x()) + ',' +
                     exact(robot.position_cell().y()) + ',' + exact(robot.cell_centre().x()) + ',' +
                     exact(robot.cell_centre().y()) + ',' + exact(robot.probability()) + ',' +
                     (robot.unseen() ? "1" : "0") + ',' + exact(step.centroid_cell().x()) + ',' +
                     exact(step.centroid_cell().y()) + ',' + exact(step.centroid_probability()) +
                     ',' + exact(step.formation_probability()) + ',' + exact(step.confidence()) +
                     ',' + message.model() + ',' +
                     exact(robot.has_position() ? robot.position().x() : robot.cell_centre().x()) +
                     ',' +
                     exact(robot.has_position() ? robot.position().y() : robot.cell_centre().y()) +
                     ',' + exact(robot.has_radius_50_mm() ? robot.radius_50_mm() : 0.0F) + ',' +
                     exact(robot.has_radius_90_mm() ? robot.radius_90_mm() : 0.0F) + ',' +
                     exact(message.grid_length()) + 'x' + exact(message.grid_width()) + ',' +
                     exact(message.step_seconds()));
    }
  }
  return rows;
}

// The CSV rows of every message, one after the other: what `--from-log` writes for the same
// frames.
inline std::vector<std::string> rows_of(const std::vector<proto::FormationPrediction>& messages) {
  std::vector<std::string> rows;
  for (const proto::FormationPrediction& message : messages) {
    const std::vector<std::string> more = rows_of(message);
    rows.insert(rows.end(), more.begin(), more.end());
  }
  return rows;
}

}  // namespace ssl_formation::testing
