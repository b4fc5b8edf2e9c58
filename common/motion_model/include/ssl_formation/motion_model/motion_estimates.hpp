#pragma once
// Every back-off level's estimate of a motion table: the stored rows added up their keys'
// coarser levels, and each level's sums shrunk towards its parent's estimate (the `all` level
// towards the horizon's prior). MotionModel predicts from these; the pruning
// (motion_table_pruning.hpp) judges by them which rows say something their parent does not.
//
// A table stores rows at any level: a robot's own row, or at a coarser key what was folded into
// it (rows that added nothing over that key). A key's sums are its stored row and every stored
// row beneath it, so folding a row into its parent changes no coarser sum.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace motion_model {

struct MotionModelSettings {
  // How many instances a row needs to weigh as much as its coarser row. Frames 16 ms apart
  // are far from independent, so this is a few seconds of one robot's frames.
  double shrinkage = 60.0;
  // The damping of constant velocity before any data, as robots that brake with this time
  // constant (s): k(h) = tau / h x (1 - exp(-h / tau)).
  double prior_time_constant_s = 0.7;
  // The spread before any data: sqrt(mean squared error) = base + per_second x horizon.
  double prior_error_mm = 100.0;
  double prior_error_mm_per_s = 450.0;
  // Fewer held-out instances than this: Gaussian radii and uncalibrated probabilities.
  std::size_t min_calibration_instances = 100;
  // A game phase with at least this many held-out instances has radii of its own: at a
  // kick-off the robots run where the rows of their state learned little.
  std::size_t min_phase_calibration_instances = 50;
  // The rules' prior in HALT and timeouts (rows of those states shrink towards it): robots
  // brake with this time constant and then stand, give or take the vision's noise. A robot whose
  // mean sighting is within that noise stands (MotionModel forecasts it there).
  double halt_brake_time_constant_s = 0.15;
  double halt_error_mm = 20.0;
  // A standing robot is forecast where it stands, in every state (MotionModel::stands): slower
  // than `stay_speed_mm_s` by its tracker, or slower than the standing speed (the first of
  // MotionFeatures::speed_limits_mm_s) with its mean sighting over the settle window within
  // `stay_spread_mm` of its last (3 mm of vision noise puts 95% of a standing robot's last
  // sightings within 7.3 mm of that mean, and shakes its tracked velocity well past 100 mm/s).
  double stay_speed_mm_s = 100.0;
  double stay_spread_mm = 8.0;
  // How many held-out instances of a game phase weigh as much as keeping its rows' mean
  // displacement whole (MotionModel's mean weights).
  double mean_weight_shrinkage = 20.0;
  // An ablation (ssl-evaluate's "pooled model"): every robot, in every state, takes what a robot
  // with no row at all would: the horizon's one fit of the regressors over all the table's
  // instances (in HALT the rules' prior), its mean weighed per phase as the model does. The
  // rules, the standing robots' places and the set plays are the model's, and its calibration
  // is fitted the same way, on its own forecasts. What the model wins over it is what its keyed
  // rows (robot, cell, velocity class, contexts) add.
  bool pooled = false;
};

// A row's forecast of a displacement: d = mean + sum of coefficients_i x regressor_i, with the
// expected squared distance of the truth from it.
struct MotionEstimate {
  double mean_x = 0.0, mean_y = 0.0;  // residual against damped constant velocity, mm
  double mean_square = 0.0;           // of the truth about the estimate, mm^2
  double n = 0.0;
  // Of the regressors (motion_regressors_of): e's is the damping of constant velocity.
  std::array<double, motion_regressors> coefficients{1.0};
};

// The least-squares fit of a row's sums, each coefficient held towards the parent's by
// `shrinkage` instances of a 500 mm regressor and the mean towards what the parent predicts at
// the row's mean regressors by `shrinkage` instances (ridge towards the parent).
MotionEstimate shrink_motion_row(const MotionRow& row, const MotionEstimate& parent,
                                 double shrinkage);

// Whether the rows of a game phase fit the team's mean velocity (regressor t); the others'
// are fitted without it, and so their parents, down to the horizon's root.
bool motion_team_velocity_holds(GamePhase phase);
// Whether the forecasts of a game phase keep their rows' mean displacement (MotionModel weighs
// it per phase on the held-out sample; the others keep none of it).
bool motion_mean_holds(GamePhase phase);
// The finest level whose rows the forecasts of a robot of `context` read: in HALT and timeouts
// the velocity level (every robot stands wherever it is; what a robot's or a zone's few halts
// say beyond that is where that match's play resumed), else the robot's own row.
MotionLevel motion_finest_level_read(std::uint32_t context);

// What a horizon's rows back off to when even the `all` level has no counts.
struct MotionHorizonPrior {
  double damping = 1.0;
  MotionEstimate root;   // every game context's rows pooled
  MotionEstimate still;  // the rules' prior in HALT and timeouts
  // The root without the team's velocity, for the phases whose rows leave it out.
  MotionEstimate root_without_team_velocity;
  // What a row at the `all` level (or a robot with no row at all) is held towards.
  const MotionEstimate& prior_of(std::uint32_t context) const;
};

// The horizon's prior from the sum of all its rows (`root`); under a prior table, the root is
// held towards that table's root (`generic_root`) rather than towards damped constant velocity.
MotionHorizonPrior motion_horizon_prior(const MotionConfig& config,
                                        const MotionModelSettings& settings, int horizon_index,
                                        const MotionRow& root,
                                        const MotionEstimate* generic_root = nullptr);

// Every key's sums and estimate, at every level, and each horizon's prior. A robot's key has no
// finer key beneath it, so its sums are its stored row: they are read from the table rather than
// copied (most keys are robots', and a season's table is tens of megabytes). `table` must outlive
// the estimates.
class MotionLevelEstimates {
 public:
  // The prior table's estimate of a key, if it has one (MotionModel's --prior-table): a row is
  // held towards it instead of towards its own parent, so a new opponent's rows give way to
  // its own as they fill.
  using GenericEstimate = std::function<std::optional<MotionEstimate>(MotionKey)>;

  MotionLevelEstimates(const MotionTable& table, const MotionModelSettings& settings,
                       const std::vector<MotionEstimate>* generic_roots = nullptr,
                       const GenericEstimate& generic = nullptr);

  const MotionHorizonPrior& horizon(int horizon_index) const {
    return horizons_[static_cast<std::size_t>(horizon_index)];
  }
  std::size_t size() const { return keys_.size(); }
  // The keys, their sums and estimates, numbered 0 to size() - 1: the coarser keys first, then
  // the robots'.
  MotionKey key(std::size_t i) const { return keys_[i]; }
  const MotionRow& sums(std::size_t i) const {
    return i < coarse_.size() ? coarse_.row(static_cast<std::uint32_t>(i))
                              : rows_.row(robot_rows_[i - coarse_.size()]);
  }
  const MotionEstimate& estimate(std::size_t i) const { return estimates_[i]; }
  // The number of `key`, MotionRowMap::no_row if it has no counts at any level.
  std::uint32_t number(MotionKey key) const;

 private:
  const MotionRowMap& rows_;  // the table's
  MotionRowMap coarse_;       // the sums of every key above the robots'
  // Each robot key's row in rows_, in the order of its number past the coarser keys, and back.
  std::vector<std::uint32_t> robot_rows_;
  std::vector<std::uint32_t> robot_number_of_row_;  // no_row for a row above the robots'
  std::vector<MotionKey> keys_;
  std::vector<MotionEstimate> estimates_;
  std::vector<MotionHorizonPrior> horizons_;
};

// The log-likelihood (nats) of a row's instances under an estimate, taken as an isotropic
// Gaussian of its mean square about its forecast, up to a constant per instance: how well the
// estimate fits the instances the row summed. `mean_weight` scales the estimate's mean as the
// forecasts do in the row's game phase.
double motion_log_likelihood(const MotionRow& row, const MotionEstimate& estimate,
                             double mean_weight);

}  // namespace motion_model
}  // namespace ssl_formation
