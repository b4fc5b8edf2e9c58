#include "ssl_formation/models/game_rules.hpp"

#include <cmath>
#include <limits>

namespace ssl_formation::models {

namespace {

constexpr double stop_speed_limit_mm_s = 1500.0;
constexpr double ball_distance_mm = 500.0;

// The predicted team's robot nearest to `point`: the one placing the ball, or its kicker.
std::optional<std::uint32_t> nearest_robot(const Formation& formation, Point point) {
  std::optional<std::uint32_t> nearest;
  double best = std::numeric_limits<double>::infinity();
  for (const FormationRobot& robot : formation.robots) {
    const double d = std::hypot(robot.position.x - point.x, robot.position.y - point.y);
    if (d < best) {
      best = d;
      nearest = robot.robot_id;
    }
  }
  return nearest;
}

}  // namespace

MotionRules rules_of_the_game(const MatchMoment& moment) {
  MotionRules rules;
  rules.keep_away_mm = ball_distance_mm;
  switch (moment.game_state) {
    case GameState::stop:
      // "All robots have to slow down to less than 1.5 m/s. Additionally, all robots have to
      // keep at least 0.5 meters distance to the ball" (Stop).
      rules.max_speed_mm_s = stop_speed_limit_mm_s;
      rules.keep_away_from = moment.ball;
      break;
    case GameState::ball_placement:
      // Not STOP's speed limit: "This rule does not apply to ball placement" (Fouls: Robot Stop
      // Speed). The placing team moves freely; at our placement the opponent, the non-placing
      // team, "ha[s] to keep at least 0.5 meters distance to the line between the ball and the
      // placement position" (Fouls: Ball Placement Interference).
      if (moment.phase == GamePhase::ball_placement_us && moment.ball) {
        rules.keep_away_from = moment.ball;
        rules.keep_away_to = moment.designated_position;
      }
      break;
    case GameState::kickoff_preparation: {
      // "All robots have to move to their own half of the field excluding the center circle.
      // However, one robot of the attacking team is also allowed to be inside the whole center
      // circle" (Kick-Off). The ball is on the centre mark.
      // Only where the team stands as the sides say: a team gathering in the half the options
      // or the referee call the other one means the sides are wrong (or not known yet), and
      // holding its robots to the wrong half would move every one of them the wrong way.
      rules.own_half = moment.formation().centroid.x < 0.0;
      const Point centre = moment.ball.value_or(Point{0.0, 0.0});
      rules.keep_away_from = centre;
      if (moment.phase == GamePhase::kickoff_opponent) {
        rules.exempt_robot_id = nearest_robot(moment.formation(), centre);
      }
      break;
    }
    case GameState::free_kick:
      // "Robots of the defending team still have to stay at least 0.5 meters distance away from
      // the ball" (Direct Free Kick), until the ball is in play.
      if (moment.phase == GamePhase::free_kick_us && moment.ball &&
          std::hypot(moment.ball_velocity.x, moment.ball_velocity.y) < ball_at_rest_mm_s) {
        rules.keep_away_from = moment.ball;
      }
      break;
    default:
      break;  // HALT and timeouts are the model's prior (MotionModelSettings); play runs free
  }
  return rules;
}

}  // namespace ssl_formation::models
