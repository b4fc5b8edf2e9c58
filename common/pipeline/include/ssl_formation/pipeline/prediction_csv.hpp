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

#include <string>
#include <string_view>

#include "ssl_formation/pipeline/prediction_pipeline.hpp"

namespace ssl_formation {

// The header line, with its newline.
std::string_view prediction_csv_header();

// Appends the lines of one prediction (each with its newline) to `out`.
void append_prediction_csv(const PredictedFormation& predicted, std::string& out);

}  // namespace ssl_formation
