#pragma once
// What the match simulation's files share: the distances and speeds of its play and of the rules
// it plays by, and the geometry helpers its robots and referee use.

#include <algorithm>
#include <cmath>
#include <vector>

#include "ssl_formation/simulation/match_simulation.hpp"

namespace ssl_formation::simulation::detail {

constexpr double kPi = 3.14159265358979323846;
// The ball: at a holder's feet this far ahead of its centre, passed and shot at these speeds,
// taken by a robot this close to it.
constexpr double kBallAheadMm = 110.0;
constexpr double kPassSpeedMmS = 4000.0;
constexpr double kShotSpeedMmS = 6000.0;
constexpr double kTakeBallMm = 150.0;
// A goalkeeper stands this far in front of its goal line, and follows the ball's y by this
// share within the goal's width.
constexpr double kKeeperLineMm = 200.0;
constexpr double kKeeperFollow = 0.4;
constexpr double kKeeperRangeMm = 450.0;
// Our markers stand between their opponent and our goal, this far from the opponent.
constexpr double kMarkingMm = 350.0;
// The share of shots that score in the plain game (GameShape has its own); the others go wide,
// for a free kick.
constexpr double kGoalShare = 0.4;
// Of the shots wide, the share a defender touched last: a corner for the opponent; the others
// give us a goal kick.
constexpr double kCornerShare = 0.5;
// While the game is stopped robots keep this far from the ball and drive at most this fast
// (the rules: 0.5 m and 1.5 m/s).
constexpr double kStopDistanceMm = 600.0;
constexpr double kStopSpeedMmS = 1500.0;
// On their way robots keep out of this disc around the ball (the rules' 0.5 m and a margin).
constexpr double kKeepOutMm = 560.0;
// A foul the referee calls (GameShape): the ball is placed this far from where it was, and at
// least this far inside the field lines.
constexpr double kFoulPlacementMinMm = 1000.0;
constexpr double kFoulPlacementMaxMm = 3000.0;
constexpr double kPlacementMarginMm = 300.0;
// A kick-off: the kicking team's other robots, and all of the other team, stay out of the
// centre circle (radius 0.5 m) and in their own halves.
constexpr double kCentreCircleMm = 650.0;
constexpr double kOwnHalfMarginMm = 150.0;
// Ball placement carries the ball at this speed once the placing robot has it.
constexpr double kPlacementSpeedMmS = 1500.0;
// Our possession, after a goal kick or our kick-off, lasts this long before the opponent wins
// the ball back.
constexpr double kOurPossessionMinS = 2.0;
constexpr double kOurPossessionMaxS = 5.0;

inline double length(Point p) { return std::hypot(p.x, p.y); }
// `p` moved out to `distance` from `centre` if it is closer.
inline Point away_from(Point p, Point centre, double distance) {
  const double dx = p.x - centre.x;
  const double dy = p.y - centre.y;
  const double l = std::hypot(dx, dy);
  if (l >= distance) return p;
  if (l == 0.0) return Point{centre.x - distance, centre.y};
  return Point{centre.x + dx / l * distance, centre.y + dy / l * distance};
}
// `p` moved out to `distance` from the segment from `a` to `b` if it is closer: off the path a
// robot placing the ball takes.
inline Point away_from_segment(Point p, Point a, Point b, double distance) {
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  const double l2 = dx * dx + dy * dy;
  const double t =
      l2 > 0.0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / l2, 0.0, 1.0) : 0.0;
  const Point closest{a.x + t * dx, a.y + t * dy};
  if (std::hypot(p.x - closest.x, p.y - closest.y) >= distance) return p;
  if (p.x == closest.x && p.y == closest.y && l2 > 0.0) {
    // On the path: out to its right.
    const double l = std::sqrt(l2);
    return Point{closest.x + dy / l * distance, closest.y - dx / l * distance};
  }
  return away_from(p, closest, distance);
}
// The team a team command (a kick-off, a free kick, a placement) is for: its yellow value is
// even, its blue one odd.
inline TeamColor team_of_command(int command) {
  return command % 2 == 0 ? TeamColor::yellow : TeamColor::blue;
}
inline Point minus(Point a, Point b) { return Point{a.x - b.x, a.y - b.y}; }
inline Point towards(Point from, Point to, double distance) {
  const Point d = minus(to, from);
  const double l = length(d);
  if (l <= distance || l == 0.0) return to;
  return Point{from.x + d.x * distance / l, from.y + d.y * distance / l};
}

// The index in [first, last) whose position (position_of(index)) is nearest to `p`; the first
// such on a tie.
template <class PositionOf>
inline int nearest_of(int first, int last, Point p, PositionOf position_of) {
  int nearest = first;
  double best = 1e18;
  for (int i = first; i < last; ++i) {
    const double d = length(minus(position_of(i), p));
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  return nearest;
}

// A kick-off line-up: the opponent in its half (-x), ours in the other, in rows, keepers on
// their lines. Far enough apart for TeamMotion.
inline std::vector<Point> line_up(const FieldSize& field, int team_size) {
  std::vector<Point> out;
  const double half_length = field.length_mm / 2.0;
  const double half_width = field.width_mm / 2.0;
  for (const double side : {-1.0, 1.0}) {
    out.push_back(Point{side * (half_length - kKeeperLineMm), 0.0});
    const int players = team_size - 1;
    for (int i = 0; i < players; ++i) {
      const int row = i % 2;
      const int column = i / 2;
      const int columns = (players + 1) / 2;
      const double x = side * half_length * (0.25 + 0.35 * row);
      const double y = -half_width * 0.8 + 1.6 * half_width * (column + 0.5) / columns;
      out.push_back(Point{x, y});
    }
  }
  return out;
}

// The limits with the area robots stay in: the field and most of its boundary area (300 mm in
// the rules), which robots making way for one another may use.
inline MotionLimits within_boundary(MotionLimits limits, const FieldSize& field) {
  constexpr double kBoundaryUsedMm = 250.0;
  limits.area_half_length_mm = field.length_mm / 2.0 + kBoundaryUsedMm;
  limits.area_half_width_mm = field.width_mm / 2.0 + kBoundaryUsedMm;
  return limits;
}

}  // namespace ssl_formation::simulation::detail
