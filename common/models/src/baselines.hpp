#pragma once
// The baselines SSL teams use today to guess where the opponent goes, each from the robot's own
// tracker (vision/robot_tracker.hpp, as the motion model's): persistence, constant velocity and
// constant acceleration, and the last two damped by factors per step fitted by least squares on
// the training part. Made by the factory only.

#include <deque>
#include <memory>
#include <vector>

#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/vision/robot_tracker.hpp"

namespace ssl_formation {
inline namespace models {

// Each robot's tracker over the samples, in normalised coordinates, and what it said at each
// sample of the last `keep_s` seconds. A track starts again where the robot jumped (a ghost or a
// swapped id is no velocity: MotionFeatures::is_jump), after RobotTracker::forget_after_s
// unseen, where time went back, or when the opponent changed ends.
class BaselineTracks {
 public:
  BaselineTracks(double velocity_window_s, double keep_s);

  struct Seen {
    double time_s = 0.0;
    Point position;  // normalised
    // Once the robot's track had gone on for half the velocity window, its tracker's velocity
    // (mm/s) and acceleration (mm/s^2) then.
    bool has_kinematics = false;
    Point velocity;
    Point acceleration;
  };

  void add(const Formation& formation);
  void clear();
  // The robot's record at the last formation added; none if it was not in it.
  const Seen* latest(std::uint32_t robot_id) const;
  // The robot's kept record nearest `time_s`, within `tolerance_s`.
  const Seen* nearest(std::uint32_t robot_id, double time_s, double tolerance_s) const;

 private:
  struct Track {
    RobotTracker tracker;
    Point last_observed;
    std::deque<Seen> seen;
    double latest_s = -1.0;  // the time of the newest record
  };
  double velocity_window_s_;
  double keep_s_;
  std::vector<Track> tracks_;  // by robot id
  std::optional<double> last_time_s_;
  AttackDirection attacks_ = AttackDirection::positive_x;
};

// How a baseline extrapolates one step of `horizon_s` from a robot's position, velocity and
// acceleration, with its factors for that step.
enum class Extrapolation { stay, velocity, acceleration };
struct StepFactors {
  double velocity = 1.0;
  double acceleration = 1.0;
};

class BaselineForecaster : public Forecaster {
 public:
  BaselineForecaster(Extrapolation extrapolation, const ModelSettings& settings,
                     std::vector<StepFactors> factors = {});
  PreparedTable install_table(PreparedTable) noexcept override { return {}; }  // needs none
  bool ready() const override { return true; }
  void observe(const MatchMoment& moment) override { tracks_.add(moment.formation()); }
  void forecast(const MatchMoment& moment, int steps, Prediction& out, ForecastUse use) override;
  void forget_match() override { tracks_.clear(); }

 private:
  StepFactors factors(int step) const;

  Extrapolation extrapolation_;
  ModelSettings settings_;
  std::vector<StepFactors> factors_;  // per step; beyond them the last, or 1 before any
  BaselineTracks tracks_;
};

// What the baselines learn: nothing (persistence, constant velocity and acceleration), or their
// factors per step (the damped ones), by least squares over every robot and instant learned
// from: the factors minimising the squared distance to where the robots really were.
class BaselineLearner : public Learner {
 public:
  BaselineLearner(ModelKind kind, Extrapolation extrapolation, bool damped,
                  const ModelSettings& settings);
  void observe(const MatchMoment& moment) override { tracks_.add(moment.formation()); }
  void learn(const MatchMoment& moment) override;
  void forget_match() override { tracks_.clear(); }
  void absorb(const Learner& other) override;
  std::uint64_t progress() const override { return fitted_; }
  std::unique_ptr<Forecaster> forecaster(const TableMetadata& metadata) const override;

  // The fitted factors per step (1 while nothing moved).
  std::vector<StepFactors> factors() const;

 private:
  // The sums of the normal equations of one step: displacement d, velocity term v = velocity x h
  // and acceleration term a = acceleration x h^2 / 2.
  struct Sums {
    double vv = 0.0, va = 0.0, aa = 0.0, dv = 0.0, da = 0.0;
  };

  ModelKind kind_;
  Extrapolation extrapolation_;
  bool damped_;
  ModelSettings settings_;
  BaselineTracks tracks_;
  std::vector<Sums> sums_;  // per step
  std::uint64_t fitted_ = 0;
};

}  // namespace models
}  // namespace ssl_formation
