#include "team_robots.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace ssl_formation::predictor::web {
namespace {

VisionDetection frame(double t, std::uint32_t camera) {
  VisionDetection f;
  f.frame_number = 1;
  f.t_capture = t;
  f.camera_id = camera;
  return f;
}

void add_robot(VisionDetection& f, bool blue, std::uint32_t id, float x, float y) {
  (blue ? f.robots_blue : f.robots_yellow).push_back(VisionRobot{id, true, x, y, 1.0F});
}

TEST(TeamRobots, MergesCamerasByIdNewestWins) {
  TeamRobots ours(TeamColor::blue, 1.0, 4.0);
  VisionDetection left = frame(10.0, 0);
  add_robot(left, true, 3, -1000, 0);
  add_robot(left, true, 1, -2000, 500);
  add_robot(left, false, 7, 0, 0);  // the opponent: not ours
  VisionDetection right = frame(10.02, 1);
  add_robot(right, true, 3, -990, 10);  // seen by both cameras: the newer detection wins
  ours.add(left);
  ours.add(right);
  const auto& robots = ours.current();
  ASSERT_EQ(robots.size(), 2u);
  EXPECT_EQ(robots[0].robot_id, 1u);
  EXPECT_EQ(robots[1].robot_id, 3u);
  EXPECT_DOUBLE_EQ(robots[1].x, -990);
  // An older frame arriving late does not overwrite a newer detection.
  VisionDetection late = frame(10.01, 2);
  add_robot(late, true, 3, 4000, 4000);
  ours.add(late);
  EXPECT_DOUBLE_EQ(ours.current()[1].x, -990);
}

TEST(TeamRobots, ForgetsRobotsNoCameraReportsAndRestartsWithTheClock) {
  TeamRobots ours(TeamColor::yellow, 1.0, 4.0);
  VisionDetection first = frame(10.0, 0);
  add_robot(first, false, 2, 100, 100);
  add_robot(first, false, 5, 200, 200);
  ours.add(first);
  VisionDetection later = frame(10.8, 0);
  add_robot(later, false, 5, 210, 200);
  ours.add(later);
  EXPECT_EQ(ours.current().size(), 2u);
  VisionDetection much_later = frame(11.5, 0);
  add_robot(much_later, false, 5, 220, 200);
  ours.add(much_later);
  ASSERT_EQ(ours.current().size(), 1u);  // robot 2 not seen for 1.5 s
  EXPECT_EQ(ours.current()[0].robot_id, 5u);
  // The data clock restarts (a new log or producer): the old robots go at once.
  VisionDetection restarted = frame(0.0, 0);
  add_robot(restarted, false, 9, 0, 0);
  ours.add(restarted);
  ASSERT_EQ(ours.current().size(), 1u);
  EXPECT_EQ(ours.current()[0].robot_id, 9u);
}

TEST(TeamRobots, IgnoresNonsense) {
  TeamRobots ours(TeamColor::blue, 1.0, 4.0);
  VisionDetection f = frame(1.0, 0);
  add_robot(f, true, 1, std::numeric_limits<float>::quiet_NaN(), 0);
  add_robot(f, true, 2, 1e9f, 0);
  add_robot(f, true, 5000, 0, 0);
  ours.add(f);
  ours.add(frame(std::numeric_limits<double>::infinity(), 0));
  EXPECT_TRUE(ours.current().empty());
}

}  // namespace
}  // namespace ssl_formation::predictor::web
