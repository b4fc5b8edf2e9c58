#include "ssl_formation/base/formation.hpp"

namespace ssl_formation {
inline namespace base {

std::optional<TeamColor> parse_team_color(std::string_view text) {
  if (text == "yellow") return TeamColor::yellow;
  if (text == "blue") return TeamColor::blue;
  return std::nullopt;
}

std::string_view to_string(TeamColor color) {
  return color == TeamColor::yellow ? "yellow" : "blue";
}

}  // namespace base
}  // namespace ssl_formation
