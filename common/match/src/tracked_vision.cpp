#include "ssl_formation/match/tracked_vision.hpp"

#include <cmath>

#include "ssl_formation/base/wire_text.hpp"

namespace ssl_formation {
inline namespace match {

namespace {
// Metres (as the tracker sends them) to millimetres, in double.
double mm(float metres) { return static_cast<double>(metres) * 1000.0; }
}  // namespace

void to_vision_frame(const TrackedFrame& tracked, VisionFrame& frame, std::uint64_t& without_team) {
  frame.has_geometry = false;
  frame.has_detection = true;
  VisionDetection& d = frame.detection;
  d.frame_number = tracked.frame_number();
  d.t_capture = tracked.timestamp();
  d.camera_id = 0;
  d.robots_yellow.clear();
  d.robots_blue.clear();
  d.balls.clear();
  for (const TrackedBall& ball : tracked.balls()) {
    d.balls.push_back({static_cast<float>(mm(ball.pos().x())),
                       static_cast<float>(mm(ball.pos().y())),
                       ball.has_visibility() ? ball.visibility() : 1.0F});
  }
  for (const TrackedRobot& robot : tracked.robots()) {
    const RobotId& id = robot.robot_id();
    if (!id.has_id() || !(id.team() == YELLOW || id.team() == BLUE)) {
      ++without_team;
      continue;
    }
    VisionRobot out;
    out.robot_id = id.id();
    out.has_robot_id = true;
    // Metres to the raw vision's millimetres (in float, as SSL-Vision sends them).
    out.x = static_cast<float>(mm(robot.pos().x()));
    out.y = static_cast<float>(mm(robot.pos().y()));
    out.confidence = robot.has_visibility() ? robot.visibility() : 1.0F;
    (id.team() == YELLOW ? d.robots_yellow : d.robots_blue).push_back(out);
  }
}

std::optional<BallState> tracked_ball(const TrackedFrame& tracked) {
  const TrackedBall* best = nullptr;
  float best_visibility = 0.0F;
  for (const TrackedBall& ball : tracked.balls()) {
    if (!std::isfinite(ball.pos().x()) || !std::isfinite(ball.pos().y())) continue;
    const float visibility = ball.has_visibility() ? ball.visibility() : 1.0F;
    if (best == nullptr || visibility > best_visibility) {
      best = &ball;
      best_visibility = visibility;
    }
  }
  if (best == nullptr) return std::nullopt;
  BallState state;
  state.time_s = tracked.timestamp();
  state.position = Point{mm(best->pos().x()), mm(best->pos().y())};
  if (best->has_vel() && std::isfinite(best->vel().x()) && std::isfinite(best->vel().y())) {
    state.velocity = Point{mm(best->vel().x()), mm(best->vel().y())};
  }
  return state;
}

bool TrackedVision::add(std::string_view payload, double receive_s, VisionFrame& frame) {
  ++counters_.packets;
  if (!packet_.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) {
    ++counters_.undecodable;
    return false;
  }
  // The tracker's id and name as the logs and the field view may show them (wire_text.hpp).
  if (std::string uuid = printable_wire_text(packet_.uuid()); uuid != uuid_) {
    const bool silent = receive_s - last_s_ > source_timeout_s || receive_s < last_s_;
    if (!uuid_.empty() && !silent) {
      ++counters_.other_source;
      return false;
    }
    if (!uuid_.empty()) ++counters_.source_switches;
    uuid_ = std::move(uuid);
    name_ = printable_wire_text(packet_.source_name());
  }
  last_s_ = receive_s;
  if (!packet_.has_tracked_frame()) {
    ++counters_.without_frame;
    return false;
  }
  to_vision_frame(packet_.tracked_frame(), frame, counters_.robots_without_team);
  ball_ = tracked_ball(packet_.tracked_frame());
  ++counters_.frames;
  return true;
}

}  // namespace match
}  // namespace ssl_formation
