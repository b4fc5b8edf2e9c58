#include "field_markings.hpp"

namespace ssl_formation::predictor::web {

namespace {

// The rules' dimensions (SSL rules, "Field Setup"): goals 1.8 m (A) or 1 m (B) wide and 180 mm
// deep, penalty areas 3.6 x 1.8 m (A) or 2 x 1 m (B), a centre circle of 0.5 m, 0.3 m of
// boundary. Where the divisions' lengths meet is taken half way between them.
constexpr double division_a_from_length_mm = 10500.0;

ViewMarkings rules_markings(const FieldSize& field) {
  const bool division_a = field.length_mm >= division_a_from_length_mm;
  ViewMarkings m;
  m.goal_width_mm = division_a ? 1800.0 : 1000.0;
  m.goal_depth_mm = 180.0;
  m.boundary_width_mm = 300.0;
  m.penalty_area_depth_mm = division_a ? 1800.0 : 1000.0;
  m.penalty_area_width_mm = division_a ? 3600.0 : 2000.0;
  m.center_circle_radius_mm = 500.0;
  m.source = "rules";
  return m;
}

}  // namespace

ViewMarkings markings_for(const FieldSize& field, const std::optional<FieldMarkings>& stated) {
  ViewMarkings m = rules_markings(field);
  if (!stated) return m;
  int taken = 0;
  int left = 0;
  // A stated value replaces the rules' one when it is positive and at most `limit`.
  const auto take = [&](double& value, std::int32_t given, double limit) {
    if (given > 0 && static_cast<double>(given) <= limit) {
      value = given;
      ++taken;
    } else {
      ++left;
    }
  };
  const double half_length = field.length_mm / 2.0;
  take(m.goal_width_mm, stated->goal_width, field.width_mm);
  take(m.goal_depth_mm, stated->goal_depth, half_length);
  take(m.boundary_width_mm, stated->boundary_width, half_length);
  take(m.penalty_area_depth_mm, stated->penalty_area_depth, half_length);
  take(m.penalty_area_width_mm, stated->penalty_area_width, field.width_mm);
  take(m.center_circle_radius_mm, stated->center_circle_radius, field.width_mm / 2.0);
  m.source = left == 0 ? "geometry" : taken == 0 ? "rules" : "geometry and rules";
  return m;
}

}  // namespace ssl_formation::predictor::web
