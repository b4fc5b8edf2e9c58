#include "ssl_formation/vision/attack_inference.hpp"

#include <cmath>
#include <limits>

namespace ssl_formation {
inline namespace vision {

void AttackInference::reset() {
  tracks_.clear();
  direction_.reset();
  candidate_.reset();
  switches_ = 0;
}

bool AttackInference::add(double time_s, const std::vector<Robot>& robots, const FieldSize& field) {
  // Each robot's recent mean position: an exponential average over a quarter of the window
  // (O(1) a robot and sample; it follows a keeper to the other goal within seconds, and the
  // window-long hold below keeps a corner from flipping the direction).
  for (const Robot& robot : robots) {
    if (robot.robot_id >= tracks_.size()) tracks_.resize(robot.robot_id + 1);
    Track& track = tracks_[robot.robot_id];
    if (!track.seen || time_s - track.last_s > window_s_) {
      track = Track{true, time_s, time_s, robot.position.x, robot.position.y};
      continue;
    }
    const double weight = 1.0 - std::exp(-4.0 * (time_s - track.last_s) / window_s_);
    track.mean_x += weight * (robot.position.x - track.mean_x);
    track.mean_y += weight * (robot.position.y - track.mean_y);
    track.last_s = time_s;
  }
  // The goalkeeper: of the robots followed for a whole window and seen now, the one nearest a
  // goal's centre. Ghosts (seen for a few frames) never qualify.
  const double half_length = field.length_mm / 2.0;
  double nearest = std::numeric_limits<double>::infinity();
  std::optional<AttackDirection> says;
  for (const Robot& robot : robots) {
    const Track& track = tracks_[robot.robot_id];
    if (time_s - track.first_s < window_s_) continue;
    for (const double goal_x : {-half_length, half_length}) {
      const double distance = std::hypot(track.mean_x - goal_x, track.mean_y);
      if (distance < nearest) {
        nearest = distance;
        // Its own goal at -x: the opponent attacks +x.
        says = goal_x < 0 ? AttackDirection::positive_x : AttackDirection::negative_x;
      }
    }
  }
  if (!says) return false;
  if (says != candidate_) {
    candidate_ = says;
    candidate_since_s_ = time_s;
  }
  if (direction_ == candidate_) return false;
  // The first decision once a goalkeeper is known; a switch once the other goal held it a window.
  if (direction_ && time_s - candidate_since_s_ < window_s_) return false;
  if (direction_) ++switches_;
  direction_ = candidate_;
  return true;
}

}  // namespace vision
}  // namespace ssl_formation
