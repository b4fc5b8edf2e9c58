#include "ssl_formation/simulation/robot_motion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ssl_formation::simulation {

namespace {

double length(Point p) { return std::hypot(p.x, p.y); }
Point scaled(Point p, double k) { return Point{p.x * k, p.y * k}; }
Point plus(Point a, Point b) { return Point{a.x + b.x, a.y + b.y}; }
Point minus(Point a, Point b) { return Point{a.x - b.x, a.y - b.y}; }
double dot(Point a, Point b) { return a.x * b.x + a.y * b.y; }

// `p` shortened to at most `most` long.
Point at_most(Point p, double most) {
  const double l = length(p);
  return l > most && l > 0.0 ? scaled(p, most / l) : p;
}

bool positive_finite(double x) { return x > 0.0 && std::isfinite(x); }

// Within this distance of its target a robot counts as there: it stops rather than dither
// around the point at the frame rate.
constexpr double kArrivedMm = 1.0;
// A robot's speed towards a neighbour is bounded by sqrt(a * gap / kApproachShare). With 4, each
// neighbour's bound shrinks no faster than braking at a / 4 follows: four neighbours pressing at
// once still fit in one robot's acceleration.
constexpr double kApproachShare = 4.0;
constexpr double kSpeedNearFactor = 2.0;
// However close, a robot may still creep along its neighbour this fast (its approach stays
// bounded): two robots at the closest distance would otherwise hold each other forever. What
// turning the line between them adds at this speed, the clearance takes up.
constexpr double kCreepMmS = 100.0;
// Inside the clearance, a robot moves away at this many mm/s for each mm it is in.
constexpr double kPushOutPerS = 4.0;

}  // namespace

TeamMotion::TeamMotion(MotionLimits limits, std::vector<Point> positions)
    : limits_(limits),
      positions_(std::move(positions)),
      velocities_(positions_.size(), Point{0.0, 0.0}),
      next_velocities_(positions_.size(), Point{0.0, 0.0}) {
  if (!positive_finite(limits_.max_speed_mm_s) ||
      !positive_finite(limits_.max_acceleration_mm_s2) ||
      !positive_finite(limits_.robot_radius_mm) || !(limits_.clearance_mm >= 0.0) ||
      !std::isfinite(limits_.clearance_mm) || !(limits_.area_half_length_mm >= 0.0) ||
      !std::isfinite(limits_.area_half_length_mm) || !(limits_.area_half_width_mm >= 0.0) ||
      !std::isfinite(limits_.area_half_width_mm)) {
    throw std::invalid_argument("motion limits must be positive and finite");
  }
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    for (std::size_t j = i + 1; j < positions_.size(); ++j) {
      if (length(minus(positions_[i], positions_[j])) < closest_allowed_mm()) {
        throw std::invalid_argument("robots " + std::to_string(i) + " and " + std::to_string(j) +
                                    " start inside one another");
      }
    }
  }
}

Point TeamMotion::wanted_velocity(std::size_t i, Point target, double dt_s,
                                  double top_speed) const {
  const Point to_target = minus(target, positions_[i]);
  const double distance = length(to_target);
  if (distance < kArrivedMm) return Point{0.0, 0.0};
  // The fastest speed v from which braking at a still stops on the target when the braking only
  // starts after this step: v * dt + v^2 / (2 a) <= distance.
  const double a = limits_.max_acceleration_mm_s2;
  const double braking = -a * dt_s + std::sqrt(a * dt_s * a * dt_s + 2.0 * a * distance);
  const double speed = std::min({top_speed, braking, distance / dt_s});
  return scaled(to_target, speed / distance);
}

template <class Visit>
void TeamMotion::for_each_neighbour(std::size_t i, Visit visit) const {
  for (std::size_t j = 0; j < positions_.size(); ++j) {
    if (j == i) continue;
    const Point between = minus(positions_[j], positions_[i]);
    const double distance = length(between);
    const Point towards = distance > 0.0 ? scaled(between, 1.0 / distance) : Point{1.0, 0.0};
    visit(towards, distance - closest_allowed_mm());
  }
}

template <class Visit>
void TeamMotion::for_each_wall(std::size_t i, Visit visit) const {
  const Point p = positions_[i];
  if (limits_.area_half_length_mm > 0.0) {
    visit(Point{1.0, 0.0}, std::max(0.0, limits_.area_half_length_mm - p.x));
    visit(Point{-1.0, 0.0}, std::max(0.0, limits_.area_half_length_mm + p.x));
  }
  if (limits_.area_half_width_mm > 0.0) {
    visit(Point{0.0, 1.0}, std::max(0.0, limits_.area_half_width_mm - p.y));
    visit(Point{0.0, -1.0}, std::max(0.0, limits_.area_half_width_mm + p.y));
  }
}

void TeamMotion::mirror() {
  for (Point& p : positions_) p = Point{-p.x, -p.y};
  for (Point& v : velocities_) v = Point{-v.x, -v.y};
}

void TeamMotion::halt(double dt_s) {
  if (!positive_finite(dt_s)) throw std::invalid_argument("halt needs a positive time");
  const double most_change = limits_.max_acceleration_mm_s2 * dt_s;
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    const double speed = length(velocities_[i]);
    // Braking straight on only lowers the speed towards every neighbour and wall: what kept two
    // robots apart at full speed keeps them apart while they stop.
    velocities_[i] =
        speed <= most_change ? Point{0.0, 0.0} : scaled(velocities_[i], 1.0 - most_change / speed);
    positions_[i] = plus(positions_[i], scaled(velocities_[i], dt_s));
  }
}

void TeamMotion::step(double dt_s, const std::vector<Point>& targets, double speed_cap_mm_s,
                      const std::optional<KeepOut>& keep_out) {
  if (targets.size() != positions_.size()) {
    throw std::invalid_argument("step needs one target per robot");
  }
  if (!positive_finite(dt_s)) throw std::invalid_argument("step needs a positive time");
  const double a = limits_.max_acceleration_mm_s2;
  const double most_change = a * dt_s;
  const double capped_speed = speed_cap_mm_s > 0.0
                                  ? std::min(speed_cap_mm_s, limits_.max_speed_mm_s)
                                  : limits_.max_speed_mm_s;
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    // The robot placing the ball is held to the limit only, not to the cap.
    const bool placing = keep_out && keep_out->except == static_cast<int>(i);
    const double top_speed = placing ? limits_.max_speed_mm_s : capped_speed;
    Point wanted = wanted_velocity(i, targets[i], dt_s, top_speed);
    // The fastest a robot may go towards a neighbour (or a wall) with `gap` of free space
    // between them. Inside the clearance (a negative gap, left over from a crowd) it has to
    // move away, at a speed growing with how far in it is.
    const auto approach_bound = [&](double gap) {
      if (gap < 0.0) return gap * kPushOutPerS;
      return std::min(std::sqrt(a * gap / kApproachShare), gap / (2.0 * dt_s));
    };
    // Towards each neighbour no faster than the gap allows. What is taken off the approach is
    // turned to the robot's right, so two robots meeting head on pass each other rather than
    // stand nose to nose.
    for_each_neighbour(i, [&](Point towards, double gap) {
      const double excess = dot(wanted, towards) - approach_bound(gap);
      if (excess > 0.0) {
        const Point right{towards.y, -towards.x};
        wanted = plus(minus(wanted, scaled(towards, excess)), scaled(right, 0.5 * excess));
      }
    });
    for_each_wall(i, [&](Point towards, double gap) {
      const double excess = dot(wanted, towards) - approach_bound(gap);
      if (excess > 0.0) wanted = minus(wanted, scaled(towards, excess));
    });
    // The keep-out disc, as a neighbour: what is taken off the approach turns the robot round it.
    const auto keep_out_of_disc = [&](Point& velocity, bool turn) {
      if (!keep_out || keep_out->except == static_cast<int>(i)) return;
      const Point between = minus(keep_out->centre, positions_[i]);
      const double distance = length(between);
      const Point towards = distance > 0.0 ? scaled(between, 1.0 / distance) : Point{1.0, 0.0};
      const double excess = dot(velocity, towards) - approach_bound(distance - keep_out->radius_mm);
      if (excess <= 0.0) return;
      velocity = minus(velocity, scaled(towards, excess));
      if (turn) velocity = plus(velocity, scaled(Point{towards.y, -towards.x}, 0.5 * excess));
    };
    keep_out_of_disc(wanted, true);
    wanted = at_most(wanted, top_speed);
    Point next = plus(velocities_[i], at_most(minus(wanted, velocities_[i]), most_change));
    // The disc gives way to the neighbours: robots never touching matters more than keeping
    // 0.5 m from the ball.
    keep_out_of_disc(next, false);
    // The turn to the right may point at another neighbour: within the acceleration still left,
    // take off any approach beyond a bound.
    for_each_neighbour(i, [&](Point towards, double gap) {
      const double excess = dot(next, towards) - approach_bound(gap);
      if (excess > 0.0) next = minus(next, scaled(towards, excess));
      // Close by, a neighbour passing sideways turns the line between the two fast, and with it
      // any speed along it: near one, a robot slows down unless it is clearly leaving (more
      // than 120 degrees away from the neighbour), or two robots side by side could never part.
      if (dot(next, towards) > -0.5 * length(next)) {
        next = at_most(next,
                       std::max(kCreepMmS, kSpeedNearFactor * approach_bound(std::max(0.0, gap))));
      }
    });
    for_each_wall(i, [&](Point towards, double gap) {
      const double excess = dot(next, towards) - approach_bound(gap);
      if (excess > 0.0) next = minus(next, scaled(towards, excess));
    });
    next = plus(velocities_[i], at_most(minus(next, velocities_[i]), most_change));
    // Whatever pushed it (a crowd, the disc), a robot keeps to the cap, or brakes towards it if
    // it was above it, within the acceleration limit.
    const double most_speed = std::max(top_speed, length(velocities_[i]) - most_change);
    if (length(next) > most_speed) {
      next = plus(velocities_[i],
                  at_most(minus(at_most(next, most_speed), velocities_[i]), most_change));
    }
    next_velocities_[i] = at_most(next, limits_.max_speed_mm_s);
  }
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    velocities_[i] = next_velocities_[i];
    positions_[i] = plus(positions_[i], scaled(velocities_[i], dt_s));
  }
}

}  // namespace ssl_formation::simulation
