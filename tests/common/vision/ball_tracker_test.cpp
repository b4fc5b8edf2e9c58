// The ball follower (common/vision/src/ball_tracker.cpp): the most confident ball of a frame,
// cameras merged without fake speeds at their seams, the velocity of the last 0.1 s exact on exact
// motion and steady under the vision's noise, and starting over where the ball jumps or is lost.

#include "ssl_formation/vision/ball_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

namespace sf = ssl_formation;

namespace {

constexpr double frame_s = 1.0 / 60.0;

// A detection frame of `camera` at `t` with these balls (x, y, confidence).
sf::VisionDetection frame(double t, std::vector<sf::VisionBall> balls, std::uint32_t camera = 0) {
  sf::VisionDetection detection;
  detection.t_capture = t;
  detection.camera_id = camera;
  detection.balls = std::move(balls);
  return detection;
}

sf::VisionBall ball(double x, double y, float confidence = 0.95F) {
  return {static_cast<float>(x), static_cast<float>(y), confidence};
}

TEST(BallTracker, NothingBeforeTheFirstSightingAndNoVelocityFromOne) {
  sf::BallTracker tracker;
  EXPECT_FALSE(tracker.state().has_value());
  EXPECT_FALSE(tracker.at(10.0).has_value());
  tracker.add(frame(10.0, {}));  // a frame without a ball
  EXPECT_FALSE(tracker.state().has_value());
  tracker.add(frame(10.0, {ball(1200.0, -300.0)}));
  ASSERT_TRUE(tracker.state().has_value());
  EXPECT_EQ(tracker.state()->time_s, 10.0);
  EXPECT_EQ(tracker.state()->position, (sf::Point{1200.0, -300.0}));
  EXPECT_EQ(tracker.state()->velocity, (sf::Point{}));
}

TEST(BallTracker, AConstantVelocityIsExactFromTheSecondSighting) {
  sf::BallTracker tracker;
  for (int i = 0; i < 60; ++i) {
    const double t = 1700000000.0 + frame_s * i;  // Unix time: the fit must not lose digits
    const double s = frame_s * i;
    tracker.add(frame(t, {ball(-2000.0 + 3000.0 * s, 500.0 - 1000.0 * s)}));
    if (i == 0) continue;
    SCOPED_TRACE(i);
    // Positions travel as floats: a few hundredths of a millimetre.
    EXPECT_NEAR(tracker.state()->velocity.x, 3000.0, 5.0);
    EXPECT_NEAR(tracker.state()->velocity.y, -1000.0, 5.0);
  }
  EXPECT_NEAR(tracker.state()->position.x, -2000.0 + 3000.0 * 59 * frame_s, 0.01);
}

TEST(BallTracker, UnderTheVisionsNoiseTheVelocityIsSteady) {
  // A ball rolling at 2 m/s, seen with 3 mm of noise per axis at 60 frames a second: the slope
  // over 0.1 s (seven frames) has about 35 mm/s of noise; two frames' difference would have 250.
  std::mt19937_64 random(11);
  std::normal_distribution<double> noise(0.0, 3.0);
  sf::BallTracker tracker;
  double squares = 0.0;
  int counted = 0;
  for (int i = 0; i < 600; ++i) {
    const double t = frame_s * i;
    tracker.add(frame(t, {ball(2000.0 * t + noise(random), -1000.0 + noise(random))}));
    if (i < 10) continue;
    const sf::Point v = tracker.state()->velocity;
    squares += (v.x - 2000.0) * (v.x - 2000.0) + v.y * v.y;
    counted += 2;
  }
  const double rms = std::sqrt(squares / counted);
  EXPECT_LT(rms, 60.0);
  EXPECT_GT(rms, 10.0);  // the noise is there: the test measures something
}

TEST(BallTracker, TheMostConfidentBallOfAFrameCountsAndUnlikelyOnesNone) {
  sf::BallTracker tracker;
  tracker.add(
      frame(1.0, {ball(100.0, 100.0, 0.3F), ball(-500.0, 200.0, 0.9F), ball(800.0, 0.0, 0.5F)}));
  ASSERT_TRUE(tracker.state().has_value());
  EXPECT_EQ(tracker.state()->position, (sf::Point{-500.0, 200.0}));

  // Below the confidence floor, not finite, or absurdly far: no ball at all.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  tracker.reset();
  tracker.add(
      frame(2.0, {ball(100.0, 100.0, 0.05F), ball(nan, 0.0), ball(0.0, 0.0, nan), ball(1e9, 0.0)}));
  EXPECT_FALSE(tracker.state().has_value());
  tracker.add(frame(std::numeric_limits<double>::quiet_NaN(), {ball(0.0, 0.0)}));
  EXPECT_FALSE(tracker.state().has_value());
  // The floor itself counts.
  tracker.add(frame(3.0, {ball(10.0, 20.0, 0.1F)}));
  ASSERT_TRUE(tracker.state().has_value());
  EXPECT_EQ(tracker.state()->position, (sf::Point{10.0, 20.0}));
}

TEST(BallTracker, TwoCamerasAtTheirSeamGiveNoFakeVelocity) {
  // A ball lying still where two cameras overlap. Their calibrations disagree by 20 mm, and one
  // exposes 4 ms after the other: from one sighting to the next the ball seems to move 5 m/s.
  sf::BallTracker tracker;
  for (int i = 0; i < 60; ++i) {
    const double t = 50.0 + frame_s * i;
    tracker.add(frame(t, {ball(3000.0, 100.0)}, 0));
    tracker.add(frame(t + 0.004, {ball(3020.0, 100.0)}, 1));
    SCOPED_TRACE(i);
    EXPECT_NEAR(tracker.state()->velocity.x, 0.0, 1e-6);
    EXPECT_NEAR(tracker.state()->velocity.y, 0.0, 1e-6);
  }
  EXPECT_EQ(tracker.state()->position, (sf::Point{3020.0, 100.0}));  // the newest sighting
  EXPECT_NEAR(tracker.state()->time_s, 50.0 + 59 * frame_s + 0.004, 1e-9);

  // Cameras of one exposure (the same t_capture): one ball, averaged, still not moving.
  tracker.reset();
  for (int i = 0; i < 30; ++i) {
    const double t = 60.0 + frame_s * i;
    tracker.add(frame(t, {ball(3000.0, 100.0)}, 2));
    tracker.add(frame(t, {ball(3030.0, 90.0)}, 3));
    EXPECT_NEAR(tracker.state()->velocity.x, 0.0, 1e-6);
    EXPECT_NEAR(tracker.state()->velocity.y, 0.0, 1e-6);
  }
  EXPECT_EQ(tracker.state()->position, (sf::Point{3015.0, 95.0}));
}

TEST(BallTracker, ABallCrossingFromOneCameraToTheNextKeepsItsVelocity) {
  // 2 m/s along x; camera 0 sees x < 200, camera 1 x > -200 and 25 mm further on, 5 ms later.
  sf::BallTracker tracker;
  for (int i = 0; i < 60; ++i) {
    const double t = frame_s * i;
    const double x = -1000.0 + 2000.0 * t;
    if (x < 200.0) tracker.add(frame(t, {ball(x, 0.0)}, 0));
    const double later = t + 0.005;
    const double x1 = -1000.0 + 2000.0 * later;
    if (x1 > -200.0) tracker.add(frame(later, {ball(x1 + 25.0, 0.0)}, 1));
    if (i == 0) continue;
    SCOPED_TRACE(i);
    EXPECT_NEAR(tracker.state()->velocity.x, 2000.0, 2.0);
    EXPECT_NEAR(tracker.state()->velocity.y, 0.0, 2.0);
  }
}

TEST(BallTracker, AKickShowsInFullOnceTheWindowHasPassed) {
  sf::BallTracker tracker;
  int i = 0;
  for (; i <= 30; ++i) tracker.add(frame(frame_s * i, {ball(0.0, 0.0)}));
  EXPECT_NEAR(tracker.state()->velocity.x, 0.0, 1e-6);
  const double kick_s = frame_s * 30;
  for (; i <= 45; ++i) {
    const double t = frame_s * i;
    tracker.add(frame(t, {ball(5000.0 * (t - kick_s), 0.0)}));
    if (t > kick_s + 0.1 + 1e-6) {
      SCOPED_TRACE(i);
      EXPECT_NEAR(tracker.state()->velocity.x, 5000.0, 5.0);
    }
  }
}

TEST(BallTracker, ABallUnseenForHalfASecondIsGoneAndStartsOver) {
  sf::BallTracker tracker;
  for (int i = 0; i < 30; ++i) tracker.add(frame(frame_s * i, {ball(1000.0 * frame_s * i, 0.0)}));
  const double last_s = frame_s * 29;
  EXPECT_NEAR(tracker.state()->velocity.x, 1000.0, 2.0);
  EXPECT_TRUE(tracker.at(last_s + 0.49).has_value());
  EXPECT_FALSE(tracker.at(last_s + 0.51).has_value());
  // Seen again later: where it is now, with no velocity from before the gap.
  tracker.add(frame(last_s + 0.6, {ball(1200.0, 0.0)}));
  EXPECT_EQ(tracker.state()->position, (sf::Point{1200.0, 0.0}));
  EXPECT_EQ(tracker.state()->velocity, (sf::Point{}));
}

TEST(BallTracker, AJumpOfMetresIsAnotherBall) {
  sf::BallTracker tracker;
  int i = 0;
  for (; i < 20; ++i) tracker.add(frame(frame_s * i, {ball(1500.0 * frame_s * i, 0.0)}));
  EXPECT_NEAR(tracker.state()->velocity.x, 1500.0, 2.0);
  // Put down three metres away: no velocity from the jump.
  tracker.add(frame(frame_s * i, {ball(-2000.0, 2000.0)}));
  EXPECT_EQ(tracker.state()->position, (sf::Point{-2000.0, 2000.0}));
  EXPECT_EQ(tracker.state()->velocity, (sf::Point{}));
  // And it moves on from there.
  const double start = frame_s * i;
  for (++i; i < 40; ++i) {
    const double t = frame_s * i;
    tracker.add(frame(t, {ball(-2000.0, 2000.0 - 800.0 * (t - start))}));
  }
  EXPECT_NEAR(tracker.state()->velocity.x, 0.0, 2.0);
  EXPECT_NEAR(tracker.state()->velocity.y, -800.0, 2.0);

  // A fast shot is no jump: 6.5 m/s is 108 mm a frame.
  tracker.reset();
  for (i = 0; i < 20; ++i) tracker.add(frame(frame_s * i, {ball(6500.0 * frame_s * i, 0.0)}));
  EXPECT_NEAR(tracker.state()->velocity.x, 6500.0, 5.0);
}

TEST(BallTracker, AnOlderSightingDoesNotMoveTheBall) {
  sf::BallTracker tracker;
  for (int i = 0; i <= 10; ++i) tracker.add(frame(frame_s * i, {ball(1000.0 * frame_s * i, 0.0)}));
  const sf::BallState newest = *tracker.state();
  // A slower camera's frame from two frames ago, on the same line: the ball stays the newest.
  tracker.add(frame(frame_s * 8 + 0.002, {ball(1000.0 * (frame_s * 8 + 0.002), 0.0)}, 1));
  EXPECT_EQ(tracker.state()->position, newest.position);
  EXPECT_EQ(tracker.state()->time_s, newest.time_s);
  EXPECT_NEAR(tracker.state()->velocity.x, 1000.0, 2.0);
  // An older sighting metres away is nothing.
  tracker.add(frame(frame_s * 9, {ball(-3000.0, 0.0)}, 2));
  EXPECT_EQ(tracker.state()->position, newest.position);
  EXPECT_NEAR(tracker.state()->velocity.x, 1000.0, 2.0);
}

TEST(BallTracker, AClockThatWentBackIsAnotherStream) {
  sf::BallTracker tracker;
  for (int i = 0; i < 20; ++i)
    tracker.add(frame(500.0 + frame_s * i, {ball(2000.0 * frame_s * i, 0.0)}));
  // The sender restarted: its clock starts from 0.
  tracker.add(frame(0.0, {ball(100.0, 0.0)}));
  EXPECT_EQ(tracker.state()->time_s, 0.0);
  EXPECT_EQ(tracker.state()->velocity, (sf::Point{}));
  EXPECT_TRUE(tracker.at(0.1).has_value());
  EXPECT_FALSE(tracker.at(500.0).has_value());
}

TEST(BallTracker, ATrackersEstimateIsTakenAsItIsAndResetForgets) {
  sf::BallTracker tracker;
  tracker.add(frame(1.0, {ball(0.0, 0.0)}));
  tracker.set({2.0, {1500.0, -250.0}, {-300.0, 4000.0}});
  ASSERT_TRUE(tracker.state().has_value());
  EXPECT_EQ(tracker.state()->time_s, 2.0);
  EXPECT_EQ(tracker.state()->position, (sf::Point{1500.0, -250.0}));
  EXPECT_EQ(tracker.state()->velocity, (sf::Point{-300.0, 4000.0}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  tracker.set({3.0, {nan, 0.0}, {}});  // nonsense changes nothing
  EXPECT_EQ(tracker.state()->time_s, 2.0);
  tracker.reset();
  EXPECT_FALSE(tracker.state().has_value());
  EXPECT_FALSE(tracker.at(2.0).has_value());
}

TEST(BallTracker, SettingsThatCannotWorkAreRefused) {
  EXPECT_TRUE(sf::BallTrackerSettings{}.valid());
  sf::BallTrackerSettings no_window;
  no_window.velocity_window_s = 0.0;
  EXPECT_THROW(sf::BallTracker{no_window}, std::invalid_argument);
  sf::BallTrackerSettings never_forgets;
  never_forgets.forget_after_s = std::numeric_limits<double>::infinity();
  EXPECT_THROW(sf::BallTracker{never_forgets}, std::invalid_argument);
}

}  // namespace
