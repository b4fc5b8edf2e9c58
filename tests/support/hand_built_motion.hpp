#pragma once
// What the motion model's hand-built tests share: a table of one 0.5 s step, and the grid and
// field its calibration is worked out for.

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation::testing {

inline const Grid hand_built_grid(6, 4);
inline const FieldSize hand_built_field{9000.0, 6000.0};

inline MotionConfig hand_built_config() {
  MotionConfig c;
  c.step_s = 0.5;
  c.horizons = 1;
  return c;
}

}  // namespace ssl_formation::testing
