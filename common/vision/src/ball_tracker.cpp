#include "ssl_formation/vision/ball_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ssl_formation {
inline namespace vision {

namespace {
// Times equal but for rounding (a window edge that falls on a frame time).
constexpr double time_epsilon_s = 1e-9;
}  // namespace

bool BallTrackerSettings::valid() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  return std::isfinite(min_confidence) && positive(velocity_window_s) && positive(forget_after_s) &&
         non_negative(jump_mm) && non_negative(max_speed_mm_s) && non_negative(same_instant_s) &&
         positive(max_abs_coordinate_mm) && max_window_sightings >= 2;
}

BallTracker::BallTracker(BallTrackerSettings settings) : settings_(settings) {
  if (!settings_.valid()) throw std::invalid_argument("invalid ball tracker settings");
}

void BallTracker::add(const VisionDetection& detection) {
  const double t = detection.t_capture;
  if (!std::isfinite(t)) return;
  const VisionBall* best = nullptr;
  for (const VisionBall& ball : detection.balls) {
    // NaN confidences and positions fail these comparisons and are left out.
    if (!(ball.confidence >= settings_.min_confidence)) continue;
    if (!(std::abs(ball.x) <= settings_.max_abs_coordinate_mm) ||
        !(std::abs(ball.y) <= settings_.max_abs_coordinate_mm)) {
      continue;
    }
    if (best == nullptr || ball.confidence > best->confidence) best = &ball;
  }
  if (best != nullptr) observe(t, Point{best->x, best->y}, detection.camera_id);
}

void BallTracker::observe(double time_s, Point position, std::uint32_t camera_id) {
  if (!std::isfinite(time_s) || !std::isfinite(position.x) || !std::isfinite(position.y)) return;
  if (!state_) {
    start_over(time_s, position, camera_id);
    return;
  }
  const double dt = time_s - state_->time_s;
  // Unseen too long, or another clock (a restarted sender, a new recording): start over.
  if (dt > settings_.forget_after_s || dt < -settings_.forget_after_s) {
    start_over(time_s, position, camera_id);
    return;
  }
  const double dx = position.x - state_->position.x;
  const double dy = position.y - state_->position.y;
  const bool jump =
      std::hypot(dx, dy) > settings_.jump_mm + settings_.max_speed_mm_s * std::abs(dt);
  if (dt < -settings_.same_instant_s) {
    // Older than the ball we have: the newest sighting stays the ball, but this one still tells
    // where the ball was then.
    if (jump) return;
    window_.push_back({time_s, position, camera_id});
  } else if (jump) {
    // Another ball, or this one put down elsewhere: what came before says nothing of its motion.
    start_over(time_s, position, camera_id);
    return;
  } else if (dt <= settings_.same_instant_s) {
    // The same instant from another camera (or the same frame again): one ball, averaged.
    instant_sum_x_ += position.x;
    instant_sum_y_ += position.y;
    instant_weight_ += 1.0;
    state_->time_s = std::max(state_->time_s, time_s);
    state_->position = Point{instant_sum_x_ / instant_weight_, instant_sum_y_ / instant_weight_};
    window_.push_back({time_s, position, camera_id});
  } else {
    instant_sum_x_ = position.x;
    instant_sum_y_ = position.y;
    instant_weight_ = 1.0;
    state_->time_s = time_s;
    state_->position = position;
    window_.push_back({time_s, position, camera_id});
  }
  update_velocity();
}

void BallTracker::set(const BallState& state) {
  if (!std::isfinite(state.time_s) || !std::isfinite(state.position.x) ||
      !std::isfinite(state.position.y)) {
    return;
  }
  state_ = state;
  if (!std::isfinite(state.velocity.x) || !std::isfinite(state.velocity.y)) {
    state_->velocity = Point{};
  }
  instant_sum_x_ = state.position.x;
  instant_sum_y_ = state.position.y;
  instant_weight_ = 1.0;
  window_.clear();
}

void BallTracker::reset() {
  state_.reset();
  window_.clear();
  instant_weight_ = 0.0;
}

std::optional<BallState> BallTracker::at(double time_s) const {
  if (!state_ || !(std::abs(time_s - state_->time_s) <= settings_.forget_after_s)) {
    return std::nullopt;
  }
  return state_;
}

void BallTracker::start_over(double time_s, Point position, std::uint32_t camera_id) {
  state_ = BallState{time_s, position, Point{}};
  instant_sum_x_ = position.x;
  instant_sum_y_ = position.y;
  instant_weight_ = 1.0;
  window_.clear();
  window_.push_back({time_s, position, camera_id});
}

// The slope of the sightings against time, fitted within each camera: sum over cameras of
// S_tx / sum of S_tt (each camera's own offset taken out). Until some camera has two sightings of
// different instants in the window, the velocity stays what it was (zero after a start).
void BallTracker::update_velocity() {
  const double newest_s = state_->time_s;
  const double oldest_s = newest_s - settings_.velocity_window_s - time_epsilon_s;
  std::erase_if(window_, [&](const Sighting& s) { return s.time_s < oldest_s; });
  if (window_.size() > settings_.max_window_sightings) {
    window_.erase(window_.begin(),
                  window_.begin() +
                      static_cast<std::ptrdiff_t>(window_.size() - settings_.max_window_sightings));
  }

  std::vector<CameraSums>& sums = sums_scratch_;
  sums.clear();
  for (const Sighting& s : window_) {
    auto it = std::find_if(sums.begin(), sums.end(),
                           [&](const CameraSums& c) { return c.camera_id == s.camera_id; });
    if (it == sums.end()) {
      it = sums.insert(sums.end(), CameraSums{});
      it->camera_id = s.camera_id;
      it->first_s = s.time_s;
      it->last_s = s.time_s;
    }
    // Times relative to the newest keep the sums small: t_capture may be Unix time.
    const double t = s.time_s - newest_s;
    const double x = s.position.x - state_->position.x;
    const double y = s.position.y - state_->position.y;
    it->n += 1.0;
    it->t += t;
    it->x += x;
    it->y += y;
    it->tt += t * t;
    it->tx += t * x;
    it->ty += t * y;
    it->first_s = std::min(it->first_s, s.time_s);
    it->last_s = std::max(it->last_s, s.time_s);
  }
  double s_tt = 0.0, s_tx = 0.0, s_ty = 0.0;
  bool determined = false;
  for (const CameraSums& c : sums) {
    if (c.last_s - c.first_s <= settings_.same_instant_s) continue;
    determined = true;
    s_tt += c.tt - c.t * c.t / c.n;
    s_tx += c.tx - c.t * c.x / c.n;
    s_ty += c.ty - c.t * c.y / c.n;
  }
  if (!determined || !(s_tt > 0.0)) return;
  state_->velocity = Point{s_tx / s_tt, s_ty / s_tt};
}

}  // namespace vision
}  // namespace ssl_formation
