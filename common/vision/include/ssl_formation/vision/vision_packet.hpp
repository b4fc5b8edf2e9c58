#pragma once
// Builds SSL-Vision packets with every field SSL-Vision marks required set: what the simulated
// producer sends and what tests feed the sampler.

#include <cstdint>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
inline namespace vision {

struct RobotDetection {
  std::uint32_t robot_id = 0;
  Point position;  // millimetres, feed coordinates
  float orientation = 0.0F;
  float confidence = 0.9F;
};

struct DetectionFrameSpec {
  std::uint32_t camera_id = 0;
  std::uint32_t frame_number = 0;
  double t_capture = 0.0;
  double t_sent = 0.0;  // 0: same as t_capture
  std::vector<RobotDetection> yellow;
  std::vector<RobotDetection> blue;
  std::vector<Point> balls;
};

SSL_WrapperPacket make_detection_packet(const DetectionFrameSpec& spec);

// The markings the rules give a field of this size ("Field Setup"): goals 1.8 m (Division A) or
// 1 m (B) wide and 180 mm deep, penalty areas 3.6 x 1.8 m (A) or 2 x 1 m (B), a centre circle of
// 0.5 m, 0.3 m of boundary. A field at least 10.5 m long (half way between the divisions'
// lengths) is Division A's.
FieldMarkings rules_markings(const FieldSize& field);

// The field's size with those markings, as SSL-Vision states them.
void fill_geometry(SSL_GeometryData& geometry, const FieldSize& field);
SSL_WrapperPacket make_geometry_packet(const FieldSize& field);

}  // namespace vision
}  // namespace ssl_formation
