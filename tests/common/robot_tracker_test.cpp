// The robot tracker (common/src/robot_tracker.cpp): exact on exact motion, about as steady as
// differences under the vision's noise, and starting over where a track breaks.

#include "ssl_formation/robot_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace sf = ssl_formation;

namespace {

constexpr double frame_s = 1.0 / 60.0;

TEST(RobotTracker, AConstantVelocityIsExactFromTheSecondObservation) {
  sf::RobotTracker tracker;
  EXPECT_EQ(tracker.observations(), 0);
  for (int i = 0; i < 120; ++i) {
    const double t = 10.0 + frame_s * i;
    tracker.observe(t, {-2000.0 + 1500.0 * (t - 10.0), 300.0 - 400.0 * (t - 10.0)});
    if (i == 0) continue;
    SCOPED_TRACE(i);
    EXPECT_NEAR(tracker.velocity().x, 1500.0, 1e-6);
    EXPECT_NEAR(tracker.velocity().y, -400.0, 1e-6);
    EXPECT_NEAR(tracker.acceleration().x, 0.0, 1e-6);
  }
  EXPECT_EQ(tracker.observations(), 120);
  EXPECT_DOUBLE_EQ(tracker.first_s(), 10.0);
}

TEST(RobotTracker, ItFindsAConstantAccelerationAndTheVelocityNow) {
  sf::RobotTracker tracker;
  const double a = 2500.0;
  for (int i = 0; i <= 60; ++i) {
    const double t = frame_s * i;
    tracker.observe(t, {0.5 * a * t * t, 0.0});
  }
  // After a second: the velocity now (a * t), not the mean over the last frames, which a
  // difference would give (half a frame behind).
  EXPECT_NEAR(tracker.acceleration().x, a, 0.02 * a);
  EXPECT_NEAR(tracker.velocity().x, a * 1.0, 5.0);
  EXPECT_NEAR(tracker.position().x, 0.5 * a, 1.0);
}

TEST(RobotTracker, UnderNoiseItIsAboutAsSteadyAsDifferences) {
  // A robot standing still, seen with 3 mm of noise at 60 frames a second. The displacement over
  // 0.1 s has about 42 mm/s of noise per axis, and the change between two such velocities 0.1 s
  // apart about 73 mm/s. The tracker is set to follow a robot's motion closely (the velocity
  // now, not half a window ago): its velocity is about as noisy as the difference (51 mm/s with
  // this seed) and its change of velocity over 0.1 s (the acceleration times 0.1 s) a little
  // steadier than the differences' (64 mm/s).
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, 3.0);
  sf::RobotTracker tracker;
  std::vector<double> xs;
  double velocity_squares = 0.0, difference_squares = 0.0;
  double change_squares = 0.0, difference_change_squares = 0.0;
  int n = 0;
  for (int i = 0; i < 6000; ++i) {
    const double x = noise(random);
    xs.push_back(x);
    tracker.observe(frame_s * i, {x, noise(random)});
    if (i < 60) continue;  // settled
    const std::size_t last = xs.size() - 1;
    const double difference = (xs[last] - xs[last - 6]) / (6 * frame_s);
    const double earlier = (xs[last - 6] - xs[last - 12]) / (6 * frame_s);
    velocity_squares += tracker.velocity().x * tracker.velocity().x;
    difference_squares += difference * difference;
    change_squares += std::pow(tracker.acceleration().x * 0.1, 2);
    difference_change_squares += (difference - earlier) * (difference - earlier);
    ++n;
  }
  const double difference_rms = std::sqrt(difference_squares / n);
  EXPECT_NEAR(difference_rms, 42.4, 3.0);
  EXPECT_LT(std::sqrt(velocity_squares / n), 1.5 * difference_rms);
  const double difference_change_rms = std::sqrt(difference_change_squares / n);
  EXPECT_NEAR(difference_change_rms, 73.5, 5.0);
  EXPECT_LT(std::sqrt(change_squares / n), difference_change_rms);
}

TEST(RobotTracker, ATimeGoingBackOrAResetStartsANewTrack) {
  sf::RobotTracker tracker;
  tracker.observe(1.0, {0.0, 0.0});
  tracker.observe(1.1, {100.0, 0.0});
  EXPECT_EQ(tracker.observations(), 2);
  EXPECT_NEAR(tracker.velocity().x, 1000.0, 1e-6);
  // Back in time: a new track from this observation, no velocity of the old one kept.
  tracker.observe(0.5, {5000.0, 0.0});
  EXPECT_EQ(tracker.observations(), 1);
  EXPECT_DOUBLE_EQ(tracker.first_s(), 0.5);
  tracker.observe(0.6, {5000.0, 50.0});
  EXPECT_NEAR(tracker.velocity().x, 0.0, 1e-6);
  EXPECT_NEAR(tracker.velocity().y, 500.0, 1e-6);
  tracker.reset();
  EXPECT_EQ(tracker.observations(), 0);
  tracker.observe(0.7, {0.0, 0.0});
  EXPECT_EQ(tracker.observations(), 1);
  EXPECT_DOUBLE_EQ(tracker.first_s(), 0.7);
}

TEST(RobotTracker, DefaultSettingsAreValidAndBadOnesAreNot) {
  EXPECT_TRUE(sf::RobotTrackerSettings{}.valid());
  sf::RobotTrackerSettings bad;
  bad.position_noise_mm = 0.0;
  EXPECT_FALSE(bad.valid());
  bad = {};
  bad.jerk_density = std::nan("");
  EXPECT_FALSE(bad.valid());
}

}  // namespace
