#include "ssl_formation/simulation/robot_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace ssl_formation::simulation {
namespace {

constexpr double dt = 1.0 / 60.0;

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }
double length(Point p) { return std::hypot(p.x, p.y); }

// 22 robots on a Division A field, in two rows of 11, each sent to a new random point every
// few seconds, many of them across one another's paths.
TEST(TeamMotion, SpeedAccelerationAndSpaceHoldForEveryRobotInEveryFrame) {
  std::vector<Point> start;
  for (int i = 0; i < 22; ++i)
    start.push_back(Point{-5000.0 + 1000.0 * (i % 11), i < 11 ? -1000.0 : 1000.0});
  TeamMotion robots(MotionLimits{}, start);
  const MotionLimits& limits = robots.limits();
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> x(-5800.0, 5800.0);
  std::uniform_real_distribution<double> y(-4300.0, 4300.0);
  std::vector<Point> targets = start;
  double closest = 1e9;
  double fastest = 0.0;
  double hardest = 0.0;
  double travelled = 0.0;
  for (int frame = 0; frame < 60 * 120; ++frame) {
    if (frame % 150 == 0) {
      for (Point& target : targets) target = Point{x(random), y(random)};
    }
    std::vector<Point> before(robots.size());
    std::vector<Point> velocity_before(robots.size());
    for (std::size_t i = 0; i < robots.size(); ++i) {
      before[i] = robots.position(i);
      velocity_before[i] = robots.velocity(i);
    }
    robots.step(dt, targets);
    for (std::size_t i = 0; i < robots.size(); ++i) {
      const Point v = robots.velocity(i);
      fastest = std::max(fastest, length(v));
      const Point change{v.x - velocity_before[i].x, v.y - velocity_before[i].y};
      hardest = std::max(hardest, length(change) / dt);
      // It moves by its velocity: no jump.
      const double moved = distance(robots.position(i), before[i]);
      ASSERT_NEAR(moved, length(v) * dt, 1e-6) << "robot " << i << " frame " << frame;
      travelled += moved;
      for (std::size_t j = i + 1; j < robots.size(); ++j) {
        closest = std::min(closest, distance(robots.position(i), robots.position(j)));
      }
    }
  }
  EXPECT_LE(fastest, limits.max_speed_mm_s * (1 + 1e-9));
  EXPECT_LE(hardest, limits.max_acceleration_mm_s2 * (1 + 1e-9));
  EXPECT_GE(closest, 2.0 * limits.robot_radius_mm) << "two robots touched";
  // They did move, and fast: on average over a metre a second each.
  EXPECT_GT(travelled / 22.0 / 120.0, 1000.0);
  EXPECT_GT(fastest, 0.9 * limits.max_speed_mm_s);
}

// The worst case for space: 11 robots sent again and again to points crowded in a small disc
// (a corner kick's box), over many seeds.
TEST(TeamMotion, RobotsCrowdingOnePlaceNeverTouch) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    std::vector<Point> start;
    for (int i = 0; i < 11; ++i) start.push_back(Point{-5000.0 + 1000.0 * i, -3000.0});
    TeamMotion robots(MotionLimits{}, start);
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
    std::uniform_real_distribution<double> radius(0.0, 700.0);
    std::vector<Point> targets = start;
    double closest = 1e9;
    double hardest = 0.0;
    for (int frame = 0; frame < 60 * 30; ++frame) {
      if (frame % 60 == 0) {
        for (Point& target : targets) {
          const double a = angle(random);
          const double r = radius(random);
          target = Point{3500.0 + r * std::cos(a), 1500.0 + r * std::sin(a)};
        }
      }
      std::vector<Point> velocity_before(robots.size());
      for (std::size_t i = 0; i < robots.size(); ++i) velocity_before[i] = robots.velocity(i);
      robots.step(dt, targets);
      for (std::size_t i = 0; i < robots.size(); ++i) {
        const Point v = robots.velocity(i);
        hardest = std::max(
            hardest, length(Point{v.x - velocity_before[i].x, v.y - velocity_before[i].y}) / dt);
        for (std::size_t j = i + 1; j < robots.size(); ++j) {
          closest = std::min(closest, distance(robots.position(i), robots.position(j)));
        }
      }
    }
    EXPECT_GE(closest, 2.0 * robots.limits().robot_radius_mm);
    EXPECT_LE(hardest, robots.limits().max_acceleration_mm_s2 * (1 + 1e-9));
  }
}

TEST(TeamMotion, ARobotDrivesToItsTargetAsFastAsItMayAndStopsThere) {
  TeamMotion robot(MotionLimits{}, {Point{0.0, 0.0}});
  const std::vector<Point> target{Point{4000.0, 0.0}};
  int frames = 0;
  double farthest = 0.0;
  while (frames < 600 &&
         !(distance(robot.position(0), target[0]) < 2.0 && length(robot.velocity(0)) < 10.0)) {
    robot.step(dt, target);
    farthest = std::max(farthest, robot.position(0).x);
    ++frames;
  }
  // 1 s to reach 3 m/s over 1.5 m, 1 m at full speed, 1 s braking over 1.5 m: 2.33 s.
  EXPECT_NEAR(frames * dt, 2.33, 0.25);
  EXPECT_LT(farthest, 4000.0 + 5.0) << "it overshot";
  for (int i = 0; i < 60; ++i) robot.step(dt, target);
  EXPECT_LT(distance(robot.position(0), target[0]), 2.0) << "it stays";
}

TEST(TeamMotion, TwoRobotsMeetingHeadOnPassEachOtherAndArrive) {
  TeamMotion robots(MotionLimits{}, {Point{-2000.0, 0.0}, Point{2000.0, 0.0}});
  const std::vector<Point> targets{Point{2000.0, 0.0}, Point{-2000.0, 0.0}};
  double closest = 1e9;
  for (int frame = 0; frame < 60 * 6; ++frame) {
    robots.step(dt, targets);
    closest = std::min(closest, distance(robots.position(0), robots.position(1)));
  }
  EXPECT_GE(closest, 2.0 * robots.limits().robot_radius_mm);
  EXPECT_LT(distance(robots.position(0), targets[0]), 5.0);
  EXPECT_LT(distance(robots.position(1), targets[1]), 5.0);
}

TEST(TeamMotion, ATargetInsideAnotherRobotIsApproachedAsFarAsTheShellsAllow) {
  TeamMotion robots(MotionLimits{}, {Point{0.0, 0.0}, Point{1000.0, 0.0}});
  const std::vector<Point> targets{Point{1000.0, 0.0}, Point{1000.0, 0.0}};
  for (int frame = 0; frame < 60 * 4; ++frame) robots.step(dt, targets);
  const double apart = distance(robots.position(0), robots.position(1));
  EXPECT_GE(apart, 2.0 * robots.limits().robot_radius_mm);
  EXPECT_LT(apart, robots.closest_allowed_mm() + 150.0) << "it came close";
}

TEST(TeamMotion, LimitsThatMakeNoSenseAndRobotsStartingInOneAnotherAreRefused) {
  MotionLimits limits;
  limits.max_speed_mm_s = 0.0;
  EXPECT_THROW(TeamMotion(limits, {}), std::invalid_argument);
  limits = MotionLimits{};
  limits.max_acceleration_mm_s2 = std::nan("");
  EXPECT_THROW(TeamMotion(limits, {}), std::invalid_argument);
  EXPECT_THROW(TeamMotion(MotionLimits{}, {Point{0.0, 0.0}, Point{150.0, 0.0}}),
               std::invalid_argument);
  TeamMotion robots(MotionLimits{}, {Point{0.0, 0.0}});
  EXPECT_THROW(robots.step(dt, {}), std::invalid_argument);
  EXPECT_THROW(robots.step(0.0, {Point{1.0, 1.0}}), std::invalid_argument);
}

// HALT: robots at full speed brake as hard as they may, straight on, and then stand exactly
// where they stopped, however close they are to one another.
TEST(TeamMotion, HaltedRobotsBrakeWithinTheLimitAndThenStandExactlyStill) {
  // Two robots driving at full speed, and two standing closer than the clearance (which a step
  // would push apart).
  TeamMotion robots(MotionLimits{}, {Point{-3000.0, -3000.0}, Point{-3000.0, 3000.0},
                                     Point{2000.0, 0.0}, Point{2000.0, 222.0}});
  const std::vector<Point> targets{Point{5000.0, -3000.0}, Point{5000.0, 3000.0},
                                   Point{2000.0, 0.0}, Point{2000.0, 222.0}};
  for (int frame = 0; frame < 90; ++frame) robots.step(dt, targets);
  ASSERT_GT(robots.velocity(0).x, 2900.0);
  double hardest = 0.0;
  const Point heading = robots.velocity(0);
  for (int frame = 0; frame < 60; ++frame) {
    const Point v = robots.velocity(0);
    robots.halt(dt);
    const Point now = robots.velocity(0);
    hardest = std::max(hardest, length(Point{now.x - v.x, now.y - v.y}) / dt);
    EXPECT_NEAR(now.x * heading.y - now.y * heading.x, 0.0, 1e-3) << "braking straight on";
  }
  EXPECT_LE(hardest, robots.limits().max_acceleration_mm_s2 * (1 + 1e-9));
  std::vector<Point> stopped;
  for (std::size_t i = 0; i < robots.size(); ++i) stopped.push_back(robots.position(i));
  for (int frame = 0; frame < 600; ++frame) robots.halt(dt);
  for (std::size_t i = 0; i < robots.size(); ++i) {
    EXPECT_EQ(robots.position(i).x, stopped[i].x) << i;
    EXPECT_EQ(robots.position(i).y, stopped[i].y) << i;
    EXPECT_EQ(length(robots.velocity(i)), 0.0) << i;
  }
}

// While the game is stopped, robots drive round the ball's disc and one inside it leaves; the
// robot placing the ball goes to it, faster than the cap.
TEST(TeamMotion, RobotsKeepOutOfTheDiscButForTheOnePlacingTheBall) {
  const Point ball{0.0, 0.0};
  TeamMotion robots(MotionLimits{},
                    {Point{-2000.0, 10.0}, Point{2500.0, 2500.0}, Point{200.0, 0.0}});
  // Across the disc, past it, and out of it.
  const std::vector<Point> targets{Point{2000.0, 10.0}, Point{-2000.0, -2000.0},
                                   Point{200.0, 1500.0}};
  double fastest = 0.0;
  for (int frame = 0; frame < 60 * 8; ++frame) {
    robots.step(dt, targets, 1500.0, KeepOut{ball, 560.0, -1});
    for (std::size_t i = 0; i < robots.size(); ++i) {
      fastest = std::max(fastest, length(robots.velocity(i)));
      // The one that started inside it is out within half a second; the others never come in.
      if (i != 2 || frame > 30) {
        EXPECT_GE(distance(robots.position(i), ball), 500.0) << i << " frame " << frame;
      }
    }
  }
  EXPECT_LE(fastest, 1500.0 * (1 + 1e-9));
  // Round it, they got there.
  for (std::size_t i = 0; i < robots.size(); ++i) {
    EXPECT_LT(distance(robots.position(i), targets[i]), 5.0) << i;
  }

  // The placing robot (the disc's exception) drives at the ball at full speed.
  TeamMotion placing(MotionLimits{}, {Point{-3000.0, 0.0}, Point{0.0, 3000.0}});
  const std::vector<Point> to_ball{Point{-110.0, 0.0}, Point{0.0, 3000.0}};
  double placer_fastest = 0.0;
  for (int frame = 0; frame < 60 * 4; ++frame) {
    placing.step(dt, to_ball, 1500.0, KeepOut{ball, 560.0, 0});
    placer_fastest = std::max(placer_fastest, length(placing.velocity(0)));
    EXPECT_LE(length(placing.velocity(1)), 1500.0);
  }
  EXPECT_GT(placer_fastest, 2000.0);
  EXPECT_LT(distance(placing.position(0), to_ball[0]), 5.0);
}

}  // namespace
}  // namespace ssl_formation::simulation
