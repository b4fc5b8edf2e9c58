#include "ssl_formation/match/tracked_vision.hpp"

#include <cmath>

namespace ssl_formation {

void to_vision_frame(const TrackedFrame& tracked, VisionFrame& frame,
                     std::uint64_t& without_team) {
  frame.has_geometry = false;
  frame.has_detection = true;
  VisionDetection& d = frame.detection;
  d.frame_number = tracked.frame_number();
  d.t_capture = tracked.timestamp();
  d.camera_id = 0;
  d.robots_yellow.clear();
  d.robots_blue.clear();
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
    out.x = static_cast<float>(static_cast<double>(robot.pos().x()) * 1000.0);
    out.y = static_cast<float>(static_cast<double>(robot.pos().y()) * 1000.0);
    out.confidence = robot.has_visibility() ? robot.visibility() : 1.0F;
    (id.team() == YELLOW ? d.robots_yellow : d.robots_blue).push_back(out);
  }
}

bool TrackedVision::add(std::string_view payload, double receive_s, VisionFrame& frame) {
  ++counters_.packets;
  if (!packet_.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) {
    ++counters_.undecodable;
    return false;
  }
  if (packet_.uuid() != uuid_) {
    const bool silent = receive_s - last_s_ > source_timeout_s || receive_s < last_s_;
    if (!uuid_.empty() && !silent) {
      ++counters_.other_source;
      return false;
    }
    if (!uuid_.empty()) ++counters_.source_switches;
    uuid_ = packet_.uuid();
    name_ = packet_.source_name();
    source_changed_ = true;
  }
  last_s_ = receive_s;
  if (!packet_.has_tracked_frame()) {
    ++counters_.without_frame;
    return false;
  }
  to_vision_frame(packet_.tracked_frame(), frame, counters_.robots_without_team);
  ++counters_.frames;
  return true;
}

}  // namespace ssl_formation
