// The motion model under a prior table (every team's): MotionModel's prior_model, hand-built.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "hand_built_motion.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"

namespace ssl_formation {
namespace {

const Grid& grid = testing::hand_built_grid;
const FieldSize& field = testing::hand_built_field;
MotionConfig config() { return testing::hand_built_config(); }

// Robot 3 at (0, 0) moving at 1 m/s along x, in running play, moved by (dx, 0) half a second
// later.
MotionInstance moving_robot(std::int32_t dx) {
  MotionInstance i;
  i.robot_id = 3;
  i.x = 0;
  i.y = 0;
  i.d_x = dx;
  i.v_x = 1000;
  i.context = MotionFeatures::context(0, 0);
  return i;
}

// `count` instances of moving_robot(dx) counted in rows (none at a held-out time), from
// `first_s` on, 0.1 s apart.
void add(MotionTable& table, int count, std::int32_t dx, double first_s = 0.0) {
  double t = first_s;
  for (int added = 0; added < count; t += 0.1) {
    if (table.is_held_out(t)) continue;
    table.add(0, t, moving_robot(dx));
    ++added;
  }
}

MotionRobot robot() {
  MotionRobot r;
  r.robot_id = 3;
  r.kinematics.velocity = {1000.0, 0.0};
  r.has_velocity = true;
  r.context = MotionFeatures::context(0, 0);
  return r;
}

// Where `table` under `prior` forecasts robot() half a second on, along x.
double forecast_x(const MotionTable& table, const MotionModel* prior) {
  const MotionModel model(table, grid, field, MotionModelSettings{}, prior);
  return model.forecast(0, robot()).position.x;
}

TEST(MotionPrior, ANewOpponentIsForecastFromThePriorAndItsOwnRowsTakeOverAsTheyFill) {
  // Every team's robots in that state went 400 mm on; this opponent's go 400 mm back.
  MotionTable every_team(config());
  add(every_team, 3000, 400);
  const MotionModel prior(every_team, grid, field);
  EXPECT_NEAR(prior.forecast(0, robot()).position.x, 400.0, 5.0);

  // No row of its own: the prior's forecast.
  const MotionTable nothing(config());
  EXPECT_NEAR(forecast_x(nothing, &prior), 400.0, 5.0);
  // Without the prior, an empty table is damped constant velocity (1 m/s braking).
  EXPECT_LT(forecast_x(nothing, nullptr), 400.0);
  EXPECT_GT(forecast_x(nothing, nullptr), 200.0);

  // As many instances as a row's shrinkage (60): halfway between the two.
  const double shrinkage = MotionModelSettings{}.shrinkage;
  const auto own_with = [&](int count) {
    MotionTable own(config());
    add(own, count, -400, 10'000.0);
    return forecast_x(own, &prior);
  };
  EXPECT_NEAR(own_with(static_cast<int>(shrinkage)), 0.0, 10.0);
  // The own rows' share grows with their count: n / (n + 60) of the way to -400.
  double last = 400.0;
  for (const int count : {10, 60, 240, 960, 6000}) {
    const double x = own_with(count);
    const double expected = 400.0 * (shrinkage - count) / (shrinkage + count);
    EXPECT_NEAR(x, expected, 12.0) << count;
    EXPECT_LT(x, last) << count;
    last = x;
  }
  EXPECT_LT(last, -380.0);
}

TEST(MotionPrior, APriorOfOtherSettingsIsRefused) {
  MotionConfig other = config();
  other.step_s = 0.25;
  MotionTable every_team(other);
  add(every_team, 100, 400);
  const MotionModel prior(every_team, grid, field);
  const MotionTable own(config());
  EXPECT_THROW(MotionModel(own, grid, field, MotionModelSettings{}, &prior), std::invalid_argument);
}

TEST(MotionPrior, ATableUnderAPriorMergesAndReloadsExactly) {
  MotionTable every_team(config());
  add(every_team, 2000, 400);
  add(every_team, 500, 150, 500.0);
  const MotionModel prior(every_team, grid, field);

  // Two halves of a scouting, learned apart, merged, saved and loaded again...
  MotionTable first(config()), second(config()), both(config());
  add(first, 40, -400, 1000.0);
  add(second, 70, -250, 2000.0);
  add(both, 40, -400, 1000.0);
  add(both, 70, -250, 2000.0);
  MotionTable merged = first;
  merged.merge(second);
  ASSERT_EQ(merged, both);

  testing::ScratchDir dir;
  const auto path = dir.path() / "opponent.bin";
  const TableMetadata metadata{field, 0.5, 110};
  ASSERT_TRUE(save_table(path, TransitionTable(grid), metadata, merged));
  const auto loaded = load_table(path, grid);
  ASSERT_TRUE(loaded) << loaded.error().message;
  ASSERT_TRUE(loaded->motion);
  EXPECT_EQ(*loaded->motion, both);

  // ...forecast exactly as the table trained on both at once, under the same prior.
  const MotionModel reloaded(*loaded->motion, grid, field, MotionModelSettings{}, &prior);
  const MotionModel trained(both, grid, field, MotionModelSettings{}, &prior);
  for (const double vx : {0.0, 300.0, 1000.0, 2000.0}) {
    MotionRobot r = robot();
    r.kinematics.velocity = {vx, 0.0};
    const MotionForecast a = reloaded.forecast(0, r);
    const MotionForecast b = trained.forecast(0, r);
    EXPECT_EQ(a.position.x, b.position.x) << vx;
    EXPECT_EQ(a.position.y, b.position.y) << vx;
    EXPECT_EQ(a.mean_square_mm2, b.mean_square_mm2) << vx;
    EXPECT_EQ(a.radius90_mm, b.radius90_mm) << vx;
  }
}

}  // namespace
}  // namespace ssl_formation
