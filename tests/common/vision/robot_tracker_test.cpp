// The robot tracker (common/vision/src/robot_tracker.cpp): exact on exact motion, about as steady
// as differences under the vision's noise, and starting over where a track breaks.

#include "ssl_formation/vision/robot_tracker.hpp"

#include <gtest/gtest.h>

#include <array>
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
    EXPECT_NEAR(tracker.acceleration().y, 0.0, 1e-6);
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

// The filter written plainly, 3x3 matrices and all, updating its covariance at every step.
struct ReferenceFilter {
  using Matrix = std::array<std::array<double, 3>, 3>;
  static Matrix product(const Matrix& a, const Matrix& b) {
    Matrix c{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
    return c;
  }
  static Matrix transposed(const Matrix& a) {
    Matrix t{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) t[i][j] = a[j][i];
    return t;
  }
  sf::RobotTrackerSettings settings;
  int n = 0;
  double last_s = 0.0;
  sf::Point first;
  std::array<std::array<double, 3>, 2> x{};
  Matrix p{};
  void observe(double t, sf::Point z) {
    const double r = settings.position_noise_mm * settings.position_noise_mm;
    const double a0 = settings.initial_acceleration_mm_s2;
    const double dt = t - last_s;
    last_s = t;
    if (n++ == 0) {
      first = z;
      return;
    }
    if (n == 2) {
      x = {{{z.x, (z.x - first.x) / dt, 0.0}, {z.y, (z.y - first.y) / dt, 0.0}}};
      p = {{{r, r / dt, 0.0},
            {r / dt, 2 * r / (dt * dt) + a0 * a0 * dt * dt / 4, a0 * a0 * dt / 2},
            {0.0, a0 * a0 * dt / 2, a0 * a0}}};
      return;
    }
    const Matrix f{{{1, dt, dt * dt / 2}, {0, 1, dt}, {0, 0, 1}}};
    const double q = settings.jerk_density;
    const Matrix noise{
        {{q * std::pow(dt, 5) / 20, q * std::pow(dt, 4) / 8, q * std::pow(dt, 3) / 6},
         {q * std::pow(dt, 4) / 8, q * std::pow(dt, 3) / 3, q * dt * dt / 2},
         {q * std::pow(dt, 3) / 6, q * dt * dt / 2, q * dt}}};
    Matrix predicted = product(product(f, p), transposed(f));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) predicted[i][j] += noise[i][j];
    const double s = predicted[0][0] + r;
    const std::array<double, 3> k{predicted[0][0] / s, predicted[1][0] / s, predicted[2][0] / s};
    const double observed[2] = {z.x, z.y};
    for (int axis = 0; axis < 2; ++axis) {
      std::array<double, 3> moved{};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) moved[i] += f[i][j] * x[axis][j];
      const double residual = observed[axis] - moved[0];
      for (int i = 0; i < 3; ++i) x[axis][i] = moved[i] + k[i] * residual;
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p[i][j] = predicted[i][j] - k[i] * predicted[0][j];
  }
};

TEST(RobotTracker, ItIsTheFullKalmanFilterThroughChangesOfPace) {
  // 60 frames a second, then 45, then irregular, then 90: the tracker (its covariance written
  // out on its six distinct entries) against the plain filter.
  std::mt19937_64 random(3);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::uniform_real_distribution<double> jitter(0.008, 0.03);
  sf::RobotTracker tracker;
  ReferenceFilter reference;
  double t = 100.0;
  for (int i = 0; i < 1200; ++i) {
    const double dt = i < 400   ? 1.0 / 60.0
                      : i < 700 ? 1.0 / 45.0
                      : i < 800 ? jitter(random)
                                : 1.0 / 90.0;
    t += dt;
    const sf::Point z{1000.0 * std::sin(0.7 * t) + noise(random),
                      500.0 * std::cos(t) + noise(random)};
    tracker.observe(t, z);
    reference.observe(t, z);
    if (i < 2) continue;
    SCOPED_TRACE(i);
    EXPECT_NEAR(tracker.velocity().x, reference.x[0][1], 1e-6);
    EXPECT_NEAR(tracker.velocity().y, reference.x[1][1], 1e-6);
    EXPECT_NEAR(tracker.acceleration().x, reference.x[0][2], 1e-5);
    EXPECT_NEAR(tracker.position().y, reference.x[1][0], 1e-7);
  }
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
  // At the same instant again: no time passed, so no velocity can come of it; a new track.
  tracker.observe(0.6, {5100.0, 50.0});
  EXPECT_EQ(tracker.observations(), 1);
  EXPECT_DOUBLE_EQ(tracker.position().x, 5100.0);
  tracker.reset();
  EXPECT_EQ(tracker.observations(), 0);
  tracker.observe(0.7, {0.0, 0.0});
  EXPECT_EQ(tracker.observations(), 1);
  EXPECT_DOUBLE_EQ(tracker.first_s(), 0.7);
}

TEST(RobotTracker, ARobotUnseenForMoreThanASecondIsFollowedAnew) {
  sf::RobotTracker tracker;
  tracker.observe(1.0, {0.0, 0.0});
  tracker.observe(1.1, {100.0, 0.0});
  // Exactly the limit later: the same track.
  tracker.observe(1.1 + sf::RobotTracker::forget_after_s, {200.0, 0.0});
  EXPECT_EQ(tracker.observations(), 3);
  // Beyond it: a new track from this observation, nothing of the old velocity kept.
  const double later_s = 1.1 + 2.0 * sf::RobotTracker::forget_after_s + 0.01;
  tracker.observe(later_s, {-3000.0, 500.0});
  EXPECT_EQ(tracker.observations(), 1);
  EXPECT_DOUBLE_EQ(tracker.first_s(), later_s);
  tracker.observe(later_s + 0.1, {-3000.0, 600.0});
  EXPECT_NEAR(tracker.velocity().x, 0.0, 1e-6);
  EXPECT_NEAR(tracker.velocity().y, 1000.0, 1e-6);
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
