#include "field_markings.hpp"

#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::predictor::web {

ViewMarkings markings_for(const FieldSize& field, const std::optional<FieldMarkings>& stated) {
  // The rules' dimensions for the rest (rules_markings, the same ssl-producer states).
  const FieldMarkings rules = rules_markings(field);
  ViewMarkings m;
  int taken = 0;
  int left = 0;
  // A stated value replaces the rules' one when it is positive and at most `limit`.
  const auto take = [&](double& value, std::int32_t rule, std::int32_t given, double limit) {
    if (stated && given > 0 && static_cast<double>(given) <= limit) {
      value = given;
      ++taken;
    } else {
      value = rule;
      ++left;
    }
  };
  const double half_length = field.length_mm / 2.0;
  const FieldMarkings none;
  const FieldMarkings& given = stated ? *stated : none;
  take(m.goal_width_mm, rules.goal_width, given.goal_width, field.width_mm);
  take(m.goal_depth_mm, rules.goal_depth, given.goal_depth, half_length);
  take(m.boundary_width_mm, rules.boundary_width, given.boundary_width, half_length);
  take(m.penalty_area_depth_mm, rules.penalty_area_depth, given.penalty_area_depth, half_length);
  take(m.penalty_area_width_mm, rules.penalty_area_width, given.penalty_area_width, field.width_mm);
  take(m.center_circle_radius_mm, rules.center_circle_radius, given.center_circle_radius,
       field.width_mm / 2.0);
  m.source = left == 0 ? "geometry" : taken == 0 ? "rules" : "geometry and rules";
  return m;
}

}  // namespace ssl_formation::predictor::web
