#pragma once
// How far the predictions have lately been from where the robots went, in millimetres, against
// "every robot stays where it is", while the match runs: what the field view shows a team
// deciding whether to trust the predictor today. Each prediction (at most one every
// remember_interval_s) is kept until its instant comes; then every robot's predicted position
// and its position at the time of the prediction are both measured against where it is, and
// the two errors go into means that fade with a half-life of data time. Only the positions the
// prediction states are scored, so this is the model's error as the tables stand, not a test on
// held-out data (that is ssl-evaluate's). The same means are also kept per phase of the game the
// prediction was made in, since a team reads "off by 300 mm" differently in a halt and in play.

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/match/game_phase.hpp"

namespace ssl_formation {
inline namespace pipeline {

struct LiveScoreSettings {
  double half_life_s = 30.0;          // of the data clock
  double remember_interval_s = 0.25;  // predictions kept at most this often
  double tolerance_s = 0.05;          // a frame this soon after the instant checks it
  bool valid() const;
};

class LiveScore {
 public:
  explicit LiveScore(LiveScoreSettings settings = {});

  // Scores the kept predictions whose instant `formation` reaches (each robot seen in it) and
  // forgets those whose instant passed. Formations in time order; a clock going back starts
  // over.
  void observe(const Formation& formation);
  // Keeps `prediction`, made from `formation` in `phase` with `step_s` between its steps, unless
  // one was kept less than the remember interval before.
  void remember(const Prediction& prediction, const Formation& formation, double step_s,
                GamePhase phase = GamePhase::running);
  void clear();

  struct Horizon {
    double horizon_s = 0.0;
    double model_mm = 0.0;        // faded mean error of the predicted positions
    double persistence_mm = 0.0;  // the same robots, had they stayed where they were
    double robots = 0.0;          // the faded number of robots behind the means
  };
  // One per step predicted so far, nearest first; empty before anything was scored.
  const std::vector<Horizon>& horizons() const { return all_.horizons; }
  // The same for the predictions made in `phase` only; empty while none of them was scored.
  const std::vector<Horizon>& horizons(GamePhase phase) const {
    return by_phase_[static_cast<std::size_t>(phase)].horizons;
  }
  // The horizon nearest `horizon_s`, if any was scored.
  const Horizon* nearest(double horizon_s) const;
  std::uint64_t scored() const { return scored_; }

 private:
  struct Pending {
    double due_s = 0.0;
    std::size_t step = 0;
    std::uint32_t robot_id = 0;
    GamePhase phase = GamePhase::running;
    Point predicted;  // feed coordinates
    Point then;       // where it was when predicted
  };
  // Faded sums and their means, per step.
  struct Means {
    std::vector<Horizon> horizons;
    std::vector<double> model_sum;
    std::vector<double> persistence_sum;
    void reach(std::size_t step, double step_s);  // has room for `step`, of that horizon
    void add(std::size_t step, double model_mm, double persistence_mm);
    void fade(double keep);
    void update_means();
  };
  void fade_to(double time_s);

  LiveScoreSettings settings_;
  std::deque<Pending> pending_;  // in order of due time within a prediction; sorted on insert
  Means all_;
  std::array<Means, all_game_phases.size()> by_phase_;
  double last_remembered_s_ = -1e300;
  double last_seen_s_ = -1e300;
  double faded_to_s_ = -1e300;
  std::uint64_t scored_ = 0;
};

// For status lines, at the step nearest 1 s: the model's mean error and that of "everyone stays"
// as "140mm at 1.0s (stays 307mm)", or "" before anything was scored.
std::string describe_for_status(const LiveScore& score);

}  // namespace pipeline
}  // namespace ssl_formation
