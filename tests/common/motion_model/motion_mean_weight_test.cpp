// What each game phase keeps of the table's fit, hand-built: the weight of its rows' mean
// displacement (kept where held-out play bears it out, dropped where it does not or never
// holds), the team's velocity as a regressor (not at the restarts taken where the ball went
// out), and its own radii where its held-out play strays further than the others'.

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "hand_built_motion.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/motion_model/motion_predictor.hpp"

namespace ssl_formation {
namespace {

const Grid& grid = testing::hand_built_grid;
const FieldSize& field = testing::hand_built_field;
MotionConfig config() { return testing::hand_built_config(); }

std::uint32_t context_of(GamePhase phase) {
  return MotionFeatures::context(0, 0, MotionFeatures::game_context(phase, 5.0));
}

// Robot 3 at (1000, 500) in `phase`, creeping across the field (150 mm/s along y, its sightings
// over the settle window 40 mm behind), found `dx` further along x half a second later. A robot
// that stands is forecast where it stands: a creeping one's displacement along x is the rows'.
MotionInstance standing_robot(GamePhase phase, std::int32_t dx) {
  MotionInstance i;
  i.robot_id = 3;
  i.x = 1000;
  i.y = 500;
  i.d_x = dx;
  i.v_y = 150;
  i.g_y = -40;
  i.context = context_of(phase);
  return i;
}

// Instances 0.1 s apart from `first_s` until `counted` went into rows and `held_out` into the
// held-out sample: the rows learn `counted_dx`, the held-out play shows `held_out_dx`.
void add(MotionTable& table, GamePhase phase, int counted, std::int32_t counted_dx, int held_out,
         std::int32_t held_out_dx, double first_s) {
  int rows = 0, held = 0;
  for (double t = first_s; rows < counted || held < held_out; t += 0.1) {
    const bool is_held_out = table.is_held_out(t);
    if (is_held_out && held < held_out) {
      table.add(0, t, standing_robot(phase, held_out_dx));
      ++held;
    } else if (!is_held_out && rows < counted) {
      table.add(0, t, standing_robot(phase, counted_dx));
      ++rows;
    }
  }
}

// Robot 3 at (1000, 500) in `phase`, creeping as the instances above.
MotionRobot creeping_robot(GamePhase phase) {
  MotionRobot robot;
  robot.robot_id = 3;
  robot.position = {1000.0, 500.0};
  robot.has_velocity = true;
  robot.kinematics.velocity = {0.0, 150.0};
  robot.kinematics.to_recent_mean = {0.0, -40.0};
  robot.context = context_of(phase);
  return robot;
}

MotionForecast forecast_standing(const MotionModel& model, GamePhase phase) {
  return model.forecast(0, creeping_robot(phase));
}

double forecast_dx(const MotionModel& model, GamePhase phase) {
  return forecast_standing(model, phase).position.x - 1000.0;
}

TEST(MotionMeanWeight, APhasesMeanDisplacementCountsAsMuchAsItsHeldOutPlayBearsOut) {
  MotionTable table(config());
  // Running play: the rows and the held-out play agree that the robot goes 600 mm on.
  add(table, GamePhase::running, 2000, 600, 300, 600, 0.0);
  // STOP: the training's went 600 mm on, the held-out ones nowhere.
  add(table, GamePhase::stop, 2000, 600, 300, 0, 1000.0);
  const MotionModel model(table, grid, field);
  EXPECT_NEAR(forecast_dx(model, GamePhase::running), 600.0, 10.0);
  // 300 held-out instances against the weight's 20: at most a fifteenth of the mean is kept.
  EXPECT_LT(forecast_dx(model, GamePhase::stop), 60.0);
  EXPECT_GE(forecast_dx(model, GamePhase::stop), 0.0);
}

TEST(MotionMeanWeight, TooLittleHeldOutKeepsEveryMeanWhole) {
  MotionTable table(config());
  // 50 held-out instances, under the 100 the calibration needs: nothing to weigh with.
  add(table, GamePhase::kickoff_opponent, 2000, 600, 50, 0, 0.0);
  const MotionModel model(table, grid, field);
  EXPECT_NEAR(forecast_dx(model, GamePhase::kickoff_opponent), 600.0, 10.0);
}

TEST(MotionMeanWeight, TheirFreeKicksOurPlacementsAndHaltsNeverKeepTheirMean) {
  // Held-out play agreeing with the rows does not bring it back: it is the same restarts'.
  for (const GamePhase phase :
       {GamePhase::free_kick_opponent, GamePhase::ball_placement_us, GamePhase::halt}) {
    MotionTable table(config());
    add(table, phase, 2000, 600, 300, 600, 0.0);
    add(table, GamePhase::free_kick_us, 2000, 600, 300, 600, 1000.0);
    const MotionModel model(table, grid, field);
    EXPECT_NEAR(forecast_dx(model, phase), 0.0, 1.0) << static_cast<int>(phase);
    EXPECT_NEAR(forecast_dx(model, GamePhase::free_kick_us), 600.0, 10.0);
  }
}

TEST(MotionMeanWeight, AHeldOutMeanHalfAsLargeKeepsAboutHalf) {
  MotionTable table(config());
  add(table, GamePhase::ball_placement_opponent, 3000, 600, 1000, 300, 0.0);
  const MotionModel model(table, grid, field);
  // The fit is 0.5, held towards one by 20 instances of 1,000: 0.51.
  EXPECT_NEAR(forecast_dx(model, GamePhase::ball_placement_opponent), 306.0, 10.0);
}

// Robot 3 in `phase` forecast 0.5 s on, creeping while its team moves at `team_velocity_x`.
double forecast_dx_with_team(const MotionModel& model, GamePhase phase, double team_velocity_x) {
  MotionRobot robot = creeping_robot(phase);
  robot.kinematics.team_velocity = {team_velocity_x, 0.0};
  return model.forecast(0, robot).position.x - 1000.0;
}

TEST(MotionTeamVelocity, TheRestartsTakenWhereTheBallWentOutLeaveTheTeamsVelocityOut) {
  // In every phase the robot went 400 mm on whenever its team moved at 1 m/s and stayed when
  // it stood: the team's velocity explains the whole displacement.
  const std::array<GamePhase, 5> phases{GamePhase::running, GamePhase::stop,
                                        GamePhase::free_kick_opponent, GamePhase::free_kick_us,
                                        GamePhase::ball_placement_us};
  MotionTable table(config());
  double t = 0.0;
  for (const GamePhase phase : phases) {
    for (int i = 0; i < 2000; ++i, t += 0.1) {
      MotionInstance instance = standing_robot(phase, i % 2 == 0 ? 400 : 0);
      instance.t_x = i % 2 == 0 ? 1000 : 0;
      table.add(0, t, instance);
    }
  }
  const MotionModel model(table, grid, field);
  // Where it holds, the team setting off says the robot follows.
  for (const GamePhase phase : {GamePhase::running, GamePhase::stop}) {
    EXPECT_GT(
        forecast_dx_with_team(model, phase, 1000.0) - forecast_dx_with_team(model, phase, 0.0),
        300.0)
        << to_string(phase);
  }
  // At the free kicks and our placements each robot makes for its own place about the ball:
  // the forecast is the same whatever the team does.
  for (const GamePhase phase :
       {GamePhase::free_kick_opponent, GamePhase::free_kick_us, GamePhase::ball_placement_us}) {
    EXPECT_NEAR(forecast_dx_with_team(model, phase, 1000.0),
                forecast_dx_with_team(model, phase, 0.0), 0.5)
        << to_string(phase);
  }
}

// `count` instances of robot 3 standing in `phase` that moved +-`spread_mm` along x, in turn,
// into rows (held_out false) or into the held-out sample (true), from `first_s` on.
void add_spread(MotionTable& table, GamePhase phase, int count, std::int32_t spread_mm,
                bool held_out, double first_s) {
  int added = 0;
  for (double t = first_s; added < count; t += 0.1) {
    if (table.is_held_out(t) != held_out) continue;
    table.add(0, t, standing_robot(phase, added % 2 == 0 ? spread_mm : -spread_mm));
    ++added;
  }
}

double radius90(const MotionModel& model, GamePhase phase) {
  return forecast_standing(model, phase).radius90_mm;
}

TEST(MotionPhaseRadii, APhaseWhoseHeldOutPlayStraysFurtherGetsWiderRadiiNeverNarrower) {
  MotionTable table(config());
  // Every phase's rows learned robots 100 mm either way.
  for (const GamePhase phase : {GamePhase::running, GamePhase::kickoff_opponent, GamePhase::stop}) {
    add_spread(table, phase, 2000, 100, false, 0.0);
  }
  // Held out: running play as learned, the kick-offs 400 mm either way, STOP 10 mm.
  add_spread(table, GamePhase::running, 1000, 100, true, 0.0);
  add_spread(table, GamePhase::kickoff_opponent, 60, 400, true, 5000.0);
  add_spread(table, GamePhase::stop, 60, 10, true, 6000.0);
  const MotionModel model(table, grid, field);
  EXPECT_NEAR(radius90(model, GamePhase::running), 100.0, 5.0);
  EXPECT_NEAR(radius90(model, GamePhase::kickoff_opponent), 400.0, 20.0);
  // Held out of the same match, a phase's play looks tamer than the next match's: its radii
  // are never narrower than the horizon's.
  EXPECT_NEAR(radius90(model, GamePhase::stop), 100.0, 5.0);
}

}  // namespace
}  // namespace ssl_formation
