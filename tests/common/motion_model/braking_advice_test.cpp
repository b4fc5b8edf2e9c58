// Where a braking robot is advised to stop (models/src/braking_advice.cpp), as the forecaster
// asks for it: normalised robots with the tracker's kinematics.

#include "ssl_formation/motion_model/braking_advice.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace ssl_formation::models {
namespace {

constexpr double velocity_window_s = 0.1;

// A robot at `position` with `velocity` whose velocity changed by `change` over the window.
MotionRobot moving(Point position, Point velocity, Point change) {
  MotionRobot robot;
  robot.robot_id = 3;
  robot.position = position;
  robot.has_velocity = true;
  robot.kinematics.velocity = velocity;
  robot.kinematics.velocity_change = change;
  return robot;
}

bool advised(const SetPlayAdvice::Robot& robot) {
  for (const double w : robot.weight) {
    if (w > 0.0) return true;
  }
  return false;
}

TEST(BrakingPath, ARobotBrakingHardIsAdvisedWhereConstantDecelerationStopsIt) {
  // 1 m/s along +y, braking at 2 m/s² (0.2 m/s less over the 0.1 s window): it stands after
  // 0.5 s, 250 mm on.
  const std::vector<MotionRobot> robots{moving({100.0, -200.0}, {0.0, 1000.0}, {0.0, -200.0})};
  SetPlayAdvice advice;
  advise_braking(robots, velocity_window_s, 0.2, 4, advice);
  ASSERT_TRUE(advice.any);
  ASSERT_EQ(advice.robots.size(), 1u);
  const SetPlayAdvice::Robot& out = advice.robots[0];
  const double expected_y[] = {-200.0 + 160.0, -200.0 + 240.0, -200.0 + 250.0, -200.0 + 250.0};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_NEAR(out.position[k].x, 100.0, 1e-9) << k;
    EXPECT_NEAR(out.position[k].y, expected_y[k], 1e-9) << k;
    EXPECT_DOUBLE_EQ(out.weight[k], BrakingPath::weight) << k;
  }
  EXPECT_EQ(out.weight[4], 0.0);  // only the steps asked for
}

TEST(BrakingPath, NoAdviceForARobotStandingTurningSpeedingUpBrakingGentlyOrUnseenMoving) {
  MotionRobot unseen_moving;
  unseen_moving.position = {0.0, 0.0};
  const std::vector<MotionRobot> robots{
      moving({0.0, 0.0}, {100.0, 0.0}, {-300.0, 0.0}),   // too slow to be stopping
      moving({0.0, 0.0}, {1000.0, 0.0}, {0.0, -300.0}),  // turning: the change is across
      moving({0.0, 0.0}, {1000.0, 0.0}, {300.0, 0.0}),   // speeding up
      moving({0.0, 0.0}, {1000.0, 0.0}, {-50.0, 0.0}),   // slowing at 0.5 m/s² only
      unseen_moving,                                     // no velocity yet
  };
  SetPlayAdvice advice;
  advise_braking(robots, velocity_window_s, 0.5, 3, advice);
  EXPECT_FALSE(advice.any);
  ASSERT_EQ(advice.robots.size(), robots.size());
  for (std::size_t r = 0; r < robots.size(); ++r) EXPECT_FALSE(advised(advice.robots[r])) << r;
}

TEST(BrakingPath, ARobotAlreadyAdvisedKeepsItsAdviceAndTheOthersGetTheirs) {
  // The placer of their ball placement has its path; the robot beside it brakes.
  const std::vector<MotionRobot> robots{moving({0.0, 0.0}, {1500.0, 0.0}, {-300.0, 0.0}),
                                        moving({0.0, 1000.0}, {-1500.0, 0.0}, {300.0, 0.0})};
  SetPlayAdvice advice;
  advice.robots.assign(2, SetPlayAdvice::Robot{});
  advice.robots[0].position[0] = {700.0, 0.0};
  advice.robots[0].weight[0] = 0.4;
  advice.any = true;
  advise_braking(robots, velocity_window_s, 0.5, 1, advice);
  EXPECT_EQ(advice.robots[0].position[0].x, 700.0);
  EXPECT_EQ(advice.robots[0].weight[0], 0.4);
  // 1.5 m/s braking at 3 m/s² stands after 0.5 s, 375 mm on (towards -x).
  EXPECT_NEAR(advice.robots[1].position[0].x, -375.0, 1e-9);
  EXPECT_NEAR(advice.robots[1].position[0].y, 1000.0, 1e-9);
  EXPECT_DOUBLE_EQ(advice.robots[1].weight[0], BrakingPath::weight);
  EXPECT_TRUE(advice.any);
}

TEST(BrakingPath, HoldsWhileRobotsTakeTheirPlacesForARestart) {
  EXPECT_FALSE(braking_advice_holds(GamePhase::running));
  EXPECT_TRUE(braking_advice_holds(GamePhase::stop));
  EXPECT_TRUE(braking_advice_holds(GamePhase::ball_placement_opponent));
  EXPECT_TRUE(braking_advice_holds(GamePhase::ball_placement_us));
  EXPECT_TRUE(braking_advice_holds(GamePhase::free_kick_opponent));
  EXPECT_FALSE(braking_advice_holds(GamePhase::halt));
  EXPECT_FALSE(braking_advice_holds(GamePhase::kickoff_opponent));
  EXPECT_FALSE(braking_advice_holds(GamePhase::kickoff_us));
  EXPECT_FALSE(braking_advice_holds(GamePhase::free_kick_us));
  EXPECT_FALSE(braking_advice_holds(GamePhase::penalty));
}

}  // namespace
}  // namespace ssl_formation::models
