#include "ssl_formation/pipeline/live_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace ssl_formation {
inline namespace pipeline {

namespace {

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Times this close are the same instant (sums of frame intervals round).
constexpr double kSameInstantS = 1e-6;

}  // namespace

void LiveScore::Means::reach(std::size_t step, double step_s) {
  if (step >= horizons.size()) {
    horizons.resize(step + 1);
    model_sum.resize(step + 1, 0.0);
    persistence_sum.resize(step + 1, 0.0);
  }
  horizons[step].horizon_s = static_cast<double>(step + 1) * step_s;
}

void LiveScore::Means::add(std::size_t step, double model_mm, double persistence_mm) {
  model_sum[step] += model_mm;
  persistence_sum[step] += persistence_mm;
  horizons[step].robots += 1.0;
}

void LiveScore::Means::fade(double keep) {
  for (std::size_t step = 0; step < horizons.size(); ++step) {
    model_sum[step] *= keep;
    persistence_sum[step] *= keep;
    horizons[step].robots *= keep;
  }
}

void LiveScore::Means::update_means() {
  for (std::size_t step = 0; step < horizons.size(); ++step) {
    Horizon& h = horizons[step];
    if (h.robots <= 0.0) continue;
    h.model_mm = model_sum[step] / h.robots;
    h.persistence_mm = persistence_sum[step] / h.robots;
  }
}

bool LiveScoreSettings::valid() const {
  return std::isfinite(half_life_s) && half_life_s > 0.0 && std::isfinite(remember_interval_s) &&
         remember_interval_s >= 0.0 && std::isfinite(tolerance_s) && tolerance_s >= 0.0;
}

LiveScore::LiveScore(LiveScoreSettings settings) : settings_(settings) {
  if (!settings_.valid()) throw std::invalid_argument("live score settings out of range");
}

void LiveScore::clear() {
  pending_.clear();
  all_ = Means{};
  by_phase_.fill(Means{});
  last_remembered_s_ = -1e300;
  last_seen_s_ = -1e300;
  faded_to_s_ = -1e300;
  scored_ = 0;
}

void LiveScore::fade_to(double time_s) {
  if (time_s <= faded_to_s_) return;
  const double keep = std::exp2(-(time_s - faded_to_s_) / settings_.half_life_s);
  faded_to_s_ = time_s;
  all_.fade(keep);
  for (Means& means : by_phase_) means.fade(keep);
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
    const double model_mm = distance(p.predicted, robot->feed_position);
    const double persistence_mm = distance(p.then, robot->feed_position);
    all_.add(p.step, model_mm, persistence_mm);
    by_phase_[static_cast<std::size_t>(p.phase)].add(p.step, model_mm, persistence_mm);
    ++scored_;
    scored_any = true;
  }
  if (!scored_any) return;
  all_.update_means();
  for (Means& means : by_phase_) means.update_means();
}

void LiveScore::remember(const Prediction& prediction, const Formation& formation, double step_s,
                         GamePhase phase) {
  const double t = formation.time_s;
  if (t - last_remembered_s_ < settings_.remember_interval_s) return;
  last_remembered_s_ = t;
  for (std::size_t step = 0; step < prediction.steps.size(); ++step) {
    const double due = t + static_cast<double>(step + 1) * step_s;
    all_.reach(step, step_s);
    by_phase_[static_cast<std::size_t>(phase)].reach(step, step_s);
    for (const RobotPrediction& robot : prediction.steps[step].robots) {
      const FormationRobot* now = formation.find(robot.robot_id);
      if (now == nullptr) continue;
      Pending p{due, step, robot.robot_id, phase, robot.feed_position, now->feed_position};
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
  for (const Horizon& h : all_.horizons) {
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
  std::snprintf(text, sizeof text, "%.0fmm at %.1fs (stays %.0fmm)", h->model_mm, h->horizon_s,
                h->persistence_mm);
  return text;
}

}  // namespace pipeline
}  // namespace ssl_formation
