#include "ball_trail.hpp"

#include <cmath>
#include <stdexcept>

namespace ssl_formation::predictor::web {

bool BallTrailSettings::valid() const {
  return std::isfinite(keep_s) && keep_s > 0.0 && std::isfinite(spacing_s) && spacing_s >= 0.0 &&
         std::isfinite(forget_after_s) && forget_after_s > 0.0 && std::isfinite(clock_reset_s) &&
         clock_reset_s > 0.0;
}

BallTrail::BallTrail(BallTrailSettings settings) : settings_(settings) {
  if (!settings_.valid()) throw std::invalid_argument("ball trail settings out of range");
}

void BallTrail::clear() {
  path_.clear();
  times_.clear();
  seen_ = false;
  head_between_points_ = false;
  last_point_s_ = 0.0;
}

void BallTrail::update(const std::optional<BallState>& ball, double now_s) {
  if (!ball || !std::isfinite(now_s) || !std::isfinite(ball->time_s) ||
      now_s - ball->time_s > settings_.forget_after_s) {
    clear();
    return;
  }
  const double t = ball->time_s;
  if (!times_.empty() && t < times_.back() - settings_.clock_reset_s) clear();
  if (!times_.empty() && t < times_.back()) return;  // an older camera's frame: nothing new
  // A point every spacing_s, and the newest sighting in between as the path's last point, so
  // that the path ends where the ball is.
  if (times_.empty() || t >= last_point_s_ + settings_.spacing_s) {
    if (head_between_points_) {
      path_.back() = ball->position;
      times_.back() = t;
    } else {
      path_.push_back(ball->position);
      times_.push_back(t);
    }
    last_point_s_ = t;
    head_between_points_ = false;
  } else if (head_between_points_) {
    path_.back() = ball->position;
    times_.back() = t;
  } else {
    path_.push_back(ball->position);
    times_.push_back(t);
    head_between_points_ = true;
  }
  while (!times_.empty() && times_.front() < t - settings_.keep_s) {
    times_.pop_front();
    path_.pop_front();
  }
  if (times_.empty()) head_between_points_ = false;
  seen_ = !path_.empty();
}

std::optional<Point> BallTrail::position() const {
  if (!seen_) return std::nullopt;
  return path_.back();
}

}  // namespace ssl_formation::predictor::web
