// Tracked vision (common/match/src/tracked_vision.cpp): a tracker's frames in millimetres, one
// tracker followed by its uuid, another taking over only once the first falls silent for a second.

#include "ssl_formation/match/tracked_vision.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>

namespace ssl_formation {
namespace {

std::string packet(const std::string& uuid, std::uint32_t frame_number, double timestamp,
                   float x_m) {
  TrackerWrapperPacket wrapper;
  wrapper.set_uuid(uuid);
  wrapper.set_source_name("name of " + uuid);
  TrackedFrame& frame = *wrapper.mutable_tracked_frame();
  frame.set_frame_number(frame_number);
  frame.set_timestamp(timestamp);
  TrackedRobot& blue = *frame.add_robots();
  blue.mutable_robot_id()->set_id(3);
  blue.mutable_robot_id()->set_team(BLUE);
  blue.mutable_pos()->set_x(x_m);
  blue.mutable_pos()->set_y(-1.5F);
  blue.set_orientation(0.0F);
  blue.set_visibility(0.75F);
  TrackedRobot& yellow = *frame.add_robots();
  yellow.mutable_robot_id()->set_id(5);
  yellow.mutable_robot_id()->set_team(YELLOW);
  yellow.mutable_pos()->set_x(0.25F);
  yellow.mutable_pos()->set_y(2.0F);
  yellow.set_orientation(1.0F);
  TrackedRobot& unknown = *frame.add_robots();
  unknown.mutable_robot_id()->set_id(6);
  unknown.mutable_robot_id()->set_team(UNKNOWN);
  unknown.mutable_pos()->set_x(0.0F);
  unknown.mutable_pos()->set_y(0.0F);
  unknown.set_orientation(0.0F);
  return wrapper.SerializeAsString();
}

TEST(TrackedVision, FramesComeInMillimetresByTeamOnCameraZero) {
  TrackedVision tracked;
  VisionFrame frame;
  ASSERT_TRUE(tracked.add(packet("a", 17, 1234.5, 1.5F), 0.0, frame));
  EXPECT_TRUE(frame.has_detection);
  EXPECT_FALSE(frame.has_geometry);
  EXPECT_EQ(frame.detection.frame_number, 17u);
  EXPECT_EQ(frame.detection.t_capture, 1234.5);
  EXPECT_EQ(frame.detection.camera_id, 0u);
  ASSERT_EQ(frame.detection.robots_blue.size(), 1u);
  ASSERT_EQ(frame.detection.robots_yellow.size(), 1u);
  EXPECT_EQ(frame.detection.robots_blue[0].robot_id, 3u);
  EXPECT_TRUE(frame.detection.robots_blue[0].has_robot_id);
  EXPECT_FLOAT_EQ(frame.detection.robots_blue[0].x, 1500.0F);
  EXPECT_FLOAT_EQ(frame.detection.robots_blue[0].y, -1500.0F);
  EXPECT_FLOAT_EQ(frame.detection.robots_blue[0].confidence, 0.75F);
  EXPECT_FLOAT_EQ(frame.detection.robots_yellow[0].x, 250.0F);
  EXPECT_FLOAT_EQ(frame.detection.robots_yellow[0].confidence, 1.0F);  // no visibility given
  // The robot of no team is left out, and counted.
  EXPECT_EQ(tracked.counters().robots_without_team, 1u);
  EXPECT_EQ(tracked.source_uuid(), "a");
  EXPECT_EQ(tracked.source_name(), "name of a");
}

TEST(TrackedVision, ASecondTrackerIsIgnoredUntilTheFirstFallsSilentForASecond) {
  TrackedVision tracked;
  VisionFrame frame;
  ASSERT_TRUE(tracked.add(packet("a", 1, 10.0, 1.0F), 100.0, frame));
  EXPECT_FALSE(tracked.add(packet("b", 1, 10.0, 2.0F), 100.01, frame));
  EXPECT_TRUE(tracked.add(packet("a", 2, 10.016, 1.0F), 100.5, frame));
  EXPECT_FALSE(tracked.add(packet("b", 2, 10.016, 2.0F), 101.4, frame));  // a spoke 0.9 s ago
  EXPECT_EQ(tracked.counters().other_source, 2u);
  EXPECT_EQ(tracked.source_uuid(), "a");
  // a silent for more than a second: b takes over, and from then on a is the other one.
  ASSERT_TRUE(tracked.add(packet("b", 3, 10.032, 2.0F), 101.6, frame));
  EXPECT_FLOAT_EQ(frame.detection.robots_blue[0].x, 2000.0F);
  EXPECT_EQ(tracked.source_uuid(), "b");
  EXPECT_EQ(tracked.counters().source_switches, 1u);
  EXPECT_FALSE(tracked.add(packet("a", 3, 10.032, 1.0F), 101.7, frame));
  EXPECT_EQ(tracked.counters().frames, 3u);
}

TEST(TrackedVision, BadInputIsCountedNeverThrown) {
  TrackedVision tracked;
  VisionFrame frame;
  EXPECT_FALSE(tracked.add("\xff\xff\xff", 0.0, frame));
  EXPECT_FALSE(tracked.add("", 0.0, frame));  // no uuid: a required field missing
  EXPECT_EQ(tracked.counters().undecodable, 2u);
  TrackerWrapperPacket no_frame;
  no_frame.set_uuid("a");
  EXPECT_FALSE(tracked.add(no_frame.SerializeAsString(), 0.0, frame));
  EXPECT_EQ(tracked.counters().without_frame, 1u);
  EXPECT_EQ(tracked.counters().packets, 3u);
}

// A tracked ball at (x, y, z) metres, with a velocity in metres per second unless none.
void add_ball(TrackedFrame& frame, float x, float y, float z, std::optional<Point> velocity,
              std::optional<float> visibility) {
  TrackedBall& ball = *frame.add_balls();
  ball.mutable_pos()->set_x(x);
  ball.mutable_pos()->set_y(y);
  ball.mutable_pos()->set_z(z);
  if (velocity) {
    ball.mutable_vel()->set_x(static_cast<float>(velocity->x));
    ball.mutable_vel()->set_y(static_cast<float>(velocity->y));
    ball.mutable_vel()->set_z(0.5F);
  }
  if (visibility) ball.set_visibility(*visibility);
}

TEST(TrackedVision, TheBallComesInMillimetresWithItsVelocity) {
  TrackerWrapperPacket wrapper;
  ASSERT_TRUE(wrapper.ParseFromString(packet("a", 5, 300.25, 1.0F)));
  TrackedFrame& f = *wrapper.mutable_tracked_frame();
  add_ball(f, 4.0F, 4.0F, 0.0F, Point{0.0, 0.0}, 0.25F);  // a less visible second candidate
  add_ball(f, -1.5F, 0.75F, 0.1F, Point{2.5, -0.5}, 0.9F);
  add_ball(f, 0.0F, -2.0F, 0.0F, std::nullopt, 0.9F);  // as visible, but after it

  TrackedVision tracked;
  VisionFrame frame;
  ASSERT_TRUE(tracked.add(wrapper.SerializeAsString(), 0.0, frame));
  // Every ball is in the frame, as SSL-Vision's candidates would be.
  ASSERT_EQ(frame.detection.balls.size(), 3u);
  EXPECT_FLOAT_EQ(frame.detection.balls[1].x, -1500.0F);
  EXPECT_FLOAT_EQ(frame.detection.balls[1].y, 750.0F);
  EXPECT_FLOAT_EQ(frame.detection.balls[1].confidence, 0.9F);
  // The ball followed is the most visible, the first of equals, with the tracker's velocity.
  ASSERT_TRUE(tracked.ball().has_value());
  EXPECT_EQ(tracked.ball()->time_s, 300.25);
  EXPECT_NEAR(tracked.ball()->position.x, -1500.0, 1e-3);
  EXPECT_NEAR(tracked.ball()->position.y, 750.0, 1e-3);
  EXPECT_NEAR(tracked.ball()->velocity.x, 2500.0, 1e-3);
  EXPECT_NEAR(tracked.ball()->velocity.y, -500.0, 1e-3);

  // Without a velocity: zero. Without visibility: fully visible.
  TrackedFrame alone;
  alone.set_frame_number(6);
  alone.set_timestamp(301.0);
  add_ball(alone, 1.0F, 1.0F, 0.0F, std::nullopt, std::nullopt);
  add_ball(alone, 2.0F, 2.0F, 0.0F, Point{1.0, 1.0}, 0.99F);
  const std::optional<BallState> ball = tracked_ball(alone);
  ASSERT_TRUE(ball.has_value());
  EXPECT_NEAR(ball->position.x, 1000.0, 1e-3);
  EXPECT_EQ(ball->velocity, (Point{}));
  std::uint64_t without_team = 0;
  to_vision_frame(alone, frame, without_team);
  ASSERT_EQ(frame.detection.balls.size(), 2u);
  EXPECT_EQ(frame.detection.balls[0].confidence, 1.0F);

  // A frame without a ball has none, and a reused frame keeps none of the last one's.
  ASSERT_TRUE(tracked.add(packet("a", 7, 302.0, 1.0F), 0.1, frame));
  EXPECT_TRUE(frame.detection.balls.empty());
  EXPECT_FALSE(tracked.ball().has_value());
  // A ball at a position that is not finite is none.
  TrackedFrame nonsense;
  nonsense.set_frame_number(8);
  nonsense.set_timestamp(303.0);
  add_ball(nonsense, std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F, std::nullopt, 1.0F);
  EXPECT_FALSE(tracked_ball(nonsense).has_value());
}

TEST(TrackedVision, ResetForgetsTheBall) {
  TrackerWrapperPacket wrapper;
  ASSERT_TRUE(wrapper.ParseFromString(packet("a", 5, 300.25, 1.0F)));
  add_ball(*wrapper.mutable_tracked_frame(), 1.0F, 2.0F, 0.0F, std::nullopt, std::nullopt);
  TrackedVision tracked;
  VisionFrame frame;
  ASSERT_TRUE(tracked.add(wrapper.SerializeAsString(), 0.0, frame));
  EXPECT_TRUE(tracked.ball().has_value());
  tracked.reset();
  EXPECT_FALSE(tracked.ball().has_value());
}

}  // namespace
}  // namespace ssl_formation
