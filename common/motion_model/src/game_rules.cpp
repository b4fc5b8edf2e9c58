#include "ssl_formation/motion_model/game_rules.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace ssl_formation {
inline namespace motion_model {

namespace {

constexpr double stop_speed_limit_mm_s = 1500.0;
constexpr double ball_distance_mm = 500.0;

// The index of the robot (FormationRobot, MotionRobot: anything with a position) nearest to
// `point`, the first on a tie; none for no robots.
template <typename Robot>
std::optional<std::size_t> nearest_index(const std::vector<Robot>& robots, Point point) {
  std::optional<std::size_t> nearest;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const double d = std::hypot(robots[i].position.x - point.x, robots[i].position.y - point.y);
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  return nearest;
}

// The predicted team's robot nearest to `point`: the one placing the ball, or its kicker.
std::optional<std::uint32_t> nearest_robot(const Formation& formation, Point point) {
  const std::optional<std::size_t> i = nearest_index(formation.robots, point);
  if (!i) return std::nullopt;
  return formation.robots[*i].robot_id;
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

void advise_ball_placement(const std::vector<MotionRobot>& robots, Point ball, Point spot,
                           double step_s, int steps, SetPlayAdvice& advice) {
  using Path = BallPlacementPath;
  advice.robots.assign(robots.size(), SetPlayAdvice::Robot{});
  advice.any = false;
  const std::optional<std::size_t> nearest = nearest_index(robots, ball);
  if (!nearest) return;
  const std::size_t placer = *nearest;
  const MotionRobot& robot = robots[placer];
  const double to_spot = std::hypot(spot.x - ball.x, spot.y - ball.y);
  const double to_ball = std::hypot(ball.x - robot.position.x, ball.y - robot.position.y);
  // The way it takes: on to where it has the ball behind the spot; or first to the ball's far
  // side from the spot; or, for a ball within the tolerance of its spot already (whose far side
  // is no side at all), straight to the ball, which it will touch into place.
  std::array<Point, 3> path{robot.position, {}, {}};
  std::size_t corners = 2;
  if (to_ball < Path::carrying_mm) {
    path[1] = {spot.x + robot.position.x - ball.x, spot.y + robot.position.y - ball.y};
  } else if (to_spot <= Path::placed_mm) {
    const double short_of_ball = (to_ball - Path::behind_ball_mm) / to_ball;
    path[1] = {robot.position.x + (ball.x - robot.position.x) * short_of_ball,
               robot.position.y + (ball.y - robot.position.y) * short_of_ball};
  } else {
    const Point along{(spot.x - ball.x) / to_spot, (spot.y - ball.y) / to_spot};
    path[1] = {ball.x - along.x * Path::behind_ball_mm, ball.y - along.y * Path::behind_ball_mm};
    path[2] = {spot.x - along.x * Path::behind_ball_mm, spot.y - along.y * Path::behind_ball_mm};
    corners = 3;
  }
  // Its speed along the way: what it already has towards the first corner, then speeding up.
  const double first_leg = std::hypot(path[1].x - path[0].x, path[1].y - path[0].y);
  double speed = 0.0;
  if (robot.has_velocity && first_leg > 1.0) {
    const Point v = robot.kinematics.velocity;
    speed = std::clamp((v.x * (path[1].x - path[0].x) + v.y * (path[1].y - path[0].y)) / first_leg,
                       0.0, Path::speed_mm_s);
  }
  const double speeding_up_s = (Path::speed_mm_s - speed) / Path::acceleration_mm_s2;
  SetPlayAdvice::Robot& out = advice.robots[placer];
  const int advised = std::min(steps, static_cast<int>(out.weight.size()));
  for (int k = 0; k < advised; ++k) {
    const double h = (k + 1) * step_s;
    const double t = std::min(h, speeding_up_s);
    double travelled =
        speed * t + 0.5 * Path::acceleration_mm_s2 * t * t + Path::speed_mm_s * (h - t);
    Point at = path[corners - 1];
    for (std::size_t i = 0; i + 1 < corners; ++i) {
      const double leg = std::hypot(path[i + 1].x - path[i].x, path[i + 1].y - path[i].y);
      if (travelled <= leg) {
        const double f = leg > 0.0 ? travelled / leg : 0.0;
        at = {path[i].x + (path[i + 1].x - path[i].x) * f,
              path[i].y + (path[i + 1].y - path[i].y) * f};
        break;
      }
      travelled -= leg;
    }
    out.position[static_cast<std::size_t>(k)] = at;
    out.weight[static_cast<std::size_t>(k)] = Path::weight * std::min(1.0, h / Path::full_weight_s);
  }
  advice.any = advised > 0;
}

}  // namespace motion_model
}  // namespace ssl_formation
