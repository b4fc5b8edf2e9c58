#include "ssl_formation/online_calibration.hpp"

#include <algorithm>
#include <cmath>

namespace ssl_formation {

namespace {
// Predictions remembered per step at most: ten seconds of a 100 Hz feed's 16 robots. Only a
// caller that remembers without observing could reach it; the oldest go first.
constexpr std::size_t max_pending_per_step = 16000;
}  // namespace

OnlineCalibration::OnlineCalibration(OnlineCalibrationSettings settings) : settings_(settings) {}

std::size_t OnlineCalibration::bin_of(double probability) {
  const double scaled = std::clamp(probability, 0.0, 1.0) * bin_count;
  return std::min(static_cast<std::size_t>(scaled), static_cast<std::size_t>(bin_count - 1));
}

void OnlineCalibration::clear() {
  steps_.clear();
  last_time_s_.reset();
  checked_ = 0;
}

std::size_t OnlineCalibration::pending() const {
  std::size_t total = 0;
  for (const Step& step : steps_) total += step.pending.size();
  return total;
}

void OnlineCalibration::observe(const Formation& formation) {
  const double t = formation.time_s;
  if (last_time_s_ && t < *last_time_s_) clear();
  if (last_time_s_ && t > *last_time_s_) {
    const double fade = std::exp2(-(t - *last_time_s_) / settings_.half_life_s);
    for (Step& step : steps_) {
      for (Bin& bin : step.bins) {
        bin.weight *= fade;
        bin.hits *= fade;
        bin.stated *= fade;
      }
    }
  }
  last_time_s_ = t;
  for (Step& step : steps_) {
    // The predictions due by now, front first; those waiting for their robot (not seen in this
    // frame, still within the tolerance) are kept, in order, at the front.
    std::size_t due = 0;
    std::size_t kept = 0;
    for (; due < step.pending.size() && step.pending[due].due_s <= t; ++due) {
      const Pending& p = step.pending[due];
      if (p.attacks != formation.opponent_attacks) continue;  // its cells mean another side
      if (t - p.due_s > settings_.tolerance_s) continue;       // passed unseen
      const FormationRobot* robot = formation.find(p.robot_id);
      if (robot && robot->observed) {
        Bin& bin = step.bins[bin_of(p.probability)];
        bin.weight += 1.0;
        bin.hits += robot->cell == p.cell ? 1.0 : 0.0;
        bin.stated += p.probability;
        ++checked_;
      } else {
        step.pending[kept++] = p;
      }
    }
    step.pending.erase(step.pending.begin() + static_cast<std::ptrdiff_t>(kept),
                       step.pending.begin() + static_cast<std::ptrdiff_t>(due));
  }
}

void OnlineCalibration::remember(const Prediction& prediction, double time_s, double step_s,
                                 AttackDirection attacks) {
  if (steps_.size() < prediction.steps.size()) steps_.resize(prediction.steps.size());
  for (std::size_t s = 0; s < prediction.steps.size(); ++s) {
    Step& step = steps_[s];
    const double due_s = time_s + static_cast<double>(s + 1) * step_s;
    for (const RobotPrediction& robot : prediction.steps[s].robots) {
      if (step.pending.size() >= max_pending_per_step) step.pending.pop_front();
      step.pending.push_back({due_s, robot.robot_id, robot.position, robot.probability, attacks});
    }
  }
}

double OnlineCalibration::adjusted(std::size_t step, double stated) const {
  if (step >= steps_.size()) return stated;
  const Bin& bin = steps_[step].bins[bin_of(stated)];
  if (!(bin.weight > 0.0)) return stated;
  const double evidence = bin.weight / (bin.weight + settings_.prior_weight);
  const double shift = (bin.hits - bin.stated) / bin.weight;
  return std::clamp(stated + evidence * shift, min_probability, max_probability);
}

void OnlineCalibration::adjust(Prediction& prediction) const {
  if (checked_ == 0) return;
  double confidence = 1.0;
  for (std::size_t s = 0; s < prediction.steps.size(); ++s) {
    PredictedStep& step = prediction.steps[s];
    double formation = 1.0;
    for (RobotPrediction& robot : step.robots) {
      robot.probability = adjusted(s, robot.probability);
      formation *= robot.probability;
    }
    step.formation_probability = formation;
    confidence *= formation;
    step.confidence = confidence;
  }
}

}  // namespace ssl_formation
