#pragma once
// What the rules of the game say of where the predicted team's robots can go, from what the front
// end knows of the match (the referee's state, whose restart it is, the ball and a placement's
// target): the constraints every motion forecast is held to (motion_model/motion_predictor.hpp's
// MotionRules). The rules quoted are the SSL rules' chapter "Referee Commands" (2025).

#include "ssl_formation/models/model.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"

namespace ssl_formation::models {

// A ball slower than this has not been kicked: at a free kick the defenders keep their distance
// until "the ball is in play" (it moved), and after that the rule no longer holds.
inline constexpr double ball_at_rest_mm_s = 500.0;

MotionRules rules_of_the_game(const MatchMoment& moment);

}  // namespace ssl_formation::models
