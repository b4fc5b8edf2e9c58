#include "ssl_formation/motion_model/braking_advice.hpp"

#include <algorithm>
#include <cmath>

namespace ssl_formation {
inline namespace motion_model {

bool braking_advice_holds(GamePhase phase) {
  return phase == GamePhase::stop || phase == GamePhase::ball_placement_opponent ||
         phase == GamePhase::ball_placement_us || phase == GamePhase::free_kick_opponent;
}

void advise_braking(const std::vector<MotionRobot>& robots, double velocity_window_s, double step_s,
                    int steps, SetPlayAdvice& advice) {
  if (advice.robots.size() != robots.size()) {
    advice.robots.assign(robots.size(), SetPlayAdvice::Robot{});
    advice.any = false;
  }
  for (std::size_t r = 0; r < robots.size(); ++r) {
    const MotionRobot& robot = robots[r];
    SetPlayAdvice::Robot& out = advice.robots[r];
    const bool advised =
        std::any_of(out.weight.begin(), out.weight.end(), [](double w) { return w > 0.0; });
    if (advised || !robot.has_velocity) continue;
    const Point v = robot.kinematics.velocity;
    const double speed = std::hypot(v.x, v.y);
    if (speed < BrakingPath::min_speed_mm_s) continue;
    const Point heading{v.x / speed, v.y / speed};
    const Point change = robot.kinematics.velocity_change;
    const double braking = -(change.x * heading.x + change.y * heading.y) / velocity_window_s;
    if (braking < BrakingPath::min_braking_mm_s2) continue;
    const double stops_after_s = speed / braking;
    const int advised_steps = std::min(steps, static_cast<int>(out.weight.size()));
    for (int k = 0; k < advised_steps; ++k) {
      const double t = std::min((k + 1) * step_s, stops_after_s);
      const double travelled = speed * t - 0.5 * braking * t * t;
      out.position[static_cast<std::size_t>(k)] = {robot.position.x + heading.x * travelled,
                                                   robot.position.y + heading.y * travelled};
      out.weight[static_cast<std::size_t>(k)] = BrakingPath::weight;
    }
    advice.any = advice.any || advised_steps > 0;
  }
}

}  // namespace motion_model
}  // namespace ssl_formation
