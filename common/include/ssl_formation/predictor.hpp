#pragma once
// The prediction algorithm of the paper (§5) as DESIGN.md §3 makes it precise: the most likely
// next centroid from the centroid-block matrix, then for each robot the most likely
// velocity-consistent state within that block, P(formation) and the confidence chain.

#include <cstdint>
#include <vector>

#include "ssl_formation/formation.hpp"
#include "ssl_formation/transition_table.hpp"

namespace ssl_formation {

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
};

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

// One robot as the predictor sees it: an id and a state.
struct RobotStateById {
  std::uint32_t robot_id = 0;
  StateIndex state = 0;
};

// Predicts `horizon` steps from robots that share one centroid. Reuses `out`'s storage, so a
// daemon that keeps one Prediction allocates nothing per packet once warmed up.
void predict(const TransitionTable& table, const std::vector<RobotStateById>& robots, int horizon,
             Prediction& out);
Prediction predict(const TransitionTable& table, const Formation& formation, int horizon);

std::vector<RobotStateById> robot_states(const Formation& formation);
std::vector<RobotStateById> robot_states(const PredictedStep& step);

}  // namespace ssl_formation
