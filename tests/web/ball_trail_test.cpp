#include "ball_trail.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace ssl_formation::predictor::web {
namespace {

BallState ball_at(double t, double x) { return BallState{t, Point{x, 0.0}, Point{}}; }

TEST(BallTrail, KeepsAPointEverySpacingForTheLastSecondsEndingWhereTheBallIs) {
  BallTrail trail(BallTrailSettings{2.0, 0.05, 0.5, 1.0});
  EXPECT_FALSE(trail.position().has_value());
  // 5 s of a ball rolling at 1 m/s, seen 60 times a second.
  for (int frame = 0; frame <= 300; ++frame) {
    const double t = frame / 60.0;
    trail.update(ball_at(t, 1000.0 * t), t);
  }
  ASSERT_TRUE(trail.position().has_value());
  EXPECT_DOUBLE_EQ(trail.position()->x, 5000.0);
  EXPECT_DOUBLE_EQ(trail.path().back().x, 5000.0);
  // Two seconds at one point per 50 ms at least (frames are 16.7 ms apart, so each point is
  // three frames after the last): about 30 points, none older than 2 s.
  EXPECT_GE(trail.path().size(), 28U);
  EXPECT_LE(trail.path().size(), 42U);
  EXPECT_GE(trail.path().front().x, 3000.0 - 1e-6);
  for (std::size_t i = 1; i < trail.path().size(); ++i) {
    EXPECT_GT(trail.path()[i].x, trail.path()[i - 1].x) << i;
  }
}

TEST(BallTrail, ABallNotSeenLatelyIsGoneAndAClockGoingBackStartsOver) {
  BallTrail trail;
  trail.update(ball_at(10.0, 100.0), 10.0);
  trail.update(ball_at(10.1, 200.0), 10.1);
  ASSERT_EQ(trail.path().size(), 2U);
  // Frames keep coming without the ball: after half a second it is gone, path and all.
  trail.update(ball_at(10.1, 200.0), 10.5);
  EXPECT_TRUE(trail.position().has_value());
  trail.update(ball_at(10.1, 200.0), 10.7);
  EXPECT_FALSE(trail.position().has_value());
  EXPECT_TRUE(trail.path().empty());
  // Seen again, then a feed whose clock starts from 0: only the new ball.
  trail.update(ball_at(20.0, 500.0), 20.0);
  trail.update(ball_at(1.0, -700.0), 1.0);
  ASSERT_EQ(trail.path().size(), 1U);
  EXPECT_DOUBLE_EQ(trail.position()->x, -700.0);
  // No ball at all.
  trail.update(std::nullopt, 1.1);
  EXPECT_FALSE(trail.position().has_value());
}

TEST(BallTrail, RefusesSettingsOutOfRange) {
  EXPECT_THROW(BallTrail(BallTrailSettings{0.0, 0.05, 0.5, 1.0}), std::invalid_argument);
  EXPECT_THROW(BallTrail(BallTrailSettings{2.0, -1.0, 0.5, 1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace ssl_formation::predictor::web
