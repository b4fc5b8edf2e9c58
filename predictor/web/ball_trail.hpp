#pragma once
// The ball and the path it took over the last seconds, for the field view: where the front end's
// ball follower last put it, kept every `spacing_s` of data time for `keep_s`. A ball not seen
// for `forget_after_s` before the feed's newest frame is gone from the view (off the field,
// covered, in a robot's hands), and so is its path. Pure: fed with the follower's state and the
// newest frame's time.

#include <deque>
#include <optional>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/vision/ball_tracker.hpp"

namespace ssl_formation::predictor::web {

struct BallTrailSettings {
  double keep_s = 2.0;
  double spacing_s = 0.05;
  double forget_after_s = 0.5;
  // A sighting this much older than the newest kept one means the data clock restarted.
  double clock_reset_s = 1.0;
  bool valid() const;
};

class BallTrail {
 public:
  // Throws std::invalid_argument for settings that are not valid().
  explicit BallTrail(BallTrailSettings settings = {});

  // The follower's ball (none: never seen since its last reset) as of the feed's newest frame at
  // `now_s`, on the data clock.
  void update(const std::optional<BallState>& ball, double now_s);
  void clear();

  // Where the ball is; none when it is not seen lately.
  std::optional<Point> position() const;
  // Its path, oldest first, ending where it is; empty when it is not seen lately.
  const std::deque<Point>& path() const { return path_; }

 private:
  BallTrailSettings settings_;
  std::deque<Point> path_;
  std::deque<double> times_;          // the data time of each point of path_
  double last_point_s_ = 0.0;         // the newest point kept every spacing_s
  bool head_between_points_ = false;  // path_'s last point is the newest sighting since then
  bool seen_ = false;
};

}  // namespace ssl_formation::predictor::web
