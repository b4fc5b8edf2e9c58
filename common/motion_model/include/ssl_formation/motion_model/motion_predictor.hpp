#pragma once
// Prediction with the motion model (motion_model.hpp): a MotionTable turned into shrunk
// estimates at every back-off level and a calibration fitted on the table's held-out sample,
// then, for each robot and step, a position in mm, the radii holding it with 50% and 90%
// probability and the calibrated probability that its predicted cell is right.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/base/probed_memory.hpp"
#include "ssl_formation/base/state.hpp"
#include "ssl_formation/motion_model/motion_estimates.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace motion_model {

// What the rules of the game say of where the opponent's robots can go under the referee's
// current command, normalised (the opponent attacks +x). The forecast is moved the least
// distance that satisfies them; MotionRules{} says nothing.
struct MotionRules {
  // STOP: "all robots have to slow down to less than 1.5 m/s" (SSL rules, Referee Commands:
  // Stop): no robot's average speed to a predicted position is above this.
  double max_speed_mm_s = std::numeric_limits<double>::infinity();
  // STOP, the defending team at a free kick or a kick-off: "at least 0.5 meters distance to the
  // ball" (Stop; Direct Free Kick; Kick-Off's centre circle).
  std::optional<Point> keep_away_from;
  // With it, the whole segment from keep_away_from to here: "all robots of the non-placing team
  // have to keep at least 0.5 meters distance to the line between the ball and the placement
  // position" (Fouls: Ball Placement Interference).
  std::optional<Point> keep_away_to;
  double keep_away_mm = 500.0;
  // The robot the rules leave out: the placing robot, or the kicker at the team's own kick-off.
  std::optional<std::uint32_t> exempt_robot_id;
  // A kick-off: "all robots have to move to their own half of the field" (Kick-Off): a robot in
  // its half (x <= 0) stays there. One still on its way back is left to the model: the rule
  // says where it ends, not where it is half a second on.
  bool own_half = false;
  bool any() const {
    return max_speed_mm_s < std::numeric_limits<double>::infinity() || keep_away_from || own_half;
  }
  // Where a robot at `from` may be `horizon_s` later, nearest to `to`.
  Point apply(std::uint32_t robot_id, Point from, double horizon_s, Point to) const;
};

// One robot as the motion model sees it: normalised position and velocity (mm/s).
struct MotionRobot {
  std::uint32_t robot_id = 0;
  Point position;
  MotionKinematics kinematics;  // valid if has_velocity; otherwise the robot counts as standing
  bool has_velocity = false;
  std::uint32_t context = 0;  // MotionHistory::Entry::context
};

// Where one robot will be `horizon_index + 1` steps ahead, normalised.
struct MotionForecast {
  Point position;
  double mean_square_mm2 = 0.0;  // the expected squared distance to the truth
  double radius50_mm = 0.0;
  double radius90_mm = 0.0;
  MotionLevel level = MotionLevel::all;  // the finest level with counts
  bool from_counts = false;              // false: the empty table's prior
  bool stays = false;                    // a standing robot, forecast where it stands
};

class MotionModel {
  // One robot's estimate at one horizon, found by its keys (88 bytes with five regressors: not
  // aligned to a line, so a robot's horizons lie back to back). No initialisers: predict() keeps
  // a scratch array of them per robot.
  struct Resolved {
    double mean_x, mean_y;  // residual against damped constant velocity, mm
    double mean_square;
    std::array<double, motion_regressors> coefficients;
    // The radii over sqrt(mean square) of the robot's game phase (Horizon::z50, z90), found
    // with the rest rather than at every frame.
    double z50, z90;
    MotionLevel level;
    // The regressor that leads to a standing robot's place (place_regressor), -1 if it has not
    // stood a settle window: forecast() puts a robot that stays there if it is within the
    // vision's noise.
    std::int8_t place_regressor;
    bool halted;  // HALT or a timeout: a robot that has stood a settle window stays
  };

 public:
  // The estimates predict() found for each robot slot at its last frame, by the robot's finest
  // key. A real robot keeps its keys (cell, velocity class, standing context) for many frames in
  // a row, so a frame mostly reads these few contiguous lines instead of probing the index: the
  // daemon sleeps 16 ms between frames, and after that every line it touches is a cache miss and
  // every page a TLB miss. (The simulated opponent of the end-to-end benchmark jumps to a new
  // formation every frame: there it misses every time.) The caller owns it, so predict() stays
  // const; it holds copies of the model's estimates, so predictions are the same without it.
  class Cache {
   public:
    void clear();

   private:
    friend class MotionModel;
    std::uint64_t model_id_ = 0;  // the model the entries are from; 0: none
    std::size_t horizons_ = 0;    // resolved per robot: those predict() reaches
    std::array<MotionKey, MotionFeatures::robot_slots> keys_{};  // per slot, at horizon 0
    std::vector<Resolved> estimates_;                            // slot-major, `horizons_` each
  };

  // `grid` and `field` are those the cell probabilities are calibrated for. Under a
  // `prior_model` (every team's table, MotionForecaster's --prior-table), each of the table's
  // rows is held towards the prior's estimate of the same row, the rows the table lacks are the
  // prior's, and a table with too little held out takes the prior's calibration: a new opponent
  // is predicted like every team, and its own rows take over as they fill. Throws
  // std::invalid_argument for a prior of other settings.
  MotionModel(const MotionTable& table, const Grid& grid, const FieldSize& field,
              MotionModelSettings settings = {}, const MotionModel* prior_model = nullptr);

  const MotionConfig& config() const { return config_; }
  int horizons() const { return config_.horizons; }

  MotionForecast forecast(int horizon_index, const MotionRobot& robot) const;
  // The same with the robot's keys at horizon 0, finest first (motion_keys), computed once for
  // every horizon: the hot path of predict().
  using RobotKeys = std::array<MotionKey, motion_levels>;
  static RobotKeys motion_keys(const MotionRobot& robot);
  MotionForecast forecast(int horizon_index, const MotionRobot& robot, const RobotKeys& keys) const;
  // The calibrated probability that the robot is in `cell` when it is forecast `forecast`.
  double cell_probability(int horizon_index, const MotionForecast& forecast, const Grid& grid,
                          const FieldSize& field, Cell cell) const;
  // The uncalibrated Gaussian mass of the cell (what the calibration maps).
  static double gaussian_cell_mass(const MotionForecast& forecast, const Grid& grid,
                                   const FieldSize& field, Cell cell);

  // Predicts `horizon` steps for every robot into `out` (reusing its storage), the states in
  // `codec`'s cells; positions are turned back into the feed's coordinates with `attacks`.
  // Steps beyond the table's horizons extrapolate the last two learned steps.
  // Every predicted position satisfies `rules`.
  void predict(const std::vector<MotionRobot>& robots, int horizon, const StateCodec& codec,
               const FieldSize& field, AttackDirection attacks, Prediction& out,
               const MotionRules& rules = {}) const;
  // The same, looking the robots' estimates up through `cache` (see Cache). With `advice` (for
  // the same robots: SetPlayMemory::recall, advise_ball_placement), each forecast is
  // moved towards where the set play takes the robot, by the advice's weight, before the rules.
  // Steps beyond the table's horizons extrapolate the forecasts before advice and rules.
  void predict(const std::vector<MotionRobot>& robots, int horizon, const StateCodec& codec,
               const FieldSize& field, AttackDirection attacks, Prediction& out, Cache& cache,
               const MotionRules& rules = {}, const SetPlayAdvice* advice = nullptr) const;

 private:
  // A slot is the key and the estimate rounded to floats, 40 bytes. Padded to a cache line, a
  // probe read one line where an unpadded slot sometimes straddles two, but the index took 60%
  // more memory (five sections of a season's holdout: 20 MB more), and the rolling prediction
  // benchmark did not tell the two apart (12x9, 3 steps: medians 4.74 and 4.75 us, 2026-12-07).
  struct Slot {
    MotionKey key;
    float mean_x, mean_y, mean_square;
    std::array<float, motion_regressors> coefficients;
  };
  using Estimate = MotionEstimate;
  // A non-decreasing step function from the Gaussian mass of the predicted cell to the hit
  // rate observed at such masses: block upper bounds and their rates. Empty: identity.
  struct IsotonicMap {
    std::vector<double> mass_upper;
    std::vector<double> hit_rate;
    bool empty() const { return mass_upper.empty(); }
    double operator()(double mass) const;
    // Pool-adjacent-violators over (mass, hit) pairs, sorted here.
    static IsotonicMap fit(std::vector<std::pair<double, bool>> masses);
  };
  // The horizon's prior (damping, root, the rules' still prior), then what the held-out sample
  // calibrates.
  struct Horizon : MotionHorizonPrior {
    // Per game phase (GamePhase's order), how much of its rows' mean displacement the forecasts
    // keep: none for the phases whose mean is another match's (mean_holds), else fitted on the
    // held-out sample (weigh_means), one before.
    std::array<double, all_game_phases.size()> mean_weight = initial_mean_weights();
    static std::array<double, all_game_phases.size()> initial_mean_weights() {
      std::array<double, all_game_phases.size()> weights{};
      for (std::size_t p = 0; p < weights.size(); ++p) {
        weights[p] = motion_mean_holds(all_game_phases[p]) ? 1.0 : 0.0;
      }
      return weights;
    }
    // Radius / sqrt(mean square), per game phase (GamePhase's order): the horizon's, or wider
    // for a phase whose held-out play strayed further (calibrate).
    std::array<double, all_game_phases.size()> z50{}, z90{};
    // The cell probabilities' calibration, one map for the robots forecast to stay and one for
    // the others (indexed by MotionForecast::stays). A standing robot's spread is its rows',
    // which count the few that set off, and most stay in their cell whatever its Gaussian mass
    // says: with one map for both the formation's probability (the product over the team)
    // missed by an ECE of up to 0.065 on the tuning seeds, with two by up to 0.054.
    std::array<IsotonicMap, 2> cell_calibration;
  };
  std::optional<Estimate> estimate(MotionKey key) const;  // as indexed (floats), none if absent
  const Slot* find(MotionKey key) const;
  // The finest estimate with counts among the robot's keys, else the horizon's root.
  Resolved resolve(int horizon_index, const RobotKeys& keys) const;
  // The regressor (motion_regressors_of) from a robot of `context` to its place: towards its mean
  // position over the settle window (2) or the long one (3), the longest it has stood through;
  // -1 if it has not stood a settle window.
  std::int8_t place_regressor(std::uint32_t context) const;
  // Whether the robot stands: forecast where it stands rather than by its rows (stay_speed_mm_s).
  bool stands(const MotionRobot& robot, const Resolved& e, const MotionRegressors& x) const;
  // The way (one of `x`) from a robot that has stood a settle window to its mean sighting over
  // it, if that is within the vision's noise (halt_error_mm); none otherwise.
  const Point* way_to_place(const Resolved& e, const MotionRegressors& x) const;
  // The robot's estimates for the first `horizons` learned horizons, through `cache` if there
  // is one (else in `scratch`).
  const Resolved* resolve_all(const MotionRobot& robot, std::size_t horizons, Cache* cache,
                              std::array<Resolved, MotionConfig::max_horizons>& scratch) const;
  MotionForecast forecast(int horizon_index, const MotionRobot& robot, const Resolved& e) const;
  void predict(const std::vector<MotionRobot>& robots, int horizon, const StateCodec& codec,
               const FieldSize& field, AttackDirection attacks, Prediction& out, Cache* cache,
               const MotionRules& rules, const SetPlayAdvice* advice) const;
  // Every level's estimates into index_, and the prior table's where the table has none.
  void index_estimates(const MotionLevelEstimates& estimates, const MotionModel* prior_model);
  // Sets the horizon's mean weights from the table's held-out sample; false (weights left as
  // they were) when it holds too few instances.
  bool weigh_means(const MotionTable& table, int horizon_index);
  void calibrate(const MotionTable& table, int horizon_index, const Grid& grid,
                 const FieldSize& field);
  double calibrated(int horizon_index, double mass, bool stays) const;

  MotionConfig config_;
  MotionModelSettings settings_;
  std::vector<Horizon> horizon_;
  // Every level's estimates in one open-addressing table (linear probing, power-of-two size):
  // a lookup is one or two cache lines, where a node map costs a pointer chase per probe.
  std::vector<Slot, ProbedAllocator<Slot>> index_;
  std::size_t index_mask_ = 0;
  std::uint64_t id_;  // unique per model built: what a Cache's entries are checked against
  // The standing contexts (MotionFeatures::standing_context) from which a robot has stood the
  // whole settle window, and the whole long one.
  std::uint32_t settled_context_ = MotionFeatures::standing_contexts;
  std::uint32_t long_settled_context_ = MotionFeatures::standing_contexts;
};

}  // namespace motion_model
}  // namespace ssl_formation
