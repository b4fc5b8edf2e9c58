// The training side of the motion model (common/src/motion_model.cpp): whole_mm's rounding, on
// which every learned row depends, kept bit for bit through its speed-ups.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "ssl_formation/motion_model.hpp"

namespace sf = ssl_formation;

namespace {

// whole_mm as tables up to now were trained with: clamped to +-1e9, then half a millimetre added
// or taken away by the sign and truncated. Not std::round: 0.49999999999999994 + 0.5 is 1.0 in
// doubles, so this gives 1 where std::round gives 0.
std::int32_t whole_mm_as_trained(double value) {
  const double clamped = std::clamp(value, -1.0e9, 1.0e9);
  return static_cast<std::int32_t>(clamped < 0.0 ? clamped - 0.5 : clamped + 0.5);
}

TEST(MotionWholeMm, RoundsEveryValueAsTablesWereTrained) {
  std::vector<double> values{0.0,
                             -0.0,
                             0.5,
                             -0.5,
                             1.5,
                             -1.5,
                             2.5,
                             -2.5,
                             0.49999999999999994,
                             -0.49999999999999994,
                             std::nextafter(0.5, 0.0),
                             std::nextafter(-0.5, 0.0),
                             std::nextafter(1.5, 2.0),
                             std::nextafter(-1.5, -2.0),
                             4503599627370495.5,
                             1.0e9,
                             -1.0e9,
                             1.0e9 - 0.5,
                             -1.0e9 + 0.5,
                             1.0e12,
                             -1.0e12,
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::denorm_min(),
                             -std::numeric_limits<double>::denorm_min()};
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> mm(-5000.0, 5000.0);
  for (int i = 0; i < 100000; ++i) values.push_back(mm(random));
  for (int i = -2000; i <= 2000; ++i) values.push_back(i / 4.0);  // every half and quarter
  for (const double value : values) {
    EXPECT_EQ(sf::whole_mm(value), whole_mm_as_trained(value)) << value;
  }
}

}  // namespace
