#pragma once
// Keeps the motion model's stated cell probabilities honest while the play changes. The table's
// calibration (MotionModel) was fitted on held-out seconds of the play it learned from, and a
// match departs from that for stretches at a time: in a long stoppage every robot stands, and a
// probability fitted on running play says 0.3 where the robot is sure to stay in its cell. So
// every prediction is checked when its instant comes (the robot's cell then), and each stated
// probability is moved towards the hit rate lately seen for probabilities like it (per step and
// tenth of probability), by a weight that grows with that evidence. Only what has already
// happened is used: the correction at time t comes from predictions whose instant is before t.
//
// A formation's probability (that every robot is in its predicted cell) is checked the same way,
// as a whole: the robots of one team move together (a set play, a team falling back), so the
// product of their probabilities says far less than the formations really hit. Each step's
// formation probability is moved towards the hit rate lately seen for formation probabilities
// like it; before a bin has evidence, it is the product of the adjusted robots'.
//
// The radii are kept honest per game phase: the table's were fitted on held-out seconds of the
// same matches, whose halts and set plays resemble the training's more than the next match's
// do (on the simulated match the 90% radius held 96% of the time in HALT and 65% at the
// opponent's kick-offs). Each checked robot adds how far it was off, as a multiple of each
// stated radius, to its step's and phase's histogram, faded by checks of that phase rather than
// by time (a team's kick-offs are minutes apart, and what the last showed holds for the next);
// a radius is scaled by the median (50%) or the 90th percentile (90%) of those multiples, held
// towards 1 by the same prior weight as the probabilities. A running quantile that moved the
// scale a small step per check was tried first: in the long halts of a real log, where the
// robots stand within a millimetre and the table's radii are tens of millimetres, it was still
// moving after the halt's end (the 50% radius held 96% of the robots).

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/interval_gate.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/match/game_phase.hpp"

namespace ssl_formation {
inline namespace motion_model {

struct OnlineCalibrationSettings {
  // How fast old evidence fades, in seconds of the data clock. On the inner splits (the first
  // two thirds of each recording, clean and reshaped as real logs with their mess), 60 s and
  // 120 s kept the 2 s ECE at or below 0.041 everywhere; 20 s let it reach 0.045.
  double half_life_s = 60.0;
  // The (faded) number of checked robot predictions at which a bin's observed rate weighs as
  // much as the table's calibration. On the same inner splits 30 and 200 did about as well (2 s
  // ECE at most 0.039 and 0.042); 30 is what 200 was when every frame was checked.
  double prior_weight = 30.0;
  // Predictions are remembered (to be checked) at most this often, in seconds of the data clock:
  // frames 16 ms apart say almost the same thing, and checking every one of them cost a daemon
  // a tenth of its prediction time.
  double remember_interval_s = 0.1;
  // How long after its instant a prediction may still be checked (a robot may be missing from
  // the frame that reaches it; a later one within this may see it).
  double tolerance_s = 0.05;
  // The radii's evidence in a game phase halves in weight with every this many checks of that
  // phase: a team of 11 checked 10 times a second gives it in 27 s of play. On the tuning splits
  // (the simulated match of seeds 11/12, clean and with 3 mm of noise; A's first two thirds as a
  // real log) 300, 1,000 and 3,000 held the 90% radius within 85-95% in every phase but our
  // kick-offs (83-85%) and, at 300 and 1,000, the real log's halts (95-97%).
  double radius_half_count = 3000.0;
  // Every value finite, the half-life positive, the half count at least 1 and the others not
  // negative.
  bool valid() const;
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
  // its steps from a formation normalised towards `attacks`, as stated before adjust(); unless
  // one was remembered less than the remember interval before.
  // `phase` is the game's when it was made: its robots' radii are checked as that phase's (the
  // opponent's kick-off: its preparation, `preparing`, apart from after the kick).
  void remember(const Prediction& prediction, double time_s, double step_s, AttackDirection attacks,
                GamePhase phase = GamePhase::running, bool preparing = false);
  // Moves every robot probability of `prediction` towards its bin's recent hit rate, and the
  // steps' formation probabilities and confidences with them; scales its radii by what `phase`
  // (the game's now) lately showed.
  void adjust(Prediction& prediction, GamePhase phase = GamePhase::running,
              bool preparing = false) const;
  // Forgets everything. A new table does not call for it: the live trainer replaces the table
  // every few seconds and it changes little each time, while the evidence of the last minute
  // stays true of the play; a table of another opponent is outweighed within a minute or two.
  void clear();

  // What has been checked so far (since the last clear), for status lines and tests.
  std::uint64_t checked() const { return checked_; }
  std::size_t pending() const;
  // The probability a bin would move `stated` to at step `step` (0-based); `stated` itself
  // before any evidence.
  double adjusted(std::size_t step, double stated) const;
  // The same for a formation probability stated as `stated` (the product of its robots' as
  // stated); `fallback` before its bin has evidence.
  double adjusted_formation(std::size_t step, double stated, double fallback) const;
  // Formations checked so far (since the last clear).
  std::uint64_t formations_checked() const { return formations_checked_; }
  // The factors adjust() scales the 50% and 90% radii of step `step` (0-based) by in `phase`: 1
  // before any check.
  double radius50_scale(std::size_t step, GamePhase phase, bool preparing = false) const;
  double radius90_scale(std::size_t step, GamePhase phase, bool preparing = false) const;

 private:
  struct Pending {
    double due_s = 0.0;
    std::uint64_t formation = 0;  // the sequence number of its formation's check (FormationCheck)
    std::uint32_t robot_id = 0;
    float probability = 0.0f;  // as stated, for the bin's sum (its bin is kept exactly apart)
    std::int16_t cell_x = 0, cell_y = 0;  // grids have at most a few hundred cells
    std::uint8_t bin = 0;                 // bin_of the stated probability, as a double
    AttackDirection attacks = AttackDirection::positive_x;
    std::uint8_t group = 0;                  // radius_group of the phase it was made in
    float x = 0.0f, y = 0.0f;                // the predicted position, normalised (mm)
    float radius50 = 0.0f, radius90 = 0.0f;  // as stated; 0: none to check
  };
  // The radii's evidence is kept per game phase, and apart for the preparation of the
  // opponent's kick-off: with its kick-offs remembered (set_play_memory.hpp) the robots walking
  // to their places are forecast far nearer than those running the routine after the kick, and
  // the preparation's tight radii, carried over the kick, held the 90% radius at 82-85% at
  // 1-2 s on the tuning seeds 11/12 (88-94% apart). Our kick-off's preparation kept apart too
  // held it at 80-83% instead of 83-85% there: it stays with the rest of the kick-off.
  static constexpr std::size_t radius_groups = all_game_phases.size() + 1;
  static std::size_t radius_group(GamePhase phase, bool preparing);
  // A histogram of ln(distance / stated radius) in bins of `radius_bin_width` from
  // -max_log_radius_scale to +max_log_radius_scale (beyond: the edge bins), so that a radius is
  // scaled by at most e^max_log_radius_scale either way.
  static constexpr double max_log_radius_scale = 6.9;  // about 1,000
  static constexpr double radius_bin_width = 0.05;     // 5%
  static constexpr std::size_t radius_bins =
      static_cast<std::size_t>(2.0 * max_log_radius_scale / radius_bin_width) + 1;
  // Faded weights: a check adds the current boost, which then grows by 2^(1 / half count),
  // rather than every bin being faded at every check. Scaled back when the boost grows large.
  struct RadiusEvidence {
    std::array<float, radius_bins> off50{}, off90{};
    double weight = 0.0;  // in boosted units
    double boost = 1.0;
    // The bins with any weight lie within [first, last]; fresh: checked since the scales were
    // last worked out.
    std::size_t first = radius_bins - 1, last = 0;
    bool fresh = false;
  };
  static std::size_t radius_bin_of(double off_mm, double radius_mm);
  // The q-quantile of a histogram of `weight` (boosted) whose bins outside [first, last] are
  // empty, on the log scale.
  static double log_quantile(const std::array<float, radius_bins>& bins, double weight, double q,
                             std::size_t first, std::size_t last);
  // Faded sums over the checked predictions of one bin.
  struct Bin {
    double weight = 0.0;
    double hits = 0.0;
    double stated = 0.0;
  };
  // One remembered formation, decided once each of its robots is: a hit if every robot was in
  // its cell, nothing if one passed unseen (or the ends changed).
  struct FormationCheck {
    double due_s = 0.0;
    double stated = 0.0;          // the product of the robots' stated probabilities
    std::uint32_t remaining = 0;  // robots not yet checked
    bool all_hit = true;
    bool decidable = true;
  };
  struct Step {
    // The predictions waiting for their instant, in due order (predictions come in time order),
    // in a ring of a power-of-two size: a daemon remembers and checks a few dozen every frame,
    // and a ring does that without allocating once it has grown.
    std::vector<Pending> ring;
    std::size_t head = 0, size = 0;
    Pending& at(std::size_t i) { return ring[(head + i) & (ring.size() - 1)]; }
    const Pending& at(std::size_t i) const { return ring[(head + i) & (ring.size() - 1)]; }
    void push(const Pending& pending);
    std::array<Bin, bin_count> bins{};
    // Per bin, what adjust() adds: the evidence's weight times the rate's departure from the
    // stated probabilities. Worked out by observe() (every tenth of a second of the data clock),
    // so that adjust() only looks it up.
    std::array<double, bin_count> correction{};
    // The formations remembered and not yet decided, in order; the first is number
    // `first_formation`.
    std::deque<FormationCheck> formations;
    std::uint64_t first_formation = 0;
    std::array<Bin, bin_count> formation_bins{};
    std::array<double, bin_count> formation_correction{};
    std::array<bool, bin_count> formation_checked{};  // whether the bin has any evidence
    // Per game phase, the checked robots' distances as multiples of the stated radii, and the
    // scales adjust() applies (worked out with the corrections).
    std::array<RadiusEvidence, radius_groups> radii{};
    std::array<double, radius_groups> scale50 = ones(), scale90 = ones();
    static std::array<double, radius_groups> ones() {
      std::array<double, radius_groups> all{};
      all.fill(1.0);
      return all;
    }
    FormationCheck* formation(std::uint64_t number) {
      return number >= first_formation && number - first_formation < formations.size()
                 ? &formations[number - first_formation]
                 : nullptr;
    }
  };
  static std::size_t bin_of(double probability);

  OnlineCalibrationSettings settings_;
  std::vector<Step> steps_;
  std::optional<double> last_time_s_;
  IntervalGate correcting_;   // when the corrections are worked out
  IntervalGate remembering_;  // when predictions are remembered
  std::uint64_t checked_ = 0;
  std::uint64_t formations_checked_ = 0;
  double radius_growth_;  // 2^(1 / radius_half_count)
};

}  // namespace motion_model
}  // namespace ssl_formation
