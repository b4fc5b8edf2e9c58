#pragma once
// The prediction algorithm of the paper (§5), made precise in docs/models.md: the most likely
// next centroid from the centroid-block matrix, then for each robot the most likely
// velocity-consistent state within that block, P(formation) and the confidence chain.

#include <cstdint>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/model_api/transition_table.hpp"

namespace ssl_formation {
inline namespace paper_model {

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

}  // namespace paper_model
}  // namespace ssl_formation
