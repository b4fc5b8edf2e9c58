#include "ssl_formation/motion_model/online_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace ssl_formation {
inline namespace motion_model {

namespace {
// Predictions remembered per step at most, the oldest going first: 16 robots remembered 10
// times a second for 400 s. Only a step further ahead than that (or a caller that remembers
// without observing) reaches it.
constexpr std::size_t max_pending_per_step = 65536;
constexpr std::size_t first_ring_size = 256;
// How often the corrections adjust() adds are worked out again, in seconds of the data clock: a
// division per bin, where the evidence behind them changes by a thousandth in this time.
constexpr double correction_refresh_s = 0.1;
// When a check's weight in the radii's histograms passes this, every histogram is scaled back.
constexpr double max_boost = 1e30;
}  // namespace

void OnlineCalibration::Step::push(const Pending& pending) {
  if (size == ring.size()) {
    if (size >= max_pending_per_step) {
      head = (head + 1) & (ring.size() - 1);  // the oldest goes
      --size;
    } else {
      std::vector<Pending> grown(std::max(first_ring_size, 2 * ring.size()));
      for (std::size_t i = 0; i < size; ++i) grown[i] = at(i);
      ring = std::move(grown);
      head = 0;
    }
  }
  at(size++) = pending;
}

bool OnlineCalibrationSettings::valid() const {
  const auto finite = [](double value) { return std::isfinite(value); };
  return finite(half_life_s) && finite(prior_weight) && finite(tolerance_s) &&
         finite(remember_interval_s) && finite(radius_half_count) && half_life_s > 0.0 &&
         prior_weight >= 0.0 && tolerance_s >= 0.0 && remember_interval_s >= 0.0 &&
         radius_half_count >= 1.0;
}

OnlineCalibration::OnlineCalibration(OnlineCalibrationSettings settings)
    : settings_(settings), radius_growth_(std::exp2(1.0 / settings.radius_half_count)) {}

std::size_t OnlineCalibration::bin_of(double probability) {
  const double scaled = std::clamp(probability, 0.0, 1.0) * bin_count;
  return std::min(static_cast<std::size_t>(scaled), static_cast<std::size_t>(bin_count - 1));
}

namespace {

// The natural logarithm of a positive float, within 0.0053 (a tenth of a radius bin): its
// exponent and a quadratic in its mantissa. Two exact logarithms per checked robot were 7% of a
// frame's prediction time.
double approximate_log(float x) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  const int exponent = static_cast<int>(bits >> 23) - 127;
  const float f = static_cast<float>(bits & 0x7fffffu) * (1.0f / 8388608.0f);
  return (static_cast<float>(exponent) + f * (1.3465f - 0.3465f * f)) * 0.6931471805599453;
}

}  // namespace

std::size_t OnlineCalibration::radius_bin_of(double off_mm, double radius_mm) {
  if (!(off_mm > 0.0) || !(radius_mm > 0.0)) return 0;  // spot on, or nothing to scale
  const double log_off = approximate_log(static_cast<float>(off_mm / radius_mm));
  const double at = (log_off + max_log_radius_scale) / radius_bin_width;
  if (!(at > 0.0)) return 0;
  return std::min(static_cast<std::size_t>(at), radius_bins - 1);
}

double OnlineCalibration::log_quantile(const std::array<float, radius_bins>& bins, double weight,
                                       double q, std::size_t first, std::size_t last) {
  // The bin where the cumulative weight passes q, and linearly within it.
  const double target = q * weight;
  double below = 0.0;
  for (std::size_t b = first; b <= last; ++b) {
    const double in = bins[b];
    if (below + in >= target && in > 0.0) {
      const double within = (target - below) / in;
      return -max_log_radius_scale + (static_cast<double>(b) + within) * radius_bin_width;
    }
    below += in;
  }
  return max_log_radius_scale;
}

void OnlineCalibration::clear() {
  steps_.clear();
  last_time_s_.reset();
  correcting_.reset();
  remembering_.reset();
  checked_ = 0;
  formations_checked_ = 0;
}

std::size_t OnlineCalibration::pending() const {
  std::size_t total = 0;
  for (const Step& step : steps_) total += step.size;
  return total;
}

void OnlineCalibration::observe(const Formation& formation) {
  const double t = formation.time_s;
  if (last_time_s_ && t < *last_time_s_) clear();
  const double fade = last_time_s_ && t > *last_time_s_
                          ? std::exp2(-(t - *last_time_s_) / settings_.half_life_s)
                          : 1.0;
  last_time_s_ = t;
  for (Step& step : steps_) {
    if (fade != 1.0) {
      for (auto* bins : {&step.bins, &step.formation_bins}) {
        for (Bin& bin : *bins) {
          bin.weight *= fade;
          bin.hits *= fade;
          bin.stated *= fade;
        }
      }
    }
    // The predictions due by now, front first. Those waiting for their robot (not seen in this
    // frame, still within the tolerance) are gathered at the front, in order, and stay.
    std::size_t due = 0;
    std::size_t kept = 0;
    // One prediction's robots come in the formation's order (by id), so each is found by walking
    // on from the last; a lower id starts the next prediction's.
    const std::vector<FormationRobot>& robots = formation.robots;
    std::size_t walk = 0;
    for (; due < step.size && step.at(due).due_s <= t; ++due) {
      const Pending& p = step.at(due);
      FormationCheck* check = step.formation(p.formation);
      const auto undecidable = [check] {
        if (!check) return;
        --check->remaining;
        check->decidable = false;
      };
      if (p.attacks != formation.opponent_attacks) {  // its cells mean another side
        undecidable();
        continue;
      }
      if (t - p.due_s > settings_.tolerance_s) {  // passed unseen
        undecidable();
        continue;
      }
      if (walk > 0 && (walk == robots.size() || robots[walk].robot_id > p.robot_id)) walk = 0;
      while (walk < robots.size() && robots[walk].robot_id < p.robot_id) ++walk;
      const FormationRobot* robot =
          walk < robots.size() && robots[walk].robot_id == p.robot_id ? &robots[walk] : nullptr;
      if (robot && robot->observed) {
        if (p.radius90 > 0.0f) {
          // How far off, as a multiple of each stated radius, into the phase's histograms.
          const double off = std::hypot(robot->position.x - p.x, robot->position.y - p.y);
          RadiusEvidence& evidence = step.radii[p.group];
          const std::size_t bin50 = radius_bin_of(off, p.radius50);
          const std::size_t bin90 = radius_bin_of(off, p.radius90);
          evidence.off50[bin50] += static_cast<float>(evidence.boost);
          evidence.off90[bin90] += static_cast<float>(evidence.boost);
          evidence.first = std::min({evidence.first, bin50, bin90});
          evidence.last = std::max({evidence.last, bin50, bin90});
          evidence.weight += evidence.boost;
          evidence.fresh = true;
          evidence.boost *= radius_growth_;
          if (evidence.boost > max_boost) {
            // Back to the scale of one check: the same evidence, in smaller numbers.
            const double back = 1.0 / evidence.boost;
            for (float& w : evidence.off50) w = static_cast<float>(w * back);
            for (float& w : evidence.off90) w = static_cast<float>(w * back);
            evidence.weight *= back;
            evidence.boost = 1.0;
          }
        }
        Bin& bin = step.bins[p.bin];
        const bool hit = robot->cell.x == p.cell_x && robot->cell.y == p.cell_y;
        bin.weight += 1.0;
        bin.hits += hit ? 1.0 : 0.0;
        bin.stated += p.probability;
        ++checked_;
        if (check) {
          --check->remaining;
          check->all_hit = check->all_hit && hit;
        }
      } else {
        step.at(kept++) = p;
      }
    }
    // Drops the `due - kept` handled ones: the kept move up against the not yet due.
    const std::size_t handled = due - kept;
    for (std::size_t i = kept; i-- > 0;) step.at(handled + i) = step.at(i);
    if (!step.ring.empty()) step.head = (step.head + handled) & (step.ring.size() - 1);
    step.size -= handled;
    // The formations every robot of which is decided, in order; one whose instant passed long
    // ago with robots undecided lost them (dropped from a full ring): it decides nothing.
    while (!step.formations.empty()) {
      const FormationCheck& first = step.formations.front();
      if (first.remaining > 0 && t - first.due_s <= settings_.tolerance_s) break;
      if (first.remaining == 0 && first.decidable) {
        Bin& bin = step.formation_bins[bin_of(first.stated)];
        bin.weight += 1.0;
        bin.hits += first.all_hit ? 1.0 : 0.0;
        bin.stated += first.stated;
        ++formations_checked_;
      }
      step.formations.pop_front();
      ++step.first_formation;
    }
  }
  if (!correcting_.pass(t, correction_refresh_s)) return;
  for (Step& step : steps_) {
    for (std::size_t g = 0; g < radius_groups; ++g) {
      RadiusEvidence& evidence = step.radii[g];
      if (!evidence.fresh) continue;  // nothing new since the scales were last worked out
      evidence.fresh = false;
      // The quantiles of the evidence, held towards the stated radii (scale 1) by the prior.
      const double weight = evidence.weight / evidence.boost;
      const double trust = weight / (weight + settings_.prior_weight);
      step.scale50[g] = std::exp(trust * log_quantile(evidence.off50, evidence.weight, 0.5,
                                                      evidence.first, evidence.last));
      step.scale90[g] = std::exp(trust * log_quantile(evidence.off90, evidence.weight, 0.9,
                                                      evidence.first, evidence.last));
    }
    for (std::size_t b = 0; b < step.bins.size(); ++b) {
      const Bin& bin = step.bins[b];
      step.correction[b] =
          bin.weight > 0.0
              ? (bin.hits - bin.stated) / (bin.weight + settings_.prior_weight)  // evidence x shift
              : 0.0;
      const Bin& formations = step.formation_bins[b];
      step.formation_checked[b] = formations.weight > 0.0;
      // A formation is one check where a robot is one of 6-11: the same prior weight in
      // formations lets a bin's rate count after about as many seconds of play.
      step.formation_correction[b] =
          formations.weight > 0.0
              ? (formations.hits - formations.stated) / (formations.weight + settings_.prior_weight)
              : 0.0;
    }
  }
}

void OnlineCalibration::remember(const Prediction& prediction, double time_s, double step_s,
                                 AttackDirection attacks, GamePhase phase, bool preparing) {
  const auto group = static_cast<std::uint8_t>(radius_group(phase, preparing));
  if (!remembering_.pass(time_s, settings_.remember_interval_s)) return;
  if (steps_.size() < prediction.steps.size()) steps_.resize(prediction.steps.size());
  for (std::size_t s = 0; s < prediction.steps.size(); ++s) {
    Step& step = steps_[s];
    const double due_s = time_s + static_cast<double>(s + 1) * step_s;
    FormationCheck check{due_s, 1.0, 0, true, true};
    const std::uint64_t number = step.first_formation + step.formations.size();
    for (const RobotPrediction& robot : prediction.steps[s].robots) {
      if (!std::isfinite(robot.probability)) {
        check.decidable = false;  // a formation with a robot nobody can check
        continue;
      }
      check.stated *= formation_factor(robot, robot.probability);
      ++check.remaining;
      step.push({due_s, number, robot.robot_id, static_cast<float>(robot.probability),
                 static_cast<std::int16_t>(robot.position.x),
                 static_cast<std::int16_t>(robot.position.y),
                 static_cast<std::uint8_t>(bin_of(robot.probability)), attacks, group,
                 static_cast<float>(robot.normalised_position.x),
                 static_cast<float>(robot.normalised_position.y),
                 static_cast<float>(robot.radius50_mm), static_cast<float>(robot.radius90_mm)});
    }
    step.formations.push_back(check);
    if (step.formations.size() > max_pending_per_step) {  // as the robots' ring: the oldest goes
      step.formations.pop_front();
      ++step.first_formation;
    }
  }
}

double OnlineCalibration::adjusted(std::size_t step, double stated) const {
  if (step >= steps_.size() || !std::isfinite(stated)) return stated;
  const double correction = steps_[step].correction[bin_of(stated)];
  if (correction == 0.0) return stated;
  return std::clamp(stated + correction, min_probability, max_probability);
}

double OnlineCalibration::adjusted_formation(std::size_t step, double stated,
                                             double fallback) const {
  if (step >= steps_.size() || !std::isfinite(stated)) return fallback;
  const std::size_t bin = bin_of(stated);
  if (!steps_[step].formation_checked[bin]) return fallback;
  return std::clamp(stated + steps_[step].formation_correction[bin], 0.0, 1.0);
}

std::size_t OnlineCalibration::radius_group(GamePhase phase, bool preparing) {
  if (preparing && phase == GamePhase::kickoff_opponent) return all_game_phases.size();
  return static_cast<std::size_t>(phase);
}

double OnlineCalibration::radius50_scale(std::size_t step, GamePhase phase, bool preparing) const {
  return step < steps_.size() ? steps_[step].scale50[radius_group(phase, preparing)] : 1.0;
}

double OnlineCalibration::radius90_scale(std::size_t step, GamePhase phase, bool preparing) const {
  return step < steps_.size() ? steps_[step].scale90[radius_group(phase, preparing)] : 1.0;
}

void OnlineCalibration::adjust(Prediction& prediction, GamePhase phase, bool preparing) const {
  if (checked_ == 0) return;
  double confidence = 1.0;
  for (std::size_t s = 0; s < prediction.steps.size(); ++s) {
    PredictedStep& step = prediction.steps[s];
    double stated = 1.0;
    double robots = 1.0;
    // Steps beyond those checked yet keep their radii.
    const double scale50 = radius50_scale(s, phase, preparing),
                 scale90 = radius90_scale(s, phase, preparing);
    for (RobotPrediction& robot : step.robots) {
      stated *= formation_factor(robot, robot.probability);
      robot.probability = adjusted(s, robot.probability);
      robots *= formation_factor(robot, robot.probability);
      robot.radius50_mm *= scale50;
      robot.radius90_mm *= scale90;
    }
    const double formation = adjusted_formation(s, stated, robots);
    step.formation_probability = formation;
    confidence *= formation;
    step.confidence = confidence;
  }
}

}  // namespace motion_model
}  // namespace ssl_formation
