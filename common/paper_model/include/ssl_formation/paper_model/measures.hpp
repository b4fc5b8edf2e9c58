#pragma once
// The paper's evaluation measures (§6.1), robots matched by id.

#include <vector>

#include "ssl_formation/base/state.hpp"
#include "ssl_formation/paper_model/predictor.hpp"

namespace ssl_formation {
inline namespace paper_model {

// Reference robots whose predicted state differs, or that the prediction lacks.
int count_measure(const std::vector<RobotStateById>& predicted,
                  const std::vector<RobotStateById>& reference);

// Sum over robots in both of the Manhattan distance, in cells, between position cells.
int distance_measure(const StateCodec& codec, const std::vector<RobotStateById>& predicted,
                     const std::vector<RobotStateById>& reference);

}  // namespace paper_model
}  // namespace ssl_formation
