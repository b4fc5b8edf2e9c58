#include "ssl_formation/vision/robot_tracker.hpp"

#include <cmath>

namespace ssl_formation {
inline namespace vision {

bool RobotTrackerSettings::valid() const {
  return std::isfinite(position_noise_mm) && position_noise_mm > 0.0 &&
         std::isfinite(jerk_density) && jerk_density > 0.0 &&
         std::isfinite(initial_acceleration_mm_s2) && initial_acceleration_mm_s2 > 0.0;
}

void RobotTracker::observe(double time_s, Point position) {
  const double noise = settings_.position_noise_mm * settings_.position_noise_mm;
  if (observations_ > 0 && !(time_s > last_s_ && time_s - last_s_ <= forget_after_s)) {
    observations_ = 0;
  }
  if (observations_ == 0) {
    observations_ = 1;
    first_s_ = last_s_ = time_s;
    first_position_ = position;
    state_ = {{{position.x, 0.0, 0.0}, {position.y, 0.0, 0.0}}};
    return;
  }
  const double dt = time_s - last_s_;
  last_s_ = time_s;
  if (observations_ == 1) {
    // Two positions: the velocity between them, no acceleration yet (a diffuse start would hold
    // the velocity towards zero for several frames). Their covariance is that of a difference
    // of two noisy positions.
    ++observations_;
    state_ = {{{position.x, (position.x - first_position_.x) / dt, 0.0},
               {position.y, (position.y - first_position_.y) / dt, 0.0}}};
    const double a0 = settings_.initial_acceleration_mm_s2;
    // The difference's velocity is the one half-way between the two: an acceleration a makes
    // it a dt / 2 short of the velocity now.
    covariance_ = {
        {{noise, noise / dt, 0.0},
         {noise / dt, 2.0 * noise / (dt * dt) + a0 * a0 * dt * dt / 4.0, a0 * a0 * dt / 2.0},
         {0.0, a0 * a0 * dt / 2.0, a0 * a0}}};
    return;
  }
  ++observations_;
  const double h = dt * dt / 2.0;
  // Prediction: x <- F x with F = [1 dt h; 0 1 dt; 0 0 1] (h = dt^2 / 2), P <- F P F' + Q, where
  // Q is the white-jerk model's noise over dt. Written out on the six distinct entries of the
  // symmetric P (tests/common/robot_tracker_test.cpp holds it to the plain matrix products):
  // this runs for every observed robot of every frame, in training too.
  const double dt2 = dt * dt, dt3 = dt2 * dt, dt4 = dt3 * dt, dt5 = dt4 * dt;
  const double q = settings_.jerk_density;
  auto& c = covariance_;
  const double c00 = c[0][0], c01 = c[0][1], c02 = c[0][2], c11 = c[1][1], c12 = c[1][2],
               c22 = c[2][2];
  const double p00 = c00 + 2.0 * dt * c01 + 2.0 * h * c02 + dt2 * c11 + 2.0 * dt * h * c12 +
                     h * h * c22 + q * dt5 / 20.0;
  const double p01 = c01 + dt * (c02 + c11) + (dt2 + h) * c12 + h * dt * c22 + q * dt4 / 8.0;
  const double p02 = c02 + dt * c12 + h * c22 + q * dt3 / 6.0;
  const double p11 = c11 + 2.0 * dt * c12 + dt2 * c22 + q * dt3 / 3.0;
  const double p12 = c12 + dt * c22 + q * dt2 / 2.0;
  const double p22 = c22 + q * dt;
  // Update with the observed position: gain K = P H' / (H P H' + R), H = [1 0 0].
  const double inverse = 1.0 / (p00 + noise);
  const double k0 = p00 * inverse, k1 = p01 * inverse, k2 = p02 * inverse;
  const double observed[2] = {position.x, position.y};
  for (int axis = 0; axis < 2; ++axis) {
    std::array<double, 3>& x = state_[static_cast<std::size_t>(axis)];
    const double predicted_position = x[0] + dt * x[1] + h * x[2];
    const double residual = observed[axis] - predicted_position;
    x = {predicted_position + k0 * residual, x[1] + dt * x[2] + k1 * residual,
         x[2] + k2 * residual};
  }
  const double n00 = p00 - k0 * p00, n01 = p01 - k0 * p01, n02 = p02 - k0 * p02;
  const double n11 = p11 - k1 * p01, n12 = p12 - k1 * p02, n22 = p22 - k2 * p02;
  c = {{{n00, n01, n02}, {n01, n11, n12}, {n02, n12, n22}}};
}

}  // namespace vision
}  // namespace ssl_formation
