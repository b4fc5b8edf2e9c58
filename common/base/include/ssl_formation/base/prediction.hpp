#pragma once
// A prediction as every model states it: for each step ahead, the predicted centroid cell and,
// for each robot, its predicted cell and state, its position in millimetres, the radii that hold
// it with 50% and 90% probability and the probability that its cell is right. The paper's model,
// the motion model and the baselines all fill this; the wire message, the CSV, the field view and
// the evaluation all read it.

#include <cmath>
#include <cstdint>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/state.hpp"

namespace ssl_formation {
inline namespace base {

struct RobotPrediction {
  std::uint32_t robot_id = 0;
  StateIndex state = 0;
  Cell position;
  Cell previous;
  double probability = 0.0;
  bool unseen = false;  // no candidate was ever counted: the robot holds its cell
  // The predicted position in the feed's coordinates (mm): the motion model's estimate, or for
  // the paper's model the centre of the predicted cell (filled by the PredictionPipeline).
  Point feed_position;
  Point normalised_position;
  // Radii (mm) around feed_position holding the robot with 50% and 90% probability, and the
  // expected squared error; 0 when the model states none (the paper's).
  double radius50_mm = 0.0;
  double radius90_mm = 0.0;
  double mean_square_mm2 = 0.0;
  bool stays = false;  // forecast where it stands (the motion model's standing robots)
};

// A robot's factor in its formation's probability, the product over the team. Robots that stay
// stay together (a team standing in a stoppage, or set for a restart), so the product of their
// probabilities as independent ones understates the formation's: each counts as the square
// root of its own. On the tuning seeds of the simulated match (11/12, 13/14, 15/16, 17/18 with
// 3 mm of noise) the formations' ECE was at most 0.049 / 0.043 / 0.054 / 0.050 at any horizon
// with every robot whole, 0.042 / 0.031 / 0.037 / 0.030 so (docs/results.md).
inline double formation_factor(const RobotPrediction& robot, double probability) {
  return robot.stays ? std::sqrt(probability) : probability;
}

struct PredictedStep {
  Cell centroid;
  double centroid_probability = 0.0;
  bool centroid_unseen = false;  // the centroid row is empty: the centroid stays
  std::vector<RobotPrediction> robots;
  double formation_probability = 0.0;
  double confidence = 0.0;  // product of formation probabilities up to this step
};

struct Prediction {
  std::vector<PredictedStep> steps;  // steps[0] is the next formation
};

}  // namespace base
}  // namespace ssl_formation
