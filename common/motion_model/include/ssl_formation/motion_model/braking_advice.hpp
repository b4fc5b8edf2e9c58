#pragma once
// Where a robot that is braking hard will stop. The rows of the table fit a robot's change of
// velocity with one coefficient per row, learned over robots that brake, turn and speed up
// alike. While the game is stopped and at restarts, a robot slowing down is taking its place
// (SSL rules, Referee Commands: in STOP robots keep away from the ball and slow down; a ball
// placement and a free kick have them stand at their places about the ball until it is
// played), and constant deceleration says where that is.

#include <vector>

#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"
#include "ssl_formation/motion_model/set_play_memory.hpp"

namespace ssl_formation {
inline namespace motion_model {

struct BrakingPath {
  // A robot braking at least this hard, at least this fast, is stopping (the tracker's
  // acceleration against its velocity). Under the vision's noise a standing robot's speed and
  // acceleration are tens of mm/s and a few hundred mm/s²; a robot turning has its change of
  // velocity across its velocity, not against it.
  static constexpr double min_speed_mm_s = 300.0;
  static constexpr double min_braking_mm_s2 = 1000.0;
  // How much the stopping point counts against the rows. Tuning seeds of the simulated match
  // (11/12, 13/14, 15/16 with 1,200 s of training, 17/18 with 3 mm of noise): at 0.7 every game
  // state it applies to was nearer at every horizon on all four (STOP at 1 s 161.3 to 160.6,
  // 147.4 to 145.1, 125.2 to 124.9, 199.3 to 198.2 mm). 1 did as well in STOP, 0.5 about as
  // well elsewhere (their free kicks with 3 mm of noise 130.7 against 130.0 at 1 s).
  static constexpr double weight = 0.7;
};

// Where it applies: STOP, both teams' placements (at theirs every robot but the one placing the
// ball, which has its path: game_rules.hpp) and their free kicks. Not in running play, where a
// robot braking is as often rounding a point of its run and going on: on the shared grSim
// recordings' inner splits (each one's first 4/9 against the next 2/9) the advice cost 1.1 mm at
// 0.5 s on both (94.3 to 95.4, 97.0 to 98.1), though it gained 0.5% on the simulated match.
// Not in HALT (its prior stands the robots still), not at their kick-offs (their earlier
// kick-offs advise every robot), not at our free kicks (the defenders brake to their marks and
// set off again with the kick: on the tuning seeds 17/18, 3 mm of noise, 230.5 to 232.9 mm at
// 1 s), not at our kick-offs (mixed: 841.0 to 841.8 mm at 2 s on 11/12, 900.6 to 898.0 on
// 15/16), not at penalties (no data).
bool braking_advice_holds(GamePhase phase);

// Advises each robot of `robots` (normalised, with `velocity_window_s` the window its
// kinematics' change of velocity spans) that is braking and has no advice in `advice` yet:
// at each of `steps` steps of `step_s`, where it is at constant deceleration until it stands.
// `advice` must have one entry per robot, or none (then it is made so).
void advise_braking(const std::vector<MotionRobot>& robots, double velocity_window_s, double step_s,
                    int steps, SetPlayAdvice& advice);

}  // namespace motion_model
}  // namespace ssl_formation
