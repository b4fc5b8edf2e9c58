#pragma once
// A robot's velocity and acceleration from the positions the vision reports: a constant-
// acceleration Kalman filter on each axis, the way SSL teams' trackers smooth SSL-Vision.
//
// Why not the displacement over the last 0.1 s: that is the mean velocity over the window, half
// a window behind the robot, and the change between two of them a whole window behind. The
// filter gives the velocity and the acceleration now. With the settings below it is tuned to
// follow the motion closely, not to smooth: under 3 mm of noise its velocity is about as noisy
// as the difference's (tests/common/robot_tracker_test.cpp). The baselines take their velocity
// from the same filter, so the model is compared with what a team's own tracker would
// extrapolate, not with a cruder estimate.
//
// Both axes share one covariance (it depends only on the times of the observations), so an
// observation costs one covariance update and two state updates.

#include <array>

#include "ssl_formation/base/grid.hpp"

namespace ssl_formation {
inline namespace vision {

struct RobotTrackerSettings {
  // The vision's noise on a position, one standard deviation per axis.
  double position_noise_mm = 3.0;
  // How fast a robot's acceleration may change: the spectral density of its jerk (mm^2/s^5).
  // Chosen on the inner splits (each recording's first 4/9 against the next 2/9), clean and with
  // 3 mm of noise: higher follows grSim's clean motion more closely, lower smooths the noise more.
  double jerk_density = 3.0e7;
  // A robot's acceleration before the filter has seen it change (one standard deviation).
  double initial_acceleration_mm_s2 = 3000.0;
  bool valid() const;
};

class RobotTracker {
 public:
  // A robot not seen for this long is followed anew: the play moved on, and a position from
  // before says nothing of its velocity now.
  static constexpr double forget_after_s = 1.0;

  explicit RobotTracker(RobotTrackerSettings settings = {}) : settings_(settings) {}

  // Forgets the robot: the next observation starts a new track.
  void reset() { observations_ = 0; }
  // Takes a position observed at `time_s` (the data clock). Times must increase within a track:
  // an observation at or before the last one, or more than forget_after_s after it, starts a
  // new track.
  void observe(double time_s, Point position);

  // Observations since the track started; velocity and acceleration exist from the second.
  int observations() const { return observations_; }
  double first_s() const { return first_s_; }
  double last_s() const { return last_s_; }
  Point position() const { return {state_[0][0], state_[1][0]}; }
  Point velocity() const { return {state_[0][1], state_[1][1]}; }
  Point acceleration() const { return {state_[0][2], state_[1][2]}; }

 private:
  RobotTrackerSettings settings_;
  int observations_ = 0;
  double first_s_ = 0.0;
  double last_s_ = 0.0;
  Point first_position_;
  // Per axis: position (mm), velocity (mm/s), acceleration (mm/s^2).
  std::array<std::array<double, 3>, 2> state_{};
  // The shared covariance, symmetric.
  std::array<std::array<double, 3>, 3> covariance_{};
};

}  // namespace vision
}  // namespace ssl_formation
