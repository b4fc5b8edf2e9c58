#pragma once
// How simulated robots move (issue 15's match simulation): each drives towards its target within
// the speed and acceleration an SSL robot has (about 3 m/s and 3 m/s^2), brakes in time to stop
// on it, never teleports, and never drives into another robot.
//
// The last is kept by bounds on speed near other robots, gap being the free space between two
// shells beyond the clearance:
// - towards a neighbour, at most sqrt(a * gap / 4): if both close in at that speed and then
//   brake, they stop within the gap, and the bound shrinks no faster than braking at a / 4 can
//   follow, so four neighbours at once still fit in the acceleration limit;
// - in any direction, at most sqrt(a * gap): a neighbour passing sideways turns the line
//   between the two fast, and with it the part of a robot's speed that points at the other.
// The second costs speed in a crowd (about 1 m/s at 30 cm apart); a robot may still creep at
// 0.1 m/s, and one a crowd pushed inside the clearance is pushed out. 16 robots driven into one
// small disc over 300 seeds never touched (a run made while tuning; the suite drives 11 over
// 20 seeds, and every simulated match's robots in every frame).
//
//   TeamMotion robots(limits, start_positions);
//   robots.step(1.0 / 60.0, targets);  // every frame
//   robots.position(i), robots.velocity(i)

#include <cstddef>
#include <optional>
#include <vector>

#include "ssl_formation/base/grid.hpp"

namespace ssl_formation::simulation {

struct MotionLimits {
  double max_speed_mm_s = 3000.0;
  double max_acceleration_mm_s2 = 3000.0;
  double robot_radius_mm = 90.0;  // SSL robots are at most 180 mm across
  // Free space kept between two robots' shells on top of not touching, so the vision's noise
  // never shows two robots in one another.
  double clearance_mm = 40.0;
  // Where robots may go, centred on the origin (their centres stay within +-half sizes); 0: no
  // bounds. The walls are kept to as neighbours are: robots brake for them in time.
  double area_half_length_mm = 0.0;
  double area_half_width_mm = 0.0;
};

// A disc robots keep out of, as the rules keep them 0.5 m from the ball while the game is
// stopped: kept to as a neighbour is (robots brake for it in time and pass it on their right),
// and a robot inside it is pushed out. One robot, the one placing the ball, may enter it and is
// not held to the speed cap (the rules cap the speed in STOP; a placement has to be quick).
struct KeepOut {
  Point centre;
  double radius_mm = 0.0;
  int except = -1;  // the robot that may enter; -1: none
};

class TeamMotion {
 public:
  // Robots at rest at `positions` (mm). Throws std::invalid_argument for limits that are not
  // positive and finite, or for two robots that start closer than their shells and clearance.
  TeamMotion(MotionLimits limits, std::vector<Point> positions);

  // Advances every robot by `dt_s` seconds towards its target (one per robot, in order). A
  // target inside another robot's shell is driven towards as far as the shells allow.
  // `speed_cap_mm_s` (0: the limit) caps the speed robots aim for, as the rules do while the
  // game is stopped (1.5 m/s); robots above it brake to it within the acceleration limit.
  // `keep_out`: a disc no robot but its exception drives into.
  void step(double dt_s, const std::vector<Point>& targets, double speed_cap_mm_s = 0.0,
            const std::optional<KeepOut>& keep_out = std::nullopt);
  // HALT: every robot brakes straight on as hard as the acceleration limit lets it and then
  // stands exactly where it stopped, whatever its target (no creeping, no pushing apart).
  void halt(double dt_s);
  // The same robots seen from the other end of the field: every position and velocity turned
  // about the centre.
  void mirror();

  std::size_t size() const { return positions_.size(); }
  Point position(std::size_t robot) const { return positions_.at(robot); }
  Point velocity(std::size_t robot) const { return velocities_.at(robot); }
  const MotionLimits& limits() const { return limits_; }
  // Robots closer than this centre to centre would overlap or break the clearance.
  double closest_allowed_mm() const { return 2.0 * limits_.robot_radius_mm + limits_.clearance_mm; }

 private:
  // The velocity robot `i` wants: straight at its target, as fast as it can still brake for in
  // steps of `dt_s`.
  Point wanted_velocity(std::size_t i, Point target, double dt_s, double top_speed) const;
  // visit(direction to it, free space beyond the closest allowed) for each other robot.
  template <class Visit>
  void for_each_neighbour(std::size_t i, Visit visit) const;
  // visit(direction out, free space) for each wall of the area around robot `i`.
  template <class Visit>
  void for_each_wall(std::size_t i, Visit visit) const;

  MotionLimits limits_;
  std::vector<Point> positions_;
  std::vector<Point> velocities_;
  std::vector<Point> next_velocities_;  // reused by step()
};

}  // namespace ssl_formation::simulation
