#pragma once
// Keeps the motion model's stated cell probabilities honest while the play changes. The table's
// calibration (MotionModel) was fitted on held-out seconds of the play it learned from, and a
// match departs from that for stretches at a time: in a long stoppage every robot stands, and a
// probability fitted on running play says 0.3 where the robot is sure to stay in its cell. So
// every prediction is checked when its instant comes (the robot's cell then), and each stated
// probability is moved towards the hit rate lately seen for probabilities like it (per step and
// tenth of probability), by a weight that grows with that evidence. Only what has already
// happened is used: the correction at time t comes from predictions whose instant is before t.

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "ssl_formation/formation.hpp"
#include "ssl_formation/predictor.hpp"

namespace ssl_formation {

struct OnlineCalibrationSettings {
  // How fast old evidence fades, in seconds of the data clock. On the inner splits (the first
  // two thirds of each recording, clean and reshaped as real logs with their mess), 60 s and
  // 120 s kept the 2 s ECE at or below 0.041 everywhere; 20 s let it reach 0.045.
  double half_life_s = 60.0;
  // The (faded) number of checked robot predictions at which a bin's observed rate weighs as
  // much as the table's calibration.
  double prior_weight = 200.0;
  // How long after its instant a prediction may still be checked (a robot may be missing from
  // the frame that reaches it; a later one within this may see it).
  double tolerance_s = 0.05;
  bool valid() const { return half_life_s > 0.0 && prior_weight >= 0.0 && tolerance_s >= 0.0; }
};

class OnlineCalibration {
 public:
  static constexpr int bin_count = 10;
  // Stated probabilities are kept within these bounds: a robot is never certain to be in or out
  // of a cell, and a formation's probability is their product.
  static constexpr double min_probability = 0.001;
  static constexpr double max_probability = 0.999;

  explicit OnlineCalibration(OnlineCalibrationSettings settings = {});

  // Checks every remembered prediction whose instant has come against `formation` (the cell of
  // each robot seen in it) and forgets those whose instant passed without the robot seen. Call
  // with every formation in time order; a clock going back starts over.
  void observe(const Formation& formation);
  // Remembers the robot probabilities of `prediction`, made at `time_s` with `step_s` between
  // its steps from a formation normalised towards `attacks`, as stated before adjust().
  void remember(const Prediction& prediction, double time_s, double step_s,
                AttackDirection attacks);
  // Moves every robot probability of `prediction` towards its bin's recent hit rate, and the
  // steps' formation probabilities and confidences with them.
  void adjust(Prediction& prediction) const;
  void clear();

  // What has been checked so far (since the last clear), for status lines and tests.
  std::uint64_t checked() const { return checked_; }
  std::size_t pending() const;
  // The probability a bin would move `stated` to at step `step` (0-based); `stated` itself
  // before any evidence.
  double adjusted(std::size_t step, double stated) const;

 private:
  struct Pending {
    double due_s = 0.0;
    std::uint32_t robot_id = 0;
    Cell cell;
    double probability = 0.0;
    AttackDirection attacks = AttackDirection::positive_x;
  };
  // Faded sums over the checked predictions of one bin.
  struct Bin {
    double weight = 0.0;
    double hits = 0.0;
    double stated = 0.0;
  };
  struct Step {
    std::deque<Pending> pending;  // in due order: predictions come in time order
    std::array<Bin, bin_count> bins{};
  };
  static std::size_t bin_of(double probability);

  OnlineCalibrationSettings settings_;
  std::vector<Step> steps_;
  std::optional<double> last_time_s_;
  std::uint64_t checked_ = 0;
};

}  // namespace ssl_formation
