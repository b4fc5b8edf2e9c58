#include "ssl_formation/pipeline/live_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace ssl_formation {

namespace {

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Times this close are the same instant (sums of frame intervals round).
constexpr double kSameInstantS = 1e-6;

}  // namespace

bool LiveScoreSettings::valid() const {
  return std::isfinite(half_life_s) && half_life_s > 0.0 && std::isfinite(remember_interval_s) &&
         remember_interval_s >= 0.0 && std::isfinite(tolerance_s) && tolerance_s >= 0.0;
}

LiveScore::LiveScore(LiveScoreSettings settings) : settings_(settings) {
  if (!settings_.valid()) throw std::invalid_argument("live score settings out of range");
}

void LiveScore::clear() {
  pending_.clear();
  horizons_.clear();
  model_sum_.clear();
  persistence_sum_.clear();
  last_remembered_s_ = -1e300;
  last_seen_s_ = -1e300;
  faded_to_s_ = -1e300;
  scored_ = 0;
}

void LiveScore::fade_to(double time_s) {
  if (time_s <= faded_to_s_) return;
  const double keep = std::exp2(-(time_s - faded_to_s_) / settings_.half_life_s);
  faded_to_s_ = time_s;
  for (std::size_t step = 0; step < horizons_.size(); ++step) {
    model_sum_[step] *= keep;
    persistence_sum_[step] *= keep;
    horizons_[step].robots *= keep;
  }
}

void LiveScore::observe(const Formation& formation) {
  const double t = formation.time_s;
  if (t < last_seen_s_) clear();  // another clock: nothing kept compares
  last_seen_s_ = t;
  fade_to(t);
  bool scored_any = false;
  // Each prediction is checked by the first frame at (or, by rounding, a microsecond before)
  // its instant, if that frame comes within the tolerance.
  while (!pending_.empty() && pending_.front().due_s <= t + kSameInstantS) {
    const Pending p = pending_.front();
    pending_.pop_front();
    if (t - p.due_s > settings_.tolerance_s) continue;  // its instant passed unseen
    const FormationRobot* robot = formation.find(p.robot_id);
    if (robot == nullptr) continue;
    if (p.step >= horizons_.size()) {
      horizons_.resize(p.step + 1);
      model_sum_.resize(p.step + 1, 0.0);
      persistence_sum_.resize(p.step + 1, 0.0);
    }
    model_sum_[p.step] += distance(p.predicted, robot->feed_position);
    persistence_sum_[p.step] += distance(p.then, robot->feed_position);
    horizons_[p.step].robots += 1.0;
    ++scored_;
    scored_any = true;
  }
  if (!scored_any) return;
  for (std::size_t step = 0; step < horizons_.size(); ++step) {
    Horizon& h = horizons_[step];
    if (h.robots <= 0.0) continue;
    h.model_mm = model_sum_[step] / h.robots;
    h.persistence_mm = persistence_sum_[step] / h.robots;
  }
}

void LiveScore::remember(const Prediction& prediction, const Formation& formation, double step_s) {
  const double t = formation.time_s;
  if (t - last_remembered_s_ < settings_.remember_interval_s) return;
  last_remembered_s_ = t;
  for (std::size_t step = 0; step < prediction.steps.size(); ++step) {
    const double due = t + static_cast<double>(step + 1) * step_s;
    if (step >= horizons_.size()) {
      horizons_.resize(step + 1);
      model_sum_.resize(step + 1, 0.0);
      persistence_sum_.resize(step + 1, 0.0);
    }
    horizons_[step].horizon_s = static_cast<double>(step + 1) * step_s;
    for (const RobotPrediction& robot : prediction.steps[step].robots) {
      const FormationRobot* now = formation.find(robot.robot_id);
      if (now == nullptr) continue;
      Pending p{due, step, robot.robot_id, robot.feed_position, now->feed_position};
      // Kept in order of due time: later predictions' near steps fall before earlier ones'
      // far steps.
      const auto at =
          std::upper_bound(pending_.begin(), pending_.end(), due,
                           [](double due_s, const Pending& other) { return due_s < other.due_s; });
      pending_.insert(at, p);
    }
  }
}

const LiveScore::Horizon* LiveScore::nearest(double horizon_s) const {
  const Horizon* best = nullptr;
  for (const Horizon& h : horizons_) {
    if (h.robots <= 0.0) continue;
    if (best == nullptr ||
        std::abs(h.horizon_s - horizon_s) < std::abs(best->horizon_s - horizon_s)) {
      best = &h;
    }
  }
  return best;
}

std::string describe_for_status(const LiveScore& score) {
  const LiveScore::Horizon* h = score.nearest(1.0);
  if (h == nullptr) return {};
  char text[128];
  std::snprintf(text, sizeof text, " live_error_mm=%.0f stays_error_mm=%.0f live_horizon_s=%.1f",
                h->model_mm, h->persistence_mm, h->horizon_s);
  return text;
}

}  // namespace ssl_formation
