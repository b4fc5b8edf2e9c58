#pragma once
// What the field view draws besides the field's outline: goals, penalty areas, the centre circle
// and the boundary, in millimetres. From the feed's geometry packet where it states them and they
// fit the field in use; else from the rules for the field's division (a tracker's feed carries no
// geometry, and older senders leave the penalty area out).

#include <optional>
#include <string_view>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/vision/vision_frame.hpp"

namespace ssl_formation::predictor::web {

struct ViewMarkings {
  double goal_width_mm = 0.0;
  double goal_depth_mm = 0.0;
  double boundary_width_mm = 0.0;
  double penalty_area_depth_mm = 0.0;
  double penalty_area_width_mm = 0.0;
  double center_circle_radius_mm = 0.0;
  // "geometry" when every value came from the feed's packet, "rules" when none did, "geometry
  // and rules" for a packet that states some.
  std::string_view source = "rules";
  friend bool operator==(const ViewMarkings&, const ViewMarkings&) = default;
};

// The markings of `field`: the stated ones that fit it (positive, a goal no wider and a penalty
// area no wider or deeper than the field allows), the rules' for the rest (rules_markings in
// vision_packet.hpp, which ssl-producer's geometry states too).
ViewMarkings markings_for(const FieldSize& field, const std::optional<FieldMarkings>& stated);

}  // namespace ssl_formation::predictor::web
