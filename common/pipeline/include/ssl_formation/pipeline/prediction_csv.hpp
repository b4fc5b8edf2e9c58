#pragma once
// Predictions as CSV, one line per robot per predicted step: what `ssl-predictor --from-log`
// writes, so a team can look at what the predictor would have said during a recorded match.
// Numbers are written in their shortest exact form (std::to_chars), so a reader gets back the
// very doubles and floats the multicast FormationPrediction carries.
//
// Columns, in this order:
//   t_capture              the sample instant on the data clock, s
//   frame                  the detection frame that completed the sample
//   robot_id
//   step                   1 = the next formation
//   horizon_s              step x the sampling step, s
//   state_index            the predicted state
//   predicted_cell_x/_y    the predicted position cell
//   predicted_x_mm/_y_mm   that cell's centre in the feed's coordinates (as the message's float)
//   probability            the robot's probability of that state
//   unseen                 1 if the robot's state was never seen in training (it holds its cell)
//   centroid_cell_x/_y     the predicted centroid cell of this step
//   centroid_probability
//   formation_probability
//   confidence             product of formation probabilities up to this step
// then, appended for the motion model (the columns above are unchanged):
//   model                  "paper" or "motion"
//   predicted_feed_x_mm/_y_mm  where the model predicts the robot, in the feed's coordinates:
//                          the motion model's estimate, or for the paper's model the predicted
//                          cell's centre (then equal to predicted_x_mm/_y_mm)
//   radius_50_mm/_90_mm    the radii around that position holding the robot with 50% and 90%
//                          probability; 0 for the paper's model, which states none
// The millimetres and radii are written as the message's floats.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/result.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"

namespace ssl_formation {
inline namespace pipeline {

// The header line, with its newline.
std::string_view prediction_csv_header();

// Appends the lines of one prediction (each with its newline) to `out`.
void append_prediction_csv(const PredictedFormation& predicted, std::string& out);

// One instant's predictions read back from such a file (or any file with its key columns): the
// instant on the data clock and every step's robots, in the order of their steps.
struct RecordedPrediction {
  double time_s = 0.0;
  Prediction prediction;  // steps[k] is step k + 1; a robot's fields the file lacks stay default
};
struct RecordedPredictions {
  std::vector<RecordedPrediction> instants;  // in time order
  double step_s = 0.0;                       // horizon_s of step 1
  int steps = 0;                             // the most steps of any instant
  bool has_radii = false;                    // radius_50_mm and radius_90_mm were given
  bool has_cells = false;                    // predicted_cell_x/_y
  bool has_states = false;                   // state_index
  bool has_probabilities = false;            // probability (of the robot's cell)
  bool has_formation_probability = false;    // formation_probability
  // The grid the predictions' cells are on (the grid column, written since it was added; the same
  // on every line), none in a file without it.
  std::optional<Grid> grid;
};

// Reads predictions from CSV text with a header naming its columns, in any order: at least
// t_capture, robot_id, horizon_s, predicted_feed_x_mm and predicted_feed_y_mm; optionally step
// (else horizon_s over the smallest horizon), radius_50_mm, radius_90_mm, predicted_cell_x,
// predicted_cell_y, probability, state_index, formation_probability and grid (LxW). Every horizon
// must be a whole number of the smallest. The error names `source`, the line and the column.
Result<RecordedPredictions> parse_prediction_csv(std::string_view text, std::string_view source);
Result<RecordedPredictions> read_prediction_csv(const std::string& path);

}  // namespace pipeline
}  // namespace ssl_formation
