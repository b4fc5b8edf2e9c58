#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
inline namespace vision {

namespace {

void fill_robot(SSL_DetectionRobot& out, const RobotDetection& robot) {
  out.set_confidence(robot.confidence);
  out.set_robot_id(robot.robot_id);
  out.set_x(static_cast<float>(robot.position.x));
  out.set_y(static_cast<float>(robot.position.y));
  out.set_orientation(robot.orientation);
  // A plausible image position: SSL-Vision reports both; consumers of formations ignore it.
  out.set_pixel_x(static_cast<float>(robot.position.x / 10.0 + 390.0));
  out.set_pixel_y(static_cast<float>(robot.position.y / 10.0 + 290.0));
  out.set_height(150.0F);
}

}  // namespace

SSL_WrapperPacket make_detection_packet(const DetectionFrameSpec& spec) {
  SSL_WrapperPacket packet;
  SSL_DetectionFrame& frame = *packet.mutable_detection();
  frame.set_frame_number(spec.frame_number);
  frame.set_t_capture(spec.t_capture);
  frame.set_t_sent(spec.t_sent != 0.0 ? spec.t_sent : spec.t_capture);
  frame.set_camera_id(spec.camera_id);
  for (const Point& ball : spec.balls) {
    SSL_DetectionBall& out = *frame.add_balls();
    out.set_confidence(0.95F);
    out.set_area(80);
    out.set_x(static_cast<float>(ball.x));
    out.set_y(static_cast<float>(ball.y));
    out.set_z(0.0F);
    out.set_pixel_x(static_cast<float>(ball.x / 10.0 + 390.0));
    out.set_pixel_y(static_cast<float>(ball.y / 10.0 + 290.0));
  }
  for (const RobotDetection& robot : spec.yellow) fill_robot(*frame.add_robots_yellow(), robot);
  for (const RobotDetection& robot : spec.blue) fill_robot(*frame.add_robots_blue(), robot);
  return packet;
}

FieldMarkings rules_markings(const FieldSize& field) {
  const bool division_a = field.length_mm >= 10500.0;
  return FieldMarkings{division_a ? 1800 : 1000, 180, 300, division_a ? 1800 : 1000,
                       division_a ? 3600 : 2000, 500};
}

void fill_geometry(SSL_GeometryData& geometry, const FieldSize& field) {
  SSL_GeometryFieldSize& size = *geometry.mutable_field();
  const FieldMarkings m = rules_markings(field);
  size.set_field_length(static_cast<std::int32_t>(field.length_mm));
  size.set_field_width(static_cast<std::int32_t>(field.width_mm));
  size.set_goal_width(m.goal_width);
  size.set_goal_depth(m.goal_depth);
  size.set_boundary_width(m.boundary_width);
  size.set_penalty_area_depth(m.penalty_area_depth);
  size.set_penalty_area_width(m.penalty_area_width);
  size.set_center_circle_radius(m.center_circle_radius);
}

SSL_WrapperPacket make_geometry_packet(const FieldSize& field) {
  SSL_WrapperPacket packet;
  fill_geometry(*packet.mutable_geometry(), field);
  return packet;
}

}  // namespace vision
}  // namespace ssl_formation
