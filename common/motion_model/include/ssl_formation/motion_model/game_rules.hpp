#pragma once
// What the rules of the game say of where the predicted team's robots can go, from what the front
// end knows of the match (the referee's state, whose restart it is, the ball and a placement's
// target): the constraints every motion forecast is held to (motion_model/motion_predictor.hpp's
// MotionRules), and where a placement takes the robot placing the ball (advise_ball_placement).
// The rules quoted are the SSL rules' chapter "Referee Commands" (2025).

#include <vector>

#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"

namespace ssl_formation {
inline namespace motion_model {

// A ball slower than this has not been kicked: at a free kick the defenders keep their distance
// until "the ball is in play" (it moved), and after that the rule no longer holds.
inline constexpr double ball_at_rest_mm_s = 500.0;

MotionRules rules_of_the_game(const MatchMoment& moment);

// At the opponent's ball placement the rules say where one robot is going: the ball "has to be
// placed [...] at the designated position" (Ball Placement) by a robot of the placing team,
// within 0.15 m (the game controller's ball-placement-tolerance). The robot nearest the ball is
// taken to be the one placing it. It drives to the ball (to its side away from the spot) and
// carries it there, or, already at the ball, carries it on. Fills `advice` (one entry per robot
// of `robots`, the opponent's, normalised like `ball` and `spot`) with where that path puts it
// at each of `steps` steps of `step_s`, and a weight; every other robot gets none.
struct BallPlacementPath {
  // Its speed: the rules give none. The tuning seeds' placements carry at 1.5 m/s (our
  // simulation's), real teams' speeds are not known here: the path weighs `weight`, the rows
  // of the table the rest.
  static constexpr double speed_mm_s = 1500.0;
  static constexpr double acceleration_mm_s2 = 2000.0;
  // A ball this near the spot is within the rules' tolerance: the robot goes straight to it.
  static constexpr double placed_mm = 150.0;
  // A robot this near the ball has it; the robot's centre stays this far behind the ball.
  static constexpr double carrying_mm = 300.0;
  static constexpr double behind_ball_mm = 110.0;
  // How much the path counts against the rows, reached at `full_weight_s` ahead: over the first
  // few tenths the robot's own motion (still turning to the ball, slowing at it) says more. On
  // the tuning seeds 11/12 and 13/14 (their placements, mm at 0.2 / 0.5 / 1 / 2 s; the rows
  // alone 6.2 / 31.4 / 92.1 / 241.4 and 5.6 / 28.4 / 84.1 / 204.2) a weight of 1 was worse at
  // 0.2-1 s (8.7 / 37.4 / 102.2 / 247.4), 0.5 best at 1-2 s but above damped constant
  // acceleration at 0.5 s on 13/14, 0.4 ramped over 0.5 s: 5.9 / 30.1 / 86.4 / 230.1 and
  // 5.4 / 26.9 / 75.0 / 182.2.
  static constexpr double weight = 0.4;
  static constexpr double full_weight_s = 0.5;
};
void advise_ball_placement(const std::vector<MotionRobot>& robots, Point ball, Point spot,
                           double step_s, int steps, SetPlayAdvice& advice);

}  // namespace motion_model
}  // namespace ssl_formation
