#pragma once
// The part of an SSL-Vision packet that sampling and the ball follower read (frame number,
// capture time, camera, robots, balls, field size) as plain values. Filled from a parsed
// SSL_WrapperPacket, or decoded straight from the datagram for the packets a live feed is made of
// (one detection frame each): on the daemons' hot path that skips protobuf's general parser, whose
// code and message objects cost microseconds when a daemon wakes with cold caches every 16 ms.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "ssl_formation/base/formation.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {
inline namespace vision {

struct VisionRobot {
  std::uint32_t robot_id = 0;
  bool has_robot_id = false;  // robot_id is optional in SSL-Vision's schema
  float x = 0.0F;             // millimetres, feed coordinates
  float y = 0.0F;
  float confidence = 0.0F;
};

struct VisionBall {
  float x = 0.0F;  // millimetres, feed coordinates
  float y = 0.0F;
  float confidence = 0.0F;
};

struct VisionDetection {
  std::uint32_t frame_number = 0;
  double t_capture = 0.0;
  std::uint32_t camera_id = 0;
  std::vector<VisionRobot> robots_yellow;
  std::vector<VisionRobot> robots_blue;
  std::vector<VisionBall> balls;  // every ball candidate the camera saw, in the packet's order

  const std::vector<VisionRobot>& robots(TeamColor color) const {
    return color == TeamColor::yellow ? robots_yellow : robots_blue;
  }
};

// The markings a geometry packet states besides the field's size (geometry.field, millimetres),
// for drawing the field as SSL-Vision's client does; 0 where the packet leaves an optional one
// out (older senders state no penalty area or centre circle).
struct FieldMarkings {
  std::int32_t goal_width = 0;
  std::int32_t goal_depth = 0;
  std::int32_t boundary_width = 0;
  std::int32_t penalty_area_depth = 0;
  std::int32_t penalty_area_width = 0;
  std::int32_t center_circle_radius = 0;
  friend bool operator==(const FieldMarkings&, const FieldMarkings&) = default;
};

struct VisionFrame {
  bool has_detection = false;
  VisionDetection detection;  // meaningful only if has_detection
  bool has_geometry = false;
  std::int32_t field_length = 0;  // geometry.field, millimetres; only if has_geometry
  std::int32_t field_width = 0;
  FieldMarkings markings;  // only if has_geometry
};

// Overwrites `frame` with what `packet` holds (the vectors keep their capacity).
void to_vision_frame(const SSL_WrapperPacket& packet, VisionFrame& frame);

// Decodes `datagram` into `frame` if it is an SSL_WrapperPacket holding exactly one detection
// frame, every proto2-required field present, every singular field at most once, every field
// known to our schema, every varint within 32 bits: what SSL-Vision, grSim and ssl-producer send 60
// times a second. Returns false for anything else (geometry, unknown or repeated fields, damaged
// bytes), with `frame` unspecified: parse those with protobuf, which decides whether they are
// valid. When it returns true, protobuf's parser would accept the datagram and to_vision_frame() on
// the parsed packet would give the same frame.
bool decode_detection_datagram(std::span<const std::byte> datagram, VisionFrame& frame);

enum class VisionDatagram { decoded_directly, parsed_by_protobuf, invalid };

// What a daemon does with a vision datagram: decode_detection_datagram() if it takes it, else
// protobuf's parser (into `scratch`, reused between calls) and to_vision_frame(). `invalid` is
// protobuf's verdict: bytes it cannot parse or a proto2-required field missing.
VisionDatagram read_vision_datagram(std::span<const std::byte> datagram, VisionFrame& frame,
                                    SSL_WrapperPacket& scratch);

}  // namespace vision
}  // namespace ssl_formation
