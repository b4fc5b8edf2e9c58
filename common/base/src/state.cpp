#include "ssl_formation/base/state.hpp"

namespace ssl_formation {
inline namespace base {

std::string StateCodec::describe(StateIndex index) const {
  const RobotState s = decode(index);
  const Cell v = s.velocity();
  std::string out = std::to_string(index);
  out += " centroid=(" + std::to_string(s.centroid.x) + "," + std::to_string(s.centroid.y) + ")";
  out += " position=(" + std::to_string(s.position.x) + "," + std::to_string(s.position.y) + ")";
  out += " previous=(" + std::to_string(s.previous.x) + "," + std::to_string(s.previous.y) + ")";
  out += " velocity=(" + std::to_string(v.x) + "," + std::to_string(v.y) + ")";
  return out;
}

}  // namespace base
}  // namespace ssl_formation
