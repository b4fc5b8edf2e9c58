#include "ssl_formation/paper_model/measures.hpp"

#include <algorithm>
#include <cstdlib>

namespace ssl_formation {
inline namespace paper_model {

namespace {
const RobotStateById* find(const std::vector<RobotStateById>& robots, std::uint32_t robot_id) {
  const auto it = std::find_if(robots.begin(), robots.end(),
                               [&](const RobotStateById& r) { return r.robot_id == robot_id; });
  return it == robots.end() ? nullptr : &*it;
}
}  // namespace

int count_measure(const std::vector<RobotStateById>& predicted,
                  const std::vector<RobotStateById>& reference) {
  int count = 0;
  for (const RobotStateById& ref : reference) {
    const RobotStateById* match = find(predicted, ref.robot_id);
    if (!match || match->state != ref.state) ++count;
  }
  return count;
}

int distance_measure(const StateCodec& codec, const std::vector<RobotStateById>& predicted,
                     const std::vector<RobotStateById>& reference) {
  const Grid& grid = codec.grid();
  int distance = 0;
  for (const RobotStateById& ref : reference) {
    const RobotStateById* match = find(predicted, ref.robot_id);
    if (!match) continue;
    const Cell a = grid.cell_from_id(static_cast<int>(codec.position_id(match->state)));
    const Cell b = grid.cell_from_id(static_cast<int>(codec.position_id(ref.state)));
    distance += std::abs(a.x - b.x) + std::abs(a.y - b.y);
  }
  return distance;
}

}  // namespace paper_model
}  // namespace ssl_formation
