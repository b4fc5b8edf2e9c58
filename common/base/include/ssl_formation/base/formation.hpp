#pragma once
// A formation (paper §3): the opponent robots of one sample, each with its state, and the
// transitions that sample adds to the table.

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/state.hpp"

namespace ssl_formation {
inline namespace base {

enum class TeamColor { yellow, blue };
std::optional<TeamColor> parse_team_color(std::string_view text);
std::string_view to_string(TeamColor color);
// The other team's colour.
constexpr TeamColor opposite(TeamColor color) {
  return color == TeamColor::yellow ? TeamColor::blue : TeamColor::yellow;
}

struct FormationRobot {
  std::uint32_t robot_id = 0;
  Point feed_position;  // millimetres, as the vision feed reports it
  Point position;       // normalised so that the opponent attacks towards +x
  Cell cell;
  Cell previous_cell;  // equal to cell when the robot starts a chain (velocity 0)
  StateIndex state = 0;
  // Seen in a frame since the previous instant. False for a robot carried over from an earlier
  // frame: a real log's camera packets each cover part of the field, so half the robots of an
  // instant are the last one's again. Those add nothing new to learn from (and, stamped with
  // this instant's time, would look as if they had stood still).
  bool observed = true;
};

struct Formation {
  double time_s = 0.0;             // the sample instant on the data clock
  std::uint32_t frame_number = 0;  // the detection frame that completed the sample
  Point centroid;                  // normalised, mean of the robots
  Cell centroid_cell;
  std::vector<FormationRobot> robots;  // sorted by robot id, each id once
  // False when this formation starts a chain: the first sample, or one after a gap.
  bool continues_previous = false;
  // The direction the positions were normalised with (the opponent attacks it in the feed).
  AttackDirection opponent_attacks = AttackDirection::positive_x;

  const FormationRobot* find(std::uint32_t robot_id) const {
    const auto it = std::lower_bound(
        robots.begin(), robots.end(), robot_id,
        [](const FormationRobot& robot, std::uint32_t id) { return robot.robot_id < id; });
    return it != robots.end() && it->robot_id == robot_id ? &*it : nullptr;
  }
};

struct Transition {
  std::uint32_t robot_id = 0;
  StateIndex from = 0;
  StateIndex to = 0;
  friend bool operator==(const Transition&, const Transition&) = default;
};

// One completed sample: its formation and the transitions from the previous one.
struct FormationSample {
  Formation formation;
  std::vector<Transition> transitions;
};

}  // namespace base
}  // namespace ssl_formation
