#include "team_robots.hpp"

#include <algorithm>
#include <cmath>

namespace ssl_formation::predictor::web {

namespace {
// Same sanity limits as the sampler: ids and coordinates beyond these are not a real robot.
constexpr std::uint32_t max_robot_id = 1000;
constexpr double max_abs_coordinate_mm = 100000.0;
}  // namespace

TeamRobots::TeamRobots(TeamColor color, double timeout_s, double clock_reset_s)
    : color_(color), timeout_s_(timeout_s), clock_reset_s_(clock_reset_s) {}

void TeamRobots::clear() {
  robots_.clear();
  any_ = false;
  newest_s_ = 0.0;
}

void TeamRobots::add(const VisionDetection& frame) {
  const double t = frame.t_capture;
  if (!std::isfinite(t)) return;
  if (any_ && t < newest_s_ - clock_reset_s_) clear();
  if (!any_ || t > newest_s_) newest_s_ = t;
  any_ = true;
  for (const VisionRobot& robot : frame.robots(color_)) {
    if (!robot.has_robot_id || robot.robot_id > max_robot_id) continue;
    const double x = robot.x;
    const double y = robot.y;
    if (!std::isfinite(x) || !std::isfinite(y) || std::abs(x) > max_abs_coordinate_mm ||
        std::abs(y) > max_abs_coordinate_mm) {
      continue;
    }
    const auto at =
        std::lower_bound(robots_.begin(), robots_.end(), robot.robot_id,
                         [](const TeamRobot& r, std::uint32_t id) { return r.robot_id < id; });
    if (at != robots_.end() && at->robot_id == robot.robot_id) {
      if (t >= at->time_s) *at = TeamRobot{robot.robot_id, x, y, t};  // newest wins
    } else {
      robots_.insert(at, TeamRobot{robot.robot_id, x, y, t});
    }
  }
}

const std::vector<TeamRobot>& TeamRobots::current() {
  std::erase_if(robots_, [&](const TeamRobot& r) { return r.time_s < newest_s_ - timeout_s_; });
  return robots_;
}

}  // namespace ssl_formation::predictor::web
