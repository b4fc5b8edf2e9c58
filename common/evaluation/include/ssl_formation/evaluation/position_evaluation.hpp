#pragma once
// Predictions judged as the field judges them: the distance in millimetres between where a
// method said a robot would be `horizon_s` seconds later and where it was, against the robot's
// own observed positions, and the calibration of every probability stated. Pure: formations,
// predictions and numbers in, numbers out.
//
// The baselines SSL teams use today, computed from each robot's own observed positions at the
// same instants:
//   persistence                 it stays where it is;
//   constant velocity           it goes on at its velocity now, from its RobotTracker (as the
//                               model's), once its track has run for half `velocity_window_s`;
//   damped constant velocity    the same velocity scaled by one factor per horizon, fitted on
//                               the training part by least squares (DampingFit).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "ssl_formation/evaluation/evaluation.hpp"
#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/paper_model/predictor.hpp"
#include "ssl_formation/vision/robot_tracker.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/files/table_file.hpp"

class SSL_WrapperPacket;

namespace ssl_formation::evaluation {

// Where each robot was seen in one stream, on the data clock, in the feed's coordinates: every
// sampled formation's robots by id, and each robot's velocity from a RobotTracker fed with its
// observed positions (the model's own tracker: the baselines extrapolate what a team's tracker
// would). Formations must come in time order.
class RobotTracks {
 public:
  void add(const Formation& formation);
  // The position recorded nearest to `time_s`, if one lies within `tolerance_s` of it; with the
  // time it was recorded at and the tracker's velocity then.
  struct Seen {
    double time_s = 0.0;
    Point position;
    Point velocity;               // valid if tracked_since_s is set
    std::optional<double> tracked_since_s;  // when the robot's current track started
  };
  std::optional<Seen> nearest(std::uint32_t robot_id, double time_s, double tolerance_s) const;
  // The robot's velocity at `time_s` (mm/s): its tracker's at the record nearest `time_s`
  // (within `tolerance_s`), once that track had gone on for half of `window_s`, as the model's
  // (MotionHistory). A track starts again where the robot jumped (MotionFeatures::is_jump: a
  // ghost or a swapped id is no velocity, for the baselines as for the model), after
  // RobotTracker::forget_after_s unseen, or where time went back.
  std::optional<Point> velocity(std::uint32_t robot_id, double time_s, double window_s,
                                double tolerance_s) const;

 private:
  std::vector<std::vector<Seen>> by_id_;  // indexed by robot id, each in time order
  struct Followed {
    RobotTracker tracker;
    Point last_position;  // observed, for the jump check
  };
  std::vector<Followed> followed_;  // indexed by robot id
};

// Errors in millimetres: mean, median and 90th percentile (linear interpolation between order
// statistics, as numpy's default).
class ErrorStats {
 public:
  void add(double error_mm) { errors_.push_back(error_mm); }
  std::size_t count() const { return errors_.size(); }
  double mean() const;
  double percentile(double p) const;  // p in [0, 100]; 0 without errors
  double median() const { return percentile(50.0); }

 private:
  mutable std::vector<double> errors_;
  mutable bool sorted_ = true;
};

// The least-squares damping factor k of `position + k * velocity * horizon`: the k minimising
// the squared distance to where the robots really were, over the training part.
class DampingFit {
 public:
  // `displacement`: where the robot went minus where it was; `extrapolated`: velocity x horizon.
  void add(Point displacement, Point extrapolated);
  // 1 (plain constant velocity) when nothing moved in training.
  double factor() const;

 private:
  double dot_ = 0.0;
  double norm_ = 0.0;
};

enum class PositionMethod { model, persistence, constant_velocity, damped_constant_velocity };
inline constexpr std::array<PositionMethod, 4> all_position_methods{
    PositionMethod::model, PositionMethod::persistence, PositionMethod::constant_velocity,
    PositionMethod::damped_constant_velocity};
std::string_view to_string(PositionMethod method);

// How often the truth fell within the model's stated radii.
struct RadiusCoverage {
  std::uint64_t robots = 0;  // scored robots with radii stated
  std::uint64_t within50 = 0;
  std::uint64_t within90 = 0;
  double share50() const { return robots ? double(within50) / double(robots) : 0.0; }
  double share90() const { return robots ? double(within90) / double(robots) : 0.0; }
};

// Every method's score at one horizon in seconds.
struct HorizonScore {
  double horizon_s = 0.0;
  std::array<ErrorStats, 4> error;  // by PositionMethod
  std::array<Accuracy, 4> cells;    // predicted state, cell and cell distance against the truth
  Calibration robot;                // the model's per-robot probability that its cell is right
  Calibration formation;            // the model's formation probability that every cell is right
  RadiusCoverage radii;             // the model's 50% and 90% radii
};

// How to read positions: the grid and field the formations were sampled with (each formation
// carries its own attack direction).
struct PositionSetup {
  const StateCodec* codec = nullptr;
  FieldSize field;
  double velocity_window_s = 0.1;
  double tolerance_s = 0.05;  // how far from an instant a position may be recorded to stand for it
};

// Scores one test instant: `now` (sampled at t), the model's step predicting t + horizon_s, and
// `truth`, the formation sampled nearest t + horizon_s. Each robot of `now` that `truth` holds is
// scored, every method on the same robots: its position error against the truth's position, its
// predicted cell and state against the truth's. A baseline's predicted state is (the cell of the
// mean of its predicted positions, the cell of its predicted position, the robot's cell now).
// Velocities come from `tracks` (the stream's recorded positions).
void score_instant(HorizonScore& score, const PositionSetup& setup, const RobotTracks& tracks,
                   const Formation& now, const PredictedStep& model, const Formation& truth,
                   double damping);

// The formation of `formations` (in time order) sampled nearest `time_s`, within `tolerance_s`.
const Formation* formation_near(const std::vector<Formation>& formations, double time_s,
                                double tolerance_s);

// Adds one stream of the training part to `fit`: for every formation and robot with a velocity,
// the displacement to the robot's position in the formation nearest horizon_s later.
void fit_damping(DampingFit& fit, const PositionSetup& setup, const RobotTracks& tracks,
                 const std::vector<Formation>& formations, double horizon_s);

// ---- The held-out evaluation in millimetres --------------------------------------------------

struct PositionEvaluationConfig {
  SamplerConfig sampler;  // the model's step, grid and sampling, for training and testing alike
  ModelKind model = ModelKind::paper;
  int steps = 1;          // horizons 1..steps, step k being k x step_s ahead
  double velocity_window_s = 0.1;
  // How far from t + horizon the truth may be sampled (and from t the velocity's record).
  double tolerance_s = 0.05;
  // The motion model's recalibration while it predicts the test streams (PredictionConfig).
  std::optional<OnlineCalibrationSettings> recalibration = OnlineCalibrationSettings{};
};

struct PositionEvaluation {
  std::vector<HorizonScore> horizons;  // [k - 1]
  std::vector<double> damping;         // the damped baseline's factor per horizon, from training
  std::uint64_t train_formations = 0;
  std::uint64_t transitions = 0;
  std::size_t table_memory_bytes = 0;
  std::uint64_t test_formations = 0;
  std::shared_ptr<const StoredTable> table;  // what the model was trained to
};

// Trains the model on the training streams (each its own stream: nothing spans two), fits the
// damping on them, then predicts every formation of the test streams through the
// PredictionPipeline and scores every method at every horizon on the same robots.
PositionEvaluation evaluate_positions(const PositionEvaluationConfig& config,
                                      const std::vector<std::vector<SSL_WrapperPacket>>& train,
                                      const std::vector<std::vector<SSL_WrapperPacket>>& test);

// Expected calibration error over the 10 equal-width bins: sum over bins of
// (bin count / n) x |observed frequency - mean confidence|.
double expected_calibration_error(const Calibration& calibration);

}  // namespace ssl_formation::evaluation
