#include "ssl_formation/formation.hpp"

#include <algorithm>

namespace ssl_formation {

std::optional<TeamColor> parse_team_color(std::string_view text) {
  if (text == "yellow") return TeamColor::yellow;
  if (text == "blue") return TeamColor::blue;
  return std::nullopt;
}

std::string_view to_string(TeamColor color) {
  return color == TeamColor::yellow ? "yellow" : "blue";
}

const FormationRobot* Formation::find(std::uint32_t robot_id) const {
  const auto it = std::lower_bound(
      robots.begin(), robots.end(), robot_id,
      [](const FormationRobot& robot, std::uint32_t id) { return robot.robot_id < id; });
  return it != robots.end() && it->robot_id == robot_id ? &*it : nullptr;
}

}  // namespace ssl_formation
