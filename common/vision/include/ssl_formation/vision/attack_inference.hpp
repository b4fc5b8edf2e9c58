#pragma once
// Which way the opponent attacks, inferred from where its goalkeeper stands: real logs do not say,
// and teams change ends at half time. The goalkeeper is the opponent robot that stays nearest one
// goal (the centre of a goal line) over a window of seconds; the opponent attacks away from that
// goal. The inferred direction switches only when the other goal has held the goalkeeper for a
// whole window, so an attacker lingering at our goal for a corner does not flip it.
//
// Pure: positions and times in (the feed's coordinates), a direction out.

#include <cstdint>
#include <optional>
#include <vector>

#include "ssl_formation/base/grid.hpp"

namespace ssl_formation {
inline namespace vision {

class AttackInference {
 public:
  explicit AttackInference(double window_s = 10.0) : window_s_(window_s) {}

  // One sample of the opponent's robots at `time_s` (feed coordinates, mm). Returns true when the
  // direction was decided for the first time or switched.
  struct Robot {
    std::uint32_t robot_id = 0;
    Point position;
  };
  bool add(double time_s, const std::vector<Robot>& robots, const FieldSize& field);

  // Nothing until a goalkeeper has held one goal for a window.
  std::optional<AttackDirection> direction() const { return direction_; }
  std::uint64_t switches() const { return switches_; }
  void reset();

 private:
  struct Track {
    bool seen = false;
    double first_s = 0.0;
    double last_s = 0.0;
    double mean_x = 0.0;  // exponentially weighted over the window
    double mean_y = 0.0;
  };

  double window_s_;
  std::vector<Track> tracks_;  // by robot id
  std::optional<AttackDirection> direction_;
  std::optional<AttackDirection> candidate_;  // what the goalkeeper says now
  double candidate_since_s_ = 0.0;
  std::uint64_t switches_ = 0;
};

}  // namespace vision
}  // namespace ssl_formation
