// The motion model: features, counting, back-off, the worked example of a position and its radii,
// calibration, and the pipeline predicting with it.
#include "ssl_formation/motion_model/motion_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <set>

#include "ssl_formation/motion_model/motion_predictor.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace sf = ssl_formation;

namespace {

const sf::Grid grid{12, 9};
const sf::FieldSize field{12000.0, 9000.0};

sf::MotionConfig one_second(int horizons = 1) {
  sf::MotionConfig config;
  config.step_s = 1.0;
  config.horizons = horizons;
  return config;
}

// A row of `count` instances of a robot moving at `velocity`, each displaced by `d`.
sf::MotionRow row_of(int count, sf::Point velocity, sf::Point d, double horizon_s = 1.0) {
  sf::MotionRow row;
  sf::MotionKinematics kinematics;
  kinematics.velocity = velocity;
  const sf::MotionRegressors x = sf::motion_regressors_of(kinematics, horizon_s);
  std::array<std::array<std::int64_t, 2>, sf::motion_regressors> whole{};
  for (int i = 0; i < sf::motion_regressors; ++i) {
    whole[i] = {sf::whole_mm(x[i].x), sf::whole_mm(x[i].y)};
  }
  for (int i = 0; i < count; ++i) row.add({sf::whole_mm(d.x), sf::whole_mm(d.y)}, whole);
  return row;
}

sf::MotionKey key_of(std::uint32_t robot_id, sf::Point position, sf::Point velocity,
                     sf::MotionLevel level = sf::MotionLevel::robot) {
  sf::MotionKeyParts parts;
  parts.level = level;
  parts.robot_slot = sf::MotionFeatures::robot_slot(robot_id);
  parts.cell = sf::MotionFeatures::cell(position);
  parts.velocity_class = sf::MotionFeatures::velocity_class(velocity);
  return sf::encode_motion_key(parts);
}

sf::MotionRobot moving_robot(std::uint32_t id, sf::Point position, sf::Point velocity) {
  sf::MotionRobot robot;
  robot.robot_id = id;
  robot.position = position;
  robot.kinematics.velocity = velocity;
  robot.has_velocity = true;
  return robot;
}

}  // namespace

TEST(MotionFeatures, VelocityClassesSplitSpeedIntoBandsAndDirectionIntoEightSectors) {
  EXPECT_EQ(sf::MotionFeatures::velocity_class({0.0, 0.0}), 0);
  EXPECT_EQ(sf::MotionFeatures::velocity_class({200.0, 100.0}), 0);   // under 250 mm/s: standing
  EXPECT_EQ(sf::MotionFeatures::velocity_class({500.0, 0.0}), 1);     // band 1, +x
  EXPECT_EQ(sf::MotionFeatures::velocity_class({0.0, 500.0}), 3);     // band 1, +y
  EXPECT_EQ(sf::MotionFeatures::velocity_class({-500.0, 0.0}), 5);    // band 1, -x
  EXPECT_EQ(sf::MotionFeatures::velocity_class({400.0, -400.0}), 8);  // band 1, +x-y
  EXPECT_EQ(sf::MotionFeatures::velocity_class({1000.0, 0.0}), 9);    // band 2
  EXPECT_EQ(sf::MotionFeatures::velocity_class({2000.0, 0.0}), 17);   // band 3
  EXPECT_LT(sf::MotionFeatures::velocity_class({-3000.0, -3000.0}),
            sf::MotionFeatures::velocity_classes);
}

TEST(MotionFeatures, CellsCoverTheFieldWithItsBoundaryAndClampBeyond) {
  EXPECT_EQ(sf::MotionFeatures::cell({-7000.0, -5000.0}), 0);
  EXPECT_EQ(sf::MotionFeatures::cell({-99999.0, -99999.0}), 0);
  EXPECT_EQ(sf::MotionFeatures::cell({99999.0, 99999.0}), sf::MotionFeatures::cell_count - 1);
  EXPECT_NE(sf::MotionFeatures::cell({0.0, 0.0}), sf::MotionFeatures::cell({600.0, 0.0}));
}

TEST(MotionFeatures, ZonesSplitTheLengthInQuartersAndTheWidthInACentreLaneAndTwoWings) {
  const auto zone = [](double x, double y) {
    return sf::MotionFeatures::zone_of_cell(sf::MotionFeatures::cell({x, y}));
  };
  // Cells 3 m apart or less in one zone share it; across an edge they do not.
  EXPECT_EQ(zone(250.0, -1250.0), zone(2750.0, 1250.0));
  EXPECT_NE(zone(-250.0, 0.0), zone(250.0, 0.0));         // the halfway line
  EXPECT_NE(zone(2750.0, 0.0), zone(3250.0, 0.0));        // a quarter of the length
  EXPECT_NE(zone(1000.0, 1250.0), zone(1000.0, 1750.0));  // the centre lane and a wing
  EXPECT_NE(zone(1000.0, -1250.0), zone(1000.0, -1750.0));
  // The edge zones reach beyond the field; every zone is numbered below zone_count.
  EXPECT_EQ(zone(-99999.0, -99999.0), zone(-3250.0, -1750.0));
  EXPECT_EQ(zone(99999.0, 99999.0), sf::MotionFeatures::zone_count - 1);
  std::set<int> zones;
  for (int cell = 0; cell < sf::MotionFeatures::cell_count; ++cell) {
    zones.insert(sf::MotionFeatures::zone_of_cell(cell));
  }
  EXPECT_EQ(zones.size(), static_cast<std::size_t>(sf::MotionFeatures::zone_count));
  EXPECT_EQ(*zones.rbegin(), sf::MotionFeatures::zone_count - 1);
}

TEST(MotionFeatures, TheContextTellsTheStandingTimeAndTheTeamPhaseApart) {
  const sf::Point still{100.0, -100.0}, moving{0.0, 300.0};
  // The edges: 1 m either side of the halfway line, and 250 mm/s (the first speed limit).
  EXPECT_EQ(sf::MotionFeatures::team_phase({-1000.0, 0.0}, {249.0, 0.0}), 2);
  EXPECT_EQ(sf::MotionFeatures::team_phase({-1000.1, 0.0}, {250.0, 0.0}), 1);
  EXPECT_EQ(sf::MotionFeatures::team_phase({1000.0, 0.0}, {0.0, -250.0}), 3);
  EXPECT_EQ(sf::MotionFeatures::team_phase({1000.1, 0.0}, {0.0, 0.0}), 4);
  EXPECT_EQ(sf::MotionFeatures::team_phase({-1500.0, 0.0}, still), 0);  // back in its own half
  EXPECT_EQ(sf::MotionFeatures::team_phase({-1500.0, 0.0}, moving), 1);
  EXPECT_EQ(sf::MotionFeatures::team_phase({-900.0, 2000.0}, still), 2);  // about the halfway line
  EXPECT_EQ(sf::MotionFeatures::team_phase({900.0, -2000.0}, still), 2);
  EXPECT_EQ(sf::MotionFeatures::team_phase({900.0, -2000.0}, {-260.0, 0.0}), 3);
  EXPECT_EQ(sf::MotionFeatures::team_phase({1500.0, 0.0}, still), 4);  // into the half it attacks
  EXPECT_EQ(sf::MotionFeatures::team_phase({1500.0, 0.0}, moving), 5);
  std::set<std::uint32_t> contexts;
  for (const bool flying : {false, true}) {
    for (std::uint32_t game = 0; game < sf::MotionFeatures::game_contexts; ++game) {
      for (int phase = 0; phase < sf::MotionFeatures::team_phases; ++phase) {
        for (std::uint32_t standing = 0; standing < sf::MotionFeatures::standing_contexts;
             ++standing) {
          const std::uint32_t context = sf::MotionFeatures::context(standing, phase, game, flying);
          contexts.insert(context);
          EXPECT_EQ(sf::MotionFeatures::game_context_of(context), game);
          EXPECT_EQ(sf::MotionFeatures::ball_in_flight_of(context), flying);
        }
      }
    }
  }
  EXPECT_EQ(contexts.size(), sf::MotionFeatures::context_count);
  EXPECT_EQ(*contexts.rbegin(), sf::MotionFeatures::context_count - 1);
  // Running play with the ball at rest keeps the contexts of tables learned before the game's
  // states and the ball came in.
  EXPECT_EQ(sf::MotionFeatures::context(4, 5), 29u);
  EXPECT_EQ(sf::MotionFeatures::context(4, 5, sf::MotionFeatures::running_game, false), 29u);
  // In flight from 1 m/s on, in any direction.
  EXPECT_FALSE(sf::MotionFeatures::ball_in_flight({999.0, 0.0}));
  EXPECT_TRUE(sf::MotionFeatures::ball_in_flight({0.0, -1000.0}));
  EXPECT_TRUE(sf::MotionFeatures::ball_in_flight({-800.0, 600.0}));
  EXPECT_FALSE(sf::MotionFeatures::ball_in_flight({}));
  EXPECT_EQ(sf::MotionFeatures::standing_context(99.0), sf::MotionFeatures::standing_contexts - 1);
}

TEST(MotionFeatures, EveryGamePhaseAndTimeSinceItsCommandHasItsOwnGameContext) {
  using sf::GamePhase;
  EXPECT_EQ(sf::MotionFeatures::game_context(GamePhase::running, 0.2),
            sf::MotionFeatures::running_game);
  EXPECT_EQ(sf::MotionFeatures::game_context(GamePhase::running, 30.0),
            sf::MotionFeatures::running_game);
  EXPECT_EQ(sf::MotionFeatures::game_context(GamePhase::halt, 0.1), sf::MotionFeatures::halt_game);
  EXPECT_EQ(sf::MotionFeatures::game_context(GamePhase::halt, 9.0), sf::MotionFeatures::halt_game);
  std::set<std::uint32_t> seen{sf::MotionFeatures::running_game, sf::MotionFeatures::halt_game};
  for (const GamePhase phase : sf::all_game_phases) {
    if (phase == GamePhase::running || phase == GamePhase::halt) continue;
    const std::uint32_t early = sf::MotionFeatures::game_context(phase, 0.0);
    // 1 s and 3 s since the command are the edges.
    EXPECT_EQ(sf::MotionFeatures::game_context(phase, 0.999), early);
    EXPECT_EQ(sf::MotionFeatures::game_context(phase, 1.0), early + 1);
    EXPECT_EQ(sf::MotionFeatures::game_context(phase, 2.999), early + 1);
    EXPECT_EQ(sf::MotionFeatures::game_context(phase, 3.0), early + 2);
    EXPECT_EQ(sf::MotionFeatures::game_context(phase, std::numeric_limits<double>::infinity()),
              early + 2);
    for (std::uint32_t g = early; g < early + 3; ++g) {
      EXPECT_TRUE(seen.insert(g).second) << sf::to_string(phase);
      EXPECT_EQ(sf::MotionFeatures::phase_of_game_context(g), phase);
    }
  }
  EXPECT_EQ(seen.size(), sf::MotionFeatures::game_contexts);
  EXPECT_EQ(*seen.rbegin(), sf::MotionFeatures::game_contexts - 1);
}

TEST(MotionKey, EachLevelKeepsItsFeaturesAndTheCoarserKeyDropsThem) {
  const sf::MotionKey robot = key_of(3, {1000.0, 500.0}, {1000.0, 0.0});
  const sf::MotionKeyParts parts = sf::decode_motion_key(robot);
  EXPECT_EQ(parts.level, sf::MotionLevel::robot);
  EXPECT_EQ(parts.robot_slot, 3);
  const sf::MotionKeyParts zone = sf::decode_motion_key(sf::coarser_motion_key(robot));
  EXPECT_EQ(zone.level, sf::MotionLevel::zone);
  EXPECT_EQ(zone.robot_slot, 0);
  EXPECT_EQ(zone.cell, sf::MotionFeatures::zone_of_cell(parts.cell));
  EXPECT_EQ(zone.velocity_class, parts.velocity_class);
  const sf::MotionKeyParts velocity =
      sf::decode_motion_key(sf::coarser_motion_key(sf::coarser_motion_key(robot)));
  EXPECT_EQ(velocity.level, sf::MotionLevel::velocity);
  EXPECT_EQ(velocity.cell, 0);
  EXPECT_EQ(velocity.velocity_class, parts.velocity_class);
}

TEST(MotionModel, AnEmptyTablePredictsDampedConstantVelocity) {
  const sf::MotionTable table(one_second(2));
  const sf::MotionModelSettings settings;
  const sf::MotionModel model(table, grid, field, settings);
  const sf::MotionRobot robot = moving_robot(1, {0.0, 0.0}, {1000.0, 0.0});
  for (int h = 0; h < 2; ++h) {
    const double horizon_s = h + 1.0;
    const double tau = settings.prior_time_constant_s;
    const double damping = tau / horizon_s * (1.0 - std::exp(-horizon_s / tau));
    const sf::MotionForecast f = model.forecast(h, robot);
    EXPECT_NEAR(f.position.x, damping * 1000.0 * horizon_s, 1e-9) << "horizon " << horizon_s;
    EXPECT_NEAR(f.position.y, 0.0, 1e-9);
    EXPECT_FALSE(f.from_counts);
    // Gaussian radii from the prior spread.
    const double rms = settings.prior_error_mm + settings.prior_error_mm_per_s * horizon_s;
    EXPECT_NEAR(f.radius50_mm, std::sqrt(std::log(2.0)) * rms, 1e-6);
    EXPECT_NEAR(f.radius90_mm, std::sqrt(std::log(10.0)) * rms, 1e-6);
  }
}

TEST(MotionModel, BeyondTheLearnedStepsAnAdviceCountsOnceAtItsWeight) {
  // An empty table of one learned 1 s step: 1 m/s along x, damped by k(1) then extrapolated
  // linearly. A set play's advice puts the robot at (0, 1000) at every step, at weight 0.5.
  const sf::MotionTable table(one_second(1));
  const sf::MotionModelSettings settings;
  const sf::MotionModel model(table, grid, field, settings);
  const double tau = settings.prior_time_constant_s;
  const double first = tau * (1.0 - std::exp(-1.0 / tau)) * 1000.0;  // k(1) x 1000 mm
  sf::SetPlayAdvice advice;
  advice.robots.resize(1);
  for (std::size_t k = 0; k < 3; ++k) {
    advice.robots[0].position[k] = {0.0, 1000.0};
    advice.robots[0].weight[k] = 0.5;
  }
  advice.any = true;
  sf::Prediction prediction;
  sf::MotionModel::Cache cache;
  model.predict({moving_robot(1, {0.0, 0.0}, {1000.0, 0.0})}, 3, sf::StateCodec(grid), field,
                sf::AttackDirection::positive_x, prediction, cache, {}, &advice);
  ASSERT_EQ(prediction.steps.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    // The rows' forecast (k + 1) x k(1) x 1000 mm along x, then half way to the advice: the
    // advice of an earlier step does not carry into a later one.
    const sf::Point p = prediction.steps[k].robots.at(0).normalised_position;
    EXPECT_NEAR(p.x, 0.5 * (k + 1) * first, 1e-6) << k;
    EXPECT_NEAR(p.y, 500.0, 1e-6) << k;
  }
}

TEST(MotionRow, ARowWithoutARegressorIsTheRowOfItsInstancesWithThatRegressorZero) {
  std::mt19937 random(7);
  std::uniform_int_distribution<std::int64_t> mm(-3000, 3000);
  for (int without = 0; without < sf::motion_regressors; ++without) {
    sf::MotionRow all, zeroed;
    for (int n = 0; n < 50; ++n) {
      const std::array<std::int64_t, 2> d{mm(random), mm(random)};
      std::array<std::array<std::int64_t, 2>, sf::motion_regressors> x{};
      for (auto& regressor : x) regressor = {mm(random), mm(random)};
      all.add(d, x);
      x[static_cast<std::size_t>(without)] = {0, 0};
      zeroed.add(d, x);
    }
    EXPECT_EQ(all.without_regressor(without), zeroed) << "regressor " << without;
    EXPECT_NE(all, zeroed);
  }
}

TEST(MotionModel, WorkedExampleOfAPositionAndItsRadii) {
  // One robot at (1000, 500) moving at 1 m/s along +x: half the time it went 400 mm in the next
  // second, half the time 600 mm. With no shrinkage the row predicts the mean, 500 mm ahead, and
  // its spread is 100 mm root-mean-square; without held-out data the radii are a 2-D Gaussian's.
  sf::MotionTable table(one_second());
  const sf::Point position{1000.0, 500.0}, velocity{1000.0, 0.0};
  sf::MotionRow row = row_of(500, velocity, {400.0, 0.0});
  row.add(row_of(500, velocity, {600.0, 0.0}));
  table.add_row(key_of(4, position, velocity), row);
  sf::MotionModelSettings exact;
  exact.shrinkage = 1e-9;
  const sf::MotionModel model(table, grid, field, exact);

  const sf::MotionForecast f = model.forecast(0, moving_robot(4, position, velocity));
  EXPECT_EQ(f.level, sf::MotionLevel::robot);
  EXPECT_NEAR(f.position.x, 1500.0, 1e-3);
  EXPECT_NEAR(f.position.y, 500.0, 1e-3);
  EXPECT_NEAR(f.mean_square_mm2, 100.0 * 100.0, 1e-2);
  EXPECT_NEAR(f.radius50_mm, 100.0 * std::sqrt(std::log(2.0)), 1e-3);   // 83.3 mm
  EXPECT_NEAR(f.radius90_mm, 100.0 * std::sqrt(std::log(10.0)), 1e-3);  // 151.7 mm

  // Through predict(): the same position in the feed's coordinates, rotated back for an opponent
  // attacking -x, its cell and the state built from it.
  sf::Prediction prediction;
  const sf::StateCodec codec(grid);
  model.predict({moving_robot(4, position, velocity)}, 1, codec, field,
                sf::AttackDirection::negative_x, prediction);
  ASSERT_EQ(prediction.steps.size(), 1u);
  const sf::RobotPrediction& p = prediction.steps[0].robots.at(0);
  EXPECT_EQ(p.robot_id, 4u);
  EXPECT_NEAR(p.feed_position.x, -1500.0, 1e-3);
  EXPECT_NEAR(p.feed_position.y, -500.0, 1e-3);
  EXPECT_EQ(p.position, grid.cell_of({1500.0, 500.0}, field));
  EXPECT_EQ(p.previous, grid.cell_of(position, field));
  EXPECT_NEAR(p.radius90_mm, f.radius90_mm, 1e-9);
  EXPECT_GT(p.probability, 0.0);
  EXPECT_LE(p.probability, 1.0);
}

TEST(MotionModel, ARichRowWithFewCountsDefersToTheCoarserRow) {
  const sf::Point position{-2000.0, 1000.0}, velocity{1000.0, 0.0};
  // Robot 2 in this cell and velocity class stopped dead (displacement 0), thousands of times;
  // robot 7 was seen twice going 800 mm sideways.
  sf::MotionTable table(one_second());
  table.add_row(key_of(2, position, velocity), row_of(5000, velocity, {0.0, 0.0}));
  const sf::MotionRow rare = row_of(2, velocity, {0.0, 800.0});
  table.add_row(key_of(7, position, velocity), rare);
  const sf::MotionModel model(table, grid, field);

  const sf::MotionForecast few = model.forecast(0, moving_robot(7, position, velocity));
  EXPECT_EQ(few.level, sf::MotionLevel::robot);
  // Two instances against a shrinkage of 60: the robot's own row barely moves the forecast off
  // the zone's (every robot's there, which says: it stops).
  EXPECT_LT(std::abs(few.position.y - position.y), 50.0);
  EXPECT_LT(std::abs(few.position.x - position.x), 50.0);

  // With thousands of its own instances the robot's row wins.
  sf::MotionTable rich(one_second());
  rich.add_row(key_of(2, position, velocity), row_of(5000, velocity, {0.0, 0.0}));
  rich.add_row(key_of(7, position, velocity), row_of(20000, velocity, {0.0, 800.0}));
  const sf::MotionModel rich_model(rich, grid, field);
  const sf::MotionForecast many = rich_model.forecast(0, moving_robot(7, position, velocity));
  EXPECT_NEAR(many.position.y - position.y, 800.0, 20.0);

  // A robot never seen in that cell gets the zone's row (every robot's in the 3 m zone): it
  // stops.
  const sf::MotionForecast stranger = model.forecast(0, moving_robot(9, position, velocity));
  EXPECT_EQ(stranger.level, sf::MotionLevel::zone);
  EXPECT_LT(std::hypot(stranger.position.x - position.x, stranger.position.y - position.y), 30.0);

  // So does a robot in another cell of the same zone, 2.5 m away: it stops too.
  const sf::Point same_zone{-500.0, -1000.0};
  ASSERT_NE(sf::MotionFeatures::cell(same_zone), sf::MotionFeatures::cell(position));
  ASSERT_EQ(sf::MotionFeatures::zone_of_cell(sf::MotionFeatures::cell(same_zone)),
            sf::MotionFeatures::zone_of_cell(sf::MotionFeatures::cell(position)));
  const sf::MotionForecast neighbour = model.forecast(0, moving_robot(2, same_zone, velocity));
  EXPECT_EQ(neighbour.level, sf::MotionLevel::zone);
  EXPECT_LT(std::hypot(neighbour.position.x - same_zone.x, neighbour.position.y - same_zone.y),
            30.0);

  // Elsewhere on the field only the velocity class is known.
  const sf::MotionForecast far = model.forecast(0, moving_robot(9, {4000.0, -3000.0}, velocity));
  EXPECT_EQ(far.level, sf::MotionLevel::velocity);
}

TEST(MotionModel, ThePooledAblationForecastsEveryRobotFromOneFitOfAllItsInstances) {
  // Robot 2 in one cell always went 800 mm sideways, robot 7 in another always stopped, as
  // many times: the keyed model follows each, the pooled one gives both the fit of all of them.
  const sf::Point here{-2000.0, 1000.0}, there{3000.0, -2500.0}, velocity{1000.0, 0.0};
  sf::MotionTable table(one_second());
  table.add_row(key_of(2, here, velocity), row_of(20000, velocity, {0.0, 800.0}));
  table.add_row(key_of(7, there, velocity), row_of(20000, velocity, {0.0, 0.0}));
  const sf::MotionModel keyed(table, grid, field);
  sf::MotionModelSettings settings;
  settings.pooled = true;
  const sf::MotionModel pooled(table, grid, field, settings);

  const sf::MotionForecast keyed_2 = keyed.forecast(0, moving_robot(2, here, velocity));
  const sf::MotionForecast keyed_7 = keyed.forecast(0, moving_robot(7, there, velocity));
  EXPECT_NEAR(keyed_2.position.y - here.y, 800.0, 20.0);
  EXPECT_NEAR(keyed_7.position.y - there.y, 0.0, 20.0);

  const sf::MotionForecast pooled_2 = pooled.forecast(0, moving_robot(2, here, velocity));
  const sf::MotionForecast pooled_7 = pooled.forecast(0, moving_robot(7, there, velocity));
  EXPECT_EQ(pooled_2.level, sf::MotionLevel::all);
  // Both moved as the fit of all 40,000 says, whatever their rows: the same displacement.
  EXPECT_NEAR(pooled_2.position.x - here.x, pooled_7.position.x - there.x, 1e-6);
  EXPECT_NEAR(pooled_2.position.y - here.y, pooled_7.position.y - there.y, 1e-6);
  EXPECT_GT(pooled_2.position.y - here.y, 100.0);  // half of them went sideways
  EXPECT_LT(pooled_2.position.y - here.y, 700.0);
}

// Every value of two predictions, compared exactly.
void expect_same_prediction(const sf::Prediction& a, const sf::Prediction& b) {
  ASSERT_EQ(a.steps.size(), b.steps.size());
  for (std::size_t k = 0; k < a.steps.size(); ++k) {
    const sf::PredictedStep& x = a.steps[k];
    const sf::PredictedStep& y = b.steps[k];
    EXPECT_EQ(x.centroid, y.centroid);
    EXPECT_EQ(x.centroid_probability, y.centroid_probability);
    EXPECT_EQ(x.formation_probability, y.formation_probability);
    EXPECT_EQ(x.confidence, y.confidence);
    ASSERT_EQ(x.robots.size(), y.robots.size());
    for (std::size_t r = 0; r < x.robots.size(); ++r) {
      const sf::RobotPrediction& p = x.robots[r];
      const sf::RobotPrediction& q = y.robots[r];
      EXPECT_EQ(p.robot_id, q.robot_id);
      EXPECT_EQ(p.state, q.state);
      EXPECT_EQ(p.position, q.position);
      EXPECT_EQ(p.probability, q.probability);
      EXPECT_EQ(p.unseen, q.unseen);
      EXPECT_EQ(p.feed_position.x, q.feed_position.x);
      EXPECT_EQ(p.feed_position.y, q.feed_position.y);
      EXPECT_EQ(p.radius50_mm, q.radius50_mm);
      EXPECT_EQ(p.radius90_mm, q.radius90_mm);
      EXPECT_EQ(p.mean_square_mm2, q.mean_square_mm2);
    }
  }
}

TEST(MotionModel, PredictingThroughACacheGivesTheSameValuesFrameAfterFrame) {
  // Two models of two horizons: robot 7's own row in one, only the cell's in the other.
  const sf::Point position{-2000.0, 1000.0}, velocity{1000.0, 0.0};
  sf::MotionTable table(one_second(2));
  sf::MotionTable other(one_second(2));
  for (int h = 0; h < 2; ++h) {
    const sf::MotionKey horizon_bits =
        sf::encode_motion_key({h, sf::MotionLevel::robot, 0, 0, 0, 0});
    const double horizon_s = h + 1.0;
    table.add_row(key_of(2, position, velocity) | horizon_bits,
                  row_of(5000, velocity, {0.0, 0.0}, horizon_s));
    table.add_row(key_of(7, position, velocity) | horizon_bits,
                  row_of(20000, velocity, {0.0, 800.0 * horizon_s}, horizon_s));
    other.add_row(key_of(2, position, velocity) | horizon_bits,
                  row_of(5000, velocity, {300.0, 0.0}, horizon_s));
  }
  const sf::MotionModel model(table, grid, field);
  const sf::MotionModel other_model(other, grid, field);
  const sf::StateCodec codec(grid);

  // Frames in which robots keep their keys, change cell or velocity class, stand, and share a
  // robot slot (ids 16 and 20); horizons within and beyond the learned two; then the other model
  // through the same cache.
  sf::MotionModel::Cache cache;
  sf::Prediction cached, direct;
  for (int frame = 0; frame < 40; ++frame) {
    const double shift = frame < 10 ? 10.0 * frame : 600.0 * (frame % 3);
    std::vector<sf::MotionRobot> robots{
        moving_robot(7, {position.x + shift, position.y}, velocity),
        moving_robot(2, position, frame % 5 == 0 ? sf::Point{0.0, -900.0} : velocity),
        moving_robot(16, {position.x, position.y - shift}, velocity),
        moving_robot(20, position, velocity)};
    sf::MotionRobot standing;
    standing.robot_id = 3;
    standing.position = {500.0 + shift, -800.0};
    standing.context = static_cast<std::uint32_t>(frame % 4);
    robots.push_back(standing);
    const sf::MotionModel& used = frame < 30 ? model : other_model;
    const int horizon = frame % 7 == 0 ? 4 : 2;
    used.predict(robots, horizon, codec, field, sf::AttackDirection::negative_x, cached, cache);
    used.predict(robots, horizon, codec, field, sf::AttackDirection::negative_x, direct);
    SCOPED_TRACE(frame);
    expect_same_prediction(cached, direct);
  }
}

TEST(MotionModel, HeldOutInstancesCalibrateTheRadii) {
  // Every instance: a robot standing still that then moved 300 mm in a random direction. The
  // model's rows say "it moves about 300 mm, mean displacement 0", so its rms is 300 mm; the
  // held-out sample shows every robot exactly 300 mm away: the calibrated 50% and 90% radii are
  // both 300 mm, where a Gaussian would say 250 and 455.
  sf::MotionConfig config = one_second();
  config.calibration_one_in = 2;  // half the blocks held out, for a fast test
  sf::MotionTable table(config);
  std::uint32_t id = 0;
  for (int i = 0; i < 4000; ++i) {
    const double angle = 0.001 + i * 2.399963;  // golden angle: directions spread evenly
    sf::MotionInstance instance;
    instance.robot_id = id++ % 11;
    instance.x = 0;
    instance.y = 0;
    instance.d_x = sf::whole_mm(300.0 * std::cos(angle));
    instance.d_y = sf::whole_mm(300.0 * std::sin(angle));
    table.add(0, i * 0.37, instance);
  }
  ASSERT_GT(table.held_out(), 500u);
  ASSERT_GT(table.instances(), 500u);
  const sf::MotionModel model(table, grid, field);
  const sf::MotionForecast f = model.forecast(0, moving_robot(3, {0.0, 0.0}, {0.0, 0.0}));
  EXPECT_NEAR(f.radius50_mm, 300.0, 15.0);
  EXPECT_NEAR(f.radius90_mm, 300.0, 15.0);
}

// Rows live in blocks of a few thousand: past a block's end, and in a copy that grows on its
// own, every row keeps its number, its key and its sums.
TEST(MotionRowMap, RowsKeepNumberKeyAndSumsAcrossBlocksAndInACopyThatGrows) {
  const auto key_of = [](int i) {
    return sf::encode_motion_key({.horizon_index = i % 3,
                                  .level = sf::MotionLevel::robot,
                                  .robot_slot = i % 17,
                                  .cell = (i / 17) % sf::MotionFeatures::cell_count,
                                  .velocity_class = 0,
                                  .context = static_cast<std::uint32_t>(i)});
  };
  const auto count_into = [](sf::MotionRow& row, int i) {
    row.add({i, -i}, {{{i, 1}, {2, i}, {0, 0}, {i, i}, {-1, 3}}});
  };
  sf::MotionRowMap map;
  constexpr int first = 16000;  // more than two blocks (of 7281 rows, a huge page each)
  for (int i = 0; i < first; ++i) count_into(map[key_of(i)], i);
  ASSERT_EQ(map.size(), static_cast<std::size_t>(first));
  sf::MotionRowMap copy = map;
  constexpr int more = 8000;
  for (int i = first; i < first + more; ++i) count_into(copy[key_of(i)], i);
  for (int i = 0; i < first; i += 7) count_into(copy[key_of(i)], i);  // old rows again

  EXPECT_EQ(map.size(), static_cast<std::size_t>(first)) << "the copy grew alone";
  ASSERT_EQ(copy.size(), static_cast<std::size_t>(first + more));
  for (int i = 0; i < first + more; ++i) {
    const sf::MotionRow* row = copy.find(key_of(i));
    ASSERT_NE(row, nullptr) << i;
    EXPECT_EQ(copy.row_number(key_of(i)), static_cast<std::uint32_t>(i)) << "numbered as they came";
    sf::MotionRow expected;
    count_into(expected, i);
    if (i < first && i % 7 == 0) count_into(expected, i);
    EXPECT_EQ(*row, expected) << i;
    if (i < first) {
      sf::MotionRow once;
      count_into(once, i);
      EXPECT_EQ(*map.find(key_of(i)), once) << i;
    }
  }
  std::size_t visited = 0;
  copy.for_each([&](sf::MotionKey key, const sf::MotionRow& row) {
    ++visited;
    EXPECT_EQ(copy.find(key), &row);
  });
  EXPECT_EQ(visited, copy.size());
}

TEST(MotionTable, CountsAreSumsSoMergingEqualsAddingEverythingToOne) {
  sf::MotionConfig config = one_second(2);
  config.calibration_capacity = 16;  // small, so that the merge must choose what to keep
  sf::MotionTable both(config), first(config), second(config);
  for (int i = 0; i < 3000; ++i) {
    sf::MotionInstance instance;
    instance.robot_id = static_cast<std::uint32_t>(i % 6);
    instance.x = (i * 37) % 9000 - 4500;
    instance.y = (i * 53) % 6000 - 3000;
    instance.v_x = (i * 11) % 2000 - 1000;
    instance.d_x = (i * 7) % 900 - 450;
    instance.d_y = (i * 13) % 700 - 350;
    const double t = i * 0.05;
    both.add(i % 2, t, instance);
    (i < 1700 ? first : second).add(i % 2, t, instance);
  }
  ASSERT_GT(both.held_out(), 16u);
  sf::MotionTable merged = first;
  merged.merge(second);
  EXPECT_TRUE(merged == both);
  EXPECT_EQ(merged.calibration(0), both.calibration(0));
  EXPECT_EQ(merged.sorted_rows(), both.sorted_rows());

  sf::MotionConfig other = config;
  other.step_s = 0.5;
  EXPECT_THROW(merged.merge(sf::MotionTable(other)), std::invalid_argument);
}

TEST(MotionTable, TheCalibrationSampleIsTheLowestRankedWhateverTheOrderInstancesCameIn) {
  // Every instance's time falls in a held-out block (one in two), and each comes twice: the
  // sample is a multiset, and the twins of the last kept one must not crowd out others.
  sf::MotionConfig config = one_second(1);
  config.calibration_one_in = 2;
  std::vector<std::pair<double, sf::MotionInstance>> offered;
  const sf::MotionTable probe(config);
  for (int i = 0; offered.size() < 2000; ++i) {
    const double t = i * 1.0;
    if (!probe.is_held_out(t)) continue;
    sf::MotionInstance instance;
    instance.robot_id = static_cast<std::uint32_t>(i % 6);
    instance.x = (i * 37) % 9000 - 4500;
    instance.d_x = (i * 7) % 900 - 450;
    offered.emplace_back(t, instance);
    offered.emplace_back(t, instance);
  }
  sf::MotionConfig unbounded = config;
  unbounded.calibration_capacity = static_cast<std::uint32_t>(offered.size());
  sf::MotionTable everything(unbounded);
  for (const auto& [t, instance] : offered) everything.add(0, t, instance);
  std::vector<sf::HeldOutInstance> lowest = everything.calibration(0);
  ASSERT_EQ(lowest.size(), offered.size());

  config.calibration_capacity = 50;  // cut back many times over 4000 offers
  lowest.resize(config.calibration_capacity);
  std::mt19937 random(3);
  for (int order = 0; order < 3; ++order) {
    sf::MotionTable table(config);
    for (const auto& [t, instance] : offered) table.add(0, t, instance);
    EXPECT_EQ(table.calibration(0), lowest) << "order " << order;
    EXPECT_EQ(table.held_out(), offered.size());
    std::shuffle(offered.begin(), offered.end(), random);
  }
}

namespace {

// Eleven robots driving along straight lines at constant speeds, one camera at 60 Hz.
sf::VisionFrame straight_lines(int i) {
  sf::DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(i);
  spec.t_capture = 100.0 + i / 60.0;
  const double t = i / 60.0;
  for (std::uint32_t id = 0; id < 11; ++id) {
    const double speed = 200.0 + 100.0 * id;  // mm/s
    // Back and forth over 4 s legs, so the table sees every direction.
    const double leg = std::fmod(t, 8.0);
    const double along = leg < 4.0 ? speed * leg : speed * (8.0 - leg);
    spec.yellow.push_back({id, {-4000.0 + along, -3500.0 + 700.0 * id}});
  }
  sf::VisionFrame frame;
  sf::to_vision_frame(sf::make_detection_packet(spec), frame);
  return frame;
}

// The pipeline as the predictor runs it by default: frame sampling, step 0.5 s, the motion model.
sf::PredictionConfig motion_pipeline_config(int horizon) {
  sf::PredictionConfig config;
  config.sampler.grid = grid;
  config.sampler.field = field;
  config.sampler.step_s = 0.5;
  config.sampler.sampling = sf::Sampling::frame;
  config.model = sf::ModelKind::motion;
  config.horizon = horizon;
  return config;
}

}  // namespace

TEST(MotionPipeline, PredictsPositionsWithRadiiFromATrainedTable) {
  const sf::PredictionConfig config = motion_pipeline_config(2);
  sf::MotionConfig motion = one_second(2);
  motion.step_s = 0.5;
  sf::Training training(config.sampler, sf::TransitionTable(grid), 0, sf::MotionTable(motion));
  for (int i = 0; i < 60 * 120; ++i) training.add(straight_lines(i));
  ASSERT_TRUE(training.stored_table().motion);
  EXPECT_GT(training.stored_table().motion->instances(), 10000u);

  sf::TableMetadata metadata;
  metadata.field = field;
  metadata.step_s = 0.5;
  double worst_error = 0.0;
  std::uint64_t predictions = 0;
  sf::PredictionPipeline pipeline(config, [&](const sf::PredictedFormation& p) {
    ++predictions;
    ASSERT_EQ(p.prediction.steps.size(), 2u);
    EXPECT_EQ(p.context.model, sf::ModelKind::motion);
    for (const sf::RobotPrediction& robot : p.prediction.steps[0].robots) {
      EXPECT_GT(robot.radius90_mm, robot.radius50_mm);
      EXPECT_GT(robot.radius50_mm, 0.0);
      // Robot i is at y = -3500 + 700 i and keeps its line.
      worst_error = std::max(worst_error,
                             std::abs(robot.feed_position.y - (-3500.0 + 700.0 * robot.robot_id)));
    }
  });
  pipeline.set_table(std::make_shared<const sf::StoredTable>(training.stored_table(metadata)));
  for (int i = 0; i < 600; ++i) pipeline.add(straight_lines(60 * 200 + i));
  EXPECT_GT(predictions, 500u);
  EXPECT_LT(worst_error, 50.0);
}

TEST(MotionPipeline, AVersionOneTableServesOnlyThePapersModelAndSaysSo) {
  sf::PredictionConfig config;
  config.sampler.sampling = sf::Sampling::frame;
  config.model = sf::ModelKind::motion;
  sf::PredictionPipeline pipeline(config, nullptr);
  const auto paper_only = std::make_shared<const sf::StoredTable>(
      sf::StoredTable{sf::TransitionTable(config.sampler.grid), {}, {}});
  try {
    pipeline.set_table(paper_only);
    FAIL() << "a table without the motion model's counts was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("--model paper"), std::string::npos) << error.what();
  }
  // The paper's model takes it.
  config.model = sf::ModelKind::paper;
  sf::PredictionPipeline paper(config, nullptr);
  EXPECT_NO_THROW(paper.set_table(paper_only));

  // The motion model needs frame sampling.
  config.model = sf::ModelKind::motion;
  config.sampler.sampling = sf::Sampling::step;
  EXPECT_THROW(sf::PredictionPipeline(config, nullptr), std::invalid_argument);
}

TEST(MotionPipeline, ARobotTheLastPacketDidNotSeeIsPredictedMovingAsItWasLastSeen) {
  // Real logs (docs/simulation.md): one camera id, each packet half the field, 90 packets a second.
  // Robots 0-4 drive along +x at 1 m/s on the left half, 5-9 along -y on the right half.
  const auto half_field_packet = [](int i) {
    const double t = i / 90.0;
    const bool left = i % 2 == 0;
    sf::DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = 100.0 + t;
    for (std::uint32_t id = 0; id < 10; ++id) {
      if ((id < 5) != left) continue;
      spec.yellow.push_back(
          id < 5 ? sf::RobotDetection{id, {-5000.0 + 1000.0 * t, -3000.0 + 1000.0 * id}}
                 : sf::RobotDetection{id, {1000.0 * (id - 4), 3000.0 - 1000.0 * t}});
    }
    sf::VisionFrame frame;
    sf::to_vision_frame(sf::make_detection_packet(spec), frame);
    return frame;
  };
  const sf::PredictionConfig config = motion_pipeline_config(1);
  sf::TableMetadata metadata;
  metadata.field = field;
  metadata.step_s = 0.5;
  sf::MotionConfig motion = one_second(1);
  motion.step_s = 0.5;
  // An empty table: every robot is predicted by damped constant velocity from its kinematics.
  const auto stored = std::make_shared<const sf::StoredTable>(sf::StoredTable{
      sf::TransitionTable(grid), metadata, std::make_shared<const sf::MotionTable>(motion)});
  std::size_t carried_over = 0;
  std::size_t checked = 0;
  sf::PredictionPipeline pipeline(config, [&](const sf::PredictedFormation& p) {
    if (p.formation().time_s < 101.0) return;  // a second of history for everyone
    for (const sf::RobotPrediction& robot : p.prediction.steps[0].robots) {
      const sf::FormationRobot* now = p.formation().find(robot.robot_id);
      ASSERT_NE(now, nullptr);
      if (!now->observed) ++carried_over;
      // 0.5 s ahead at 1 m/s, damped: well over 200 mm along its way, whether or not this
      // packet saw it (a robot taken as standing would be predicted where it is).
      const sf::Point moved{robot.feed_position.x - now->feed_position.x,
                            robot.feed_position.y - now->feed_position.y};
      if (robot.robot_id < 5) {
        EXPECT_GT(moved.x, 200.0) << robot.robot_id << " at " << p.formation().time_s;
      } else {
        EXPECT_LT(moved.y, -200.0) << robot.robot_id << " at " << p.formation().time_s;
      }
      ++checked;
    }
  });
  pipeline.set_table(stored);
  for (int i = 0; i < 90 * 3; ++i) pipeline.add(half_field_packet(i));
  EXPECT_GT(checked, 1500u);
  EXPECT_GT(carried_over, checked / 3);
}

TEST(MotionPipeline, ATeamStandingStillForAMinuteIsSaidToStayAsOftenAsItDoes) {
  // Trained on robots that keep moving, then shown the team standing in a stoppage: the table's
  // calibration knows nothing of that, the recalibration learns it from the predictions that
  // came true. Positions are the model's either way; probabilities move, and the radii shrink
  // (every robot is well inside them).
  sf::PredictionConfig config = motion_pipeline_config(1);
  sf::MotionConfig motion = one_second(1);
  motion.step_s = 0.5;
  sf::Training training(config.sampler, sf::TransitionTable(grid), 0, sf::MotionTable(motion));
  for (int i = 0; i < 60 * 120; ++i) training.add(straight_lines(i));
  sf::TableMetadata metadata;
  metadata.field = field;
  metadata.step_s = 0.5;
  const auto stored = std::make_shared<const sf::StoredTable>(training.stored_table(metadata));
  const auto standing = [](int i) {
    sf::DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = 500.0 + i / 60.0;
    // Each 10 mm inside a corner of its 1 m cell: the model's spread, however small, puts some
    // of the robot in the neighbouring cells.
    for (std::uint32_t id = 0; id < 11; ++id) {
      spec.yellow.push_back({id, {-4010.0 + 1000.0 * (id % 8), -2510.0 + 2000.0 * (id / 8)}});
    }
    sf::VisionFrame frame;
    sf::to_vision_frame(sf::make_detection_packet(spec), frame);
    return frame;
  };
  // Each prediction of both pipelines, in order.
  std::vector<sf::Prediction> recalibrated, as_stated;
  std::vector<double> times;
  sf::PredictionPipeline on(config, [&](const sf::PredictedFormation& p) {
    recalibrated.push_back(p.prediction);
    times.push_back(p.formation().time_s);
  });
  // The daemon's warm-up runs the last prediction again between frames: it must not be
  // remembered (checked twice), so a pipeline rehearsing every frame states the same.
  std::vector<sf::Prediction> rehearsing;
  sf::PredictionPipeline warmed(
      config, [&](const sf::PredictedFormation& p) { rehearsing.push_back(p.prediction); });
  config.recalibration.reset();
  sf::PredictionPipeline off(
      config, [&](const sf::PredictedFormation& p) { as_stated.push_back(p.prediction); });
  on.set_table(stored);
  off.set_table(stored);
  warmed.set_table(stored);
  std::size_t rehearsals = 0;
  for (int i = 0; i < 60 * 60; ++i) {
    on.add(standing(i));
    off.add(standing(i));
    warmed.add(standing(i));
    for (int r = 0; r < 3; ++r) rehearsals += warmed.rehearse(nullptr) ? 1 : 0;
  }
  EXPECT_GT(rehearsals, 10000u);
  ASSERT_EQ(rehearsing.size(), recalibrated.size());
  for (std::size_t k = 0; k < recalibrated.size(); ++k) {
    for (std::size_t r = 0; r < recalibrated[k].steps[0].robots.size(); ++r) {
      ASSERT_EQ(rehearsing[k].steps[0].robots[r].probability,
                recalibrated[k].steps[0].robots[r].probability)
          << "prediction " << k << " robot " << r;
    }
  }
  ASSERT_EQ(recalibrated.size(), as_stated.size());
  ASSERT_GT(recalibrated.size(), 3000u);
  double stated_at_end = 0.0;
  for (std::size_t k = 0; k < recalibrated.size(); ++k) {
    const auto& a = recalibrated[k].steps[0].robots;
    const auto& b = as_stated[k].steps[0].robots;
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t r = 0; r < a.size(); ++r) {
      EXPECT_EQ(a[r].position, b[r].position);
      EXPECT_EQ(a[r].feed_position.x, b[r].feed_position.x);
      EXPECT_LE(a[r].radius90_mm, b[r].radius90_mm);
      // Nothing can have been checked before the first step (0.5 s) has passed.
      if (times[k] < 500.5) {
        EXPECT_EQ(a[r].probability, b[r].probability);
      }
    }
  }
  // At the end of the minute the radii are a fraction of the table's: no robot left them.
  for (std::size_t r = 0; r < as_stated.back().steps[0].robots.size(); ++r) {
    EXPECT_LT(recalibrated.back().steps[0].robots[r].radius90_mm,
              as_stated.back().steps[0].robots[r].radius90_mm / 2.0);
  }
  // At the end of the minute: every robot stayed in its cell, and that is what is now stated.
  for (const sf::RobotPrediction& robot : recalibrated.back().steps[0].robots) {
    EXPECT_GT(robot.probability, 0.95) << robot.robot_id;
  }
  for (const sf::RobotPrediction& robot : as_stated.back().steps[0].robots) {
    stated_at_end = std::max(stated_at_end, robot.probability);
  }
  EXPECT_LT(stated_at_end, 0.95) << "the table alone already said the team stays";
  // The whole formation stayed every time, and its probability is checked as a whole: it rises
  // from what the table stated towards the formations' hit rate.
  EXPECT_GT(recalibrated.back().steps[0].formation_probability, 0.9);
  EXPECT_GT(recalibrated.back().steps[0].formation_probability,
            as_stated.back().steps[0].formation_probability + 0.1);
}
