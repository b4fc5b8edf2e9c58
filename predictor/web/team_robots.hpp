#pragma once
// Our own team's robots as the latest detection frames show them, for the field view: the sampler
// keeps only the opponent. Robots are merged by id across cameras (the newest detection wins) and
// forgotten when no camera has reported them for a while. Pure: fed packet by packet.

#include <cstdint>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/vision/vision_frame.hpp"

namespace ssl_formation::predictor::web {

struct TeamRobot {
  std::uint32_t robot_id = 0;
  double x = 0.0;  // millimetres, feed coordinates
  double y = 0.0;
  double time_s = 0.0;  // t_capture of the detection
};

class TeamRobots {
 public:
  // `color` is the team to follow; robots not seen within `timeout_s` of data time before the
  // newest frame are dropped, and a frame more than `clock_reset_s` older than the newest one
  // means the data clock restarted.
  TeamRobots(TeamColor color, double timeout_s, double clock_reset_s);

  void add(const VisionDetection& frame);
  // The robots seen within the timeout, sorted by id.
  const std::vector<TeamRobot>& current();
  void clear();
  // Follows the other team from now on (the referee named another opponent): forgets this one.
  void set_color(TeamColor color) {
    if (color == color_) return;
    color_ = color;
    clear();
  }

 private:
  TeamColor color_;
  double timeout_s_;
  double clock_reset_s_;
  double newest_s_ = 0.0;
  bool any_ = false;
  std::vector<TeamRobot> robots_;  // sorted by id
};

}  // namespace ssl_formation::predictor::web
