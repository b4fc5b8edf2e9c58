// A standing robot is forecast where it stands, whatever its rows' mean displacement says, and
// its cell probability is calibrated apart from the moving robots': hand-built tables whose
// standing robots mostly stay and sometimes set off.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "hand_built_motion.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/base/state.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"

namespace ssl_formation {
namespace {

const Grid& grid = testing::hand_built_grid;  // 6 x 4 cells of 1.5 m
const FieldSize& field = testing::hand_built_field;

// A robot that has stood a second, in running play.
std::uint32_t standing_context() {
  return MotionFeatures::context(MotionFeatures::standing_context(1.0), 0,
                                 MotionFeatures::game_context(GamePhase::running, 5.0));
}

std::uint32_t moving_context() {
  return MotionFeatures::context(0, 0, MotionFeatures::game_context(GamePhase::running, 5.0));
}

// Robot 3 standing at the centre of its cell, (750, 750); the `n`th instance of it sets off
// 1.5 m along x (into the next cell) three times in ten, and stays the other seven.
MotionInstance standing_instance(int n) {
  MotionInstance i;
  i.robot_id = 3;
  i.x = 750;
  i.y = 750;
  i.d_x = n % 10 < 3 ? 1500 : 0;
  i.context = standing_context();
  return i;
}

// Robot 5 at (-2250, -750) at 2 m/s along x: half a second on it is at the centre of the next
// cell, (-1250, -750), every time the rows learned it; `lands` false: it swerved 1.2 m across
// into another cell instead.
MotionInstance moving_instance(bool lands) {
  MotionInstance i;
  i.robot_id = 5;
  i.x = -2250;
  i.y = -750;
  i.v_x = 2000;
  i.d_x = 1000;
  i.d_y = lands ? 0 : 1200;
  i.context = moving_context();
  return i;
}

// `rows` instances into the rows and `held_out` into the held-out sample, 0.1 s apart from
// `first_s`; `instance(n, held_out)` makes the n-th of each kind.
template <typename Make>
void add(MotionTable& table, int rows, int held_out, double first_s, Make instance) {
  int counted = 0, held = 0;
  for (double t = first_s; counted < rows || held < held_out; t += 0.1) {
    if (table.is_held_out(t)) {
      if (held < held_out) table.add(0, t, instance(held++, true));
    } else if (counted < rows) {
      table.add(0, t, instance(counted++, false));
    }
  }
}

MotionRobot robot_at(std::uint32_t id, Point position, Point velocity, Point to_recent_mean,
                     std::uint32_t context) {
  MotionRobot robot;
  robot.robot_id = id;
  robot.position = position;
  robot.has_velocity = true;
  robot.kinematics.velocity = velocity;
  robot.kinematics.to_recent_mean = to_recent_mean;
  robot.context = context;
  return robot;
}

MotionModel standing_robots_model() {
  MotionTable table(testing::hand_built_config());
  add(table, 2000, 400, 0.0, [](int n, bool) { return standing_instance(n); });
  return MotionModel(table, grid, field);
}

// Held out: the standing robot stays in its cell seven times in ten, as its rows learned; the
// moving one lands in its forecast cell three times in ten, though its rows learned it always
// did.
MotionModel standing_and_moving_robots_model() {
  MotionTable table(testing::hand_built_config());
  add(table, 2000, 400, 0.0, [](int n, bool) { return standing_instance(n); });
  add(table, 2000, 400, 5000.0,
      [](int n, bool held_out) { return moving_instance(!held_out || n % 10 < 3); });
  return MotionModel(table, grid, field);
}

MotionRobot the_standing_robot() { return robot_at(3, {750.0, 750.0}, {}, {}, standing_context()); }

MotionRobot the_moving_robot() {
  return robot_at(5, {-2250.0, -750.0}, {2000.0, 0.0}, {-500.0, 0.0}, moving_context());
}

TEST(StandingRobot, IsForecastWhereItStandsThoughItsRowsHaveSomeSetOff) {
  const MotionModel model = standing_robots_model();
  // The rows' mean: three in ten went 1.5 m on, 450 mm. A creeping robot (150 mm/s across, its
  // sightings 40 mm behind it over the settle window) is forecast by them.
  const MotionForecast creeping = model.forecast(
      0, robot_at(3, {750.0, 750.0}, {0.0, 150.0}, {0.0, -40.0}, standing_context()));
  EXPECT_FALSE(creeping.stays);
  EXPECT_NEAR(creeping.position.x, 750.0 + 450.0, 30.0);
  // A standing one stays: most of its like did, and the median of where they went, which the
  // mean distance is least at, is where it stands.
  for (const Point velocity : {Point{0.0, 0.0}, Point{60.0, -70.0}}) {
    const MotionForecast standing =
        model.forecast(0, robot_at(3, {750.0, 750.0}, velocity, {0.0, 0.0}, standing_context()));
    EXPECT_TRUE(standing.stays);
    EXPECT_DOUBLE_EQ(standing.position.x, 750.0);
    EXPECT_DOUBLE_EQ(standing.position.y, 750.0);
  }
  // So does one seen once (no velocity yet).
  MotionRobot unseen = robot_at(3, {750.0, 750.0}, {}, {}, standing_context());
  unseen.has_velocity = false;
  const MotionForecast first_sighting = model.forecast(0, unseen);
  EXPECT_TRUE(first_sighting.stays);
  EXPECT_DOUBLE_EQ(first_sighting.position.x, 750.0);
}

TEST(StandingRobot, VisionNoiseShakesTheTrackedVelocityButNotTheMeanSighting) {
  const MotionModel model = standing_robots_model();
  const auto forecast = [&](Point velocity, Point to_recent_mean) {
    return model.forecast(
        0, robot_at(3, {750.0, 750.0}, velocity, to_recent_mean, standing_context()));
  };
  // 200 mm/s by its tracker, but its sightings within 5 mm of their mean: it stands.
  EXPECT_TRUE(forecast({200.0, 0.0}, {-4.0, 3.0}).stays);
  // The same speed with its sightings 20 mm behind: it creeps, and the rows forecast it.
  EXPECT_FALSE(forecast({200.0, 0.0}, {-20.0, 0.0}).stays);
  // Faster than the standing speed (250 mm/s), it moves wherever its sightings are.
  EXPECT_FALSE(forecast({300.0, 0.0}, {-4.0, 3.0}).stays);
}

TEST(StandingRobot, OneThatHasStoodASettleWindowIsForecastAtItsMeanSighting) {
  const MotionModel model = standing_robots_model();
  // Stood a second: its mean sighting over the settle window, 6 mm off its last, is its place.
  const MotionForecast settled =
      model.forecast(0, robot_at(3, {750.0, 750.0}, {20.0, 0.0}, {6.0, -3.0}, standing_context()));
  EXPECT_TRUE(settled.stays);
  EXPECT_DOUBLE_EQ(settled.position.x, 756.0);
  EXPECT_DOUBLE_EQ(settled.position.y, 747.0);
  // A mean 30 mm off is more than the vision's noise: the robot stays at its last sighting.
  const MotionForecast drifted =
      model.forecast(0, robot_at(3, {750.0, 750.0}, {50.0, 0.0}, {30.0, 0.0}, standing_context()));
  EXPECT_TRUE(drifted.stays);
  EXPECT_DOUBLE_EQ(drifted.position.x, 750.0);
  // Just stopped (standing under half a second): no settle window yet, the last sighting.
  const std::uint32_t just_stopped =
      MotionFeatures::context(MotionFeatures::standing_context(0.2), 0,
                              MotionFeatures::game_context(GamePhase::running, 5.0));
  const MotionForecast stopped =
      model.forecast(0, robot_at(3, {750.0, 750.0}, {20.0, 0.0}, {6.0, -3.0}, just_stopped));
  EXPECT_TRUE(stopped.stays);
  EXPECT_DOUBLE_EQ(stopped.position.x, 750.0);
}

TEST(StandingRobot, ItsCellProbabilityIsCalibratedApartFromTheMovingRobots) {
  // The moving robot's Gaussian mass is the larger (its rows never strayed), its hit rate the
  // smaller: one map for both would pool them and state about one half for each.
  const MotionModel model = standing_and_moving_robots_model();
  const MotionForecast standing = model.forecast(0, the_standing_robot());
  const MotionForecast moving = model.forecast(0, the_moving_robot());
  ASSERT_TRUE(standing.stays);
  ASSERT_FALSE(moving.stays);
  ASSERT_EQ(grid.cell_of(moving.position, field), grid.cell_of({-1250.0, -750.0}, field));
  EXPECT_GT(
      MotionModel::gaussian_cell_mass(moving, grid, field, grid.cell_of(moving.position, field)),
      MotionModel::gaussian_cell_mass(standing, grid, field,
                                      grid.cell_of(standing.position, field)));
  const auto stated = [&](const MotionForecast& f) {
    return model.cell_probability(0, f, grid, field, grid.cell_of(f.position, field));
  };
  EXPECT_NEAR(stated(standing), 0.7, 0.06);
  EXPECT_NEAR(stated(moving), 0.3, 0.06);
}

TEST(StandingRobot, StayingRobotsCountHalfInTheFormationsProbability) {
  // Robots that stay stay together (a team standing in a stoppage): each counts as the square
  // root of its probability in the product over the team, a moving robot as its own.
  const MotionModel model = standing_and_moving_robots_model();
  const std::vector<MotionRobot> robots{the_standing_robot(), the_moving_robot()};
  Prediction prediction;
  model.predict(robots, 1, StateCodec(grid), field, AttackDirection::positive_x, prediction);
  const std::vector<RobotPrediction>& predicted = prediction.steps.at(0).robots;
  ASSERT_EQ(predicted.size(), 2u);
  EXPECT_TRUE(predicted[0].stays);
  EXPECT_FALSE(predicted[1].stays);
  const double staying = predicted[0].probability, moving = predicted[1].probability;
  ASSERT_GT(staying, 0.5);
  ASSERT_LT(staying, 0.95);
  EXPECT_NEAR(prediction.steps[0].formation_probability, std::sqrt(staying) * moving, 1e-12);
  EXPECT_GT(prediction.steps[0].formation_probability, staying * moving * 1.05);
}

}  // namespace
}  // namespace ssl_formation
