#include "ssl_formation/robot_tracker.hpp"

#include <cmath>

namespace ssl_formation {

bool RobotTrackerSettings::valid() const {
  return std::isfinite(position_noise_mm) && position_noise_mm > 0.0 &&
         std::isfinite(jerk_density) && jerk_density > 0.0 &&
         std::isfinite(initial_acceleration_mm_s2) && initial_acceleration_mm_s2 > 0.0;
}

void RobotTracker::observe(double time_s, Point position) {
  const double noise = settings_.position_noise_mm * settings_.position_noise_mm;
  if (observations_ > 0 && !(time_s > last_s_)) observations_ = 0;
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
    covariance_ = {{{noise, noise / dt, 0.0},
                    {noise / dt, 2.0 * noise / (dt * dt) + a0 * a0 * dt * dt / 4.0, a0 * a0 * dt / 2.0},
                    {0.0, a0 * a0 * dt / 2.0, a0 * a0}}};
    return;
  }
  ++observations_;
  // Prediction: x <- F x with F = [1 dt dt^2/2; 0 1 dt; 0 0 1], P <- F P F' + Q, where Q is the
  // white-jerk model's noise over dt.
  const double dt2 = dt * dt, dt3 = dt2 * dt, dt4 = dt3 * dt, dt5 = dt4 * dt;
  const double q = settings_.jerk_density;
  const std::array<std::array<double, 3>, 3> f{{{1.0, dt, dt2 / 2.0}, {0.0, 1.0, dt}, {0.0, 0.0, 1.0}}};
  const std::array<std::array<double, 3>, 3> process{{{q * dt5 / 20.0, q * dt4 / 8.0, q * dt3 / 6.0},
                                                      {q * dt4 / 8.0, q * dt3 / 3.0, q * dt2 / 2.0},
                                                      {q * dt3 / 6.0, q * dt2 / 2.0, q * dt}}};
  std::array<std::array<double, 3>, 3> fp{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = i; k < 3; ++k) fp[i][j] += f[i][k] * covariance_[k][j];  // F is upper
    }
  }
  std::array<std::array<double, 3>, 3> predicted = process;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = j; k < 3; ++k) predicted[i][j] += fp[i][k] * f[j][k];
    }
  }
  // Update with the observed position: gain K = P H' / (H P H' + R), H = [1 0 0].
  const double innovation_variance = predicted[0][0] + noise;
  const std::array<double, 3> gain{predicted[0][0] / innovation_variance,
                                   predicted[1][0] / innovation_variance,
                                   predicted[2][0] / innovation_variance};
  const double observed[2] = {position.x, position.y};
  for (int axis = 0; axis < 2; ++axis) {
    std::array<double, 3>& x = state_[static_cast<std::size_t>(axis)];
    const double p = x[0] + dt * x[1] + dt2 / 2.0 * x[2];
    const double v = x[1] + dt * x[2];
    const double a = x[2];
    const double residual = observed[axis] - p;
    x = {p + gain[0] * residual, v + gain[1] * residual, a + gain[2] * residual};
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) covariance_[i][j] = predicted[i][j] - gain[i] * predicted[0][j];
  }
}

}  // namespace ssl_formation
