#pragma once
// A tracker's frame of moving robots (moving_robots.hpp), as TrackerWrapperPacket bytes with
// positions in metres, and the raw SSL-Vision frame of the same positions.

#include <string>

#include "moving_robots.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper_tracked.pb.h"

namespace ssl_formation::testing {

// Robot i of the yellow team at frame f (60 Hz), millimetres.
inline Point tracked_robot_position(int i, int f, int seed) {
  return moving_robot_position(static_cast<std::uint64_t>(seed), i, f / 60.0);
}

// Six yellow robots at frame f from `start_s`, as SSL-Vision reports them.
inline SSL_WrapperPacket raw_frame_of_six(int f, double start_s, int seed) {
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(f);
  spec.t_capture = start_s + f / 60.0;
  for (int i = 0; i < 6; ++i) {
    spec.yellow.push_back({static_cast<std::uint32_t>(i), tracked_robot_position(i, f, seed)});
  }
  return make_detection_packet(spec);
}

// The same robots as tracker `uuid` reports them; with `stray`, a robot of no team besides.
inline std::string tracked_frame_of_six(int f, double start_s, const std::string& uuid, int seed,
                                        bool stray = false) {
  TrackerWrapperPacket packet;
  packet.set_uuid(uuid);
  packet.set_source_name("tracker " + uuid);
  TrackedFrame& frame = *packet.mutable_tracked_frame();
  frame.set_frame_number(static_cast<std::uint32_t>(f));
  frame.set_timestamp(start_s + f / 60.0);
  for (int i = 0; i < 6; ++i) {
    TrackedRobot& robot = *frame.add_robots();
    robot.mutable_robot_id()->set_id(static_cast<std::uint32_t>(i));
    robot.mutable_robot_id()->set_team(YELLOW);
    const Point p = tracked_robot_position(i, f, seed);
    robot.mutable_pos()->set_x(static_cast<float>(p.x / 1000.0));
    robot.mutable_pos()->set_y(static_cast<float>(p.y / 1000.0));
    robot.set_orientation(0.0F);
  }
  if (stray) {
    // A robot the tracker could not place in a team: left out.
    TrackedRobot& robot = *frame.add_robots();
    robot.mutable_robot_id()->set_id(9);
    robot.mutable_pos()->set_x(0.0F);
    robot.mutable_pos()->set_y(0.0F);
    robot.set_orientation(0.0F);
  }
  return packet.SerializeAsString();
}

}  // namespace ssl_formation::testing
