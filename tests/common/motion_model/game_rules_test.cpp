// The motion model in the game's states (models/src/game_rules.cpp, the game contexts of
// motion_model and the rules' prior of motion_predictor): learned and predicted through the front
// end from vision frames and referee messages, as the daemons do.

#include "ssl_formation/motion_model/game_rules.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "match_logs.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/match_front_end.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
namespace {

constexpr double start_s = 100.0;
constexpr double step_s = 0.5;
constexpr int steps = 3;

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Six yellow robots (the opponent, attacking +x), each circling its own spot at 1.2 m/s.
Point circling(int id, double t) {
  const Point centre{-2500.0 + 1000.0 * id, id % 2 == 0 ? 1000.0 : -1000.0};
  const double angle = 2.0 * t + id;
  return {centre.x + 600.0 * std::cos(angle), centre.y + 600.0 * std::sin(angle)};
}

// A match: the robots' path by the time into it, the ball (feed coordinates) and the referee's
// command, each a function of the time.
struct Script {
  std::function<Point(int id, double t)> robot = circling;
  std::function<std::optional<Point>(double t)> ball = [](double) {
    return std::optional<Point>(Point{2000.0, 0.0});
  };
  std::function<Referee::Command(double t)> command = [](double) { return Referee::NORMAL_START; };
  std::optional<Point> designated_position;  // sent with every message (feed coordinates)
};

FrontEndConfig front_config() {
  FrontEndConfig c;
  c.sampler = sampler_config_for(ModelKind::motion);
  c.sampler.grid = Grid(3, 2);
  c.sampler.step_s = step_s;
  c.sampler.opponent_color = TeamColor::yellow;
  c.sampler.opponent_attacks = AttackDirection::positive_x;
  return c;
}

// The game controller's side of a stream: its command counter.
struct GameController {
  std::uint32_t counter = 0;
  int last_command = -1;
};

// Feeds `seconds` of the script from `from_s` (seconds into the match) to `run`'s front end:
// frames at 60 Hz, the referee's message every tenth of a second (a new counter at each new
// command).
template <typename Run>
void play(Run& run, const Script& script, double from_s, double seconds) {
  MatchFrontEnd& front = run.front;
  std::uint32_t& counter = run.game_controller.counter;
  int& last_command = run.game_controller.last_command;
  const int first = static_cast<int>(std::lround(from_s * 60.0));
  const int last = static_cast<int>(std::lround((from_s + seconds) * 60.0));
  for (int i = first; i < last; ++i) {
    const double t = i / 60.0;
    if (i % 6 == 0) {
      const Referee::Command command = script.command(t);
      if (command != last_command) ++counter;
      last_command = command;
      testing::RefereeSpec spec;
      spec.command = command;
      spec.command_counter = counter;
      spec.designated_position = script.designated_position;
      front.add_referee(testing::referee_payload(spec, start_s + t), start_s + t);
    }
    DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = start_s + t;
    for (int id = 0; id < 6; ++id) {
      spec.yellow.push_back({static_cast<std::uint32_t>(id), script.robot(id, t)});
    }
    if (const auto ball = script.ball(t)) spec.balls.push_back(*ball);
    front.add(make_detection_packet(spec));
  }
}

ModelSettings settings() {
  ModelSettings s;
  s.grid = Grid(3, 2);
  s.step_s = step_s;
  s.horizons = steps;
  s.recalibration = std::nullopt;  // the table's own forecasts
  return s;
}

// A motion model's learning: every sample of the front end learned from.
struct Learning {
  std::unique_ptr<Learner> learner = make_learner(ModelKind::motion, settings());
  GameController game_controller;
  MatchFrontEnd front{front_config(),
                      {[this](const MatchMoment& m) {
                         learner->observe(m);
                         learner->learn(m);
                       },
                       [this] { learner->forget_match(); }}};
};

// What a forecaster predicted at each sample, with what it knew then.
struct Forecast {
  double time_s = 0.0;
  GameState state = GameState::unknown;
  std::optional<Point> ball;  // normalised
  std::vector<FormationRobot> robots;
  Prediction prediction;
};

struct Forecasting {
  explicit Forecasting(const Learner& learner)
      : forecaster(learner.forecaster(TableMetadata{FieldSize{9000.0, 6000.0}, step_s, 1})) {}
  std::unique_ptr<Forecaster> forecaster;
  std::vector<Forecast> seen;
  GameController game_controller;
  MatchFrontEnd front{
      front_config(),
      {[this](const MatchMoment& m) {
         forecaster->observe(m);
         Forecast f{m.formation().time_s, m.game_state, m.ball, m.formation().robots, {}};
         forecaster->forecast(m, steps, f.prediction);
         seen.push_back(std::move(f));
       },
       [this] { forecaster->forget_match(); }}};
};

const FormationRobot& robot_of(const Forecast& f, std::uint32_t id) {
  for (const FormationRobot& r : f.robots) {
    if (r.robot_id == id) return r;
  }
  throw std::logic_error("no such robot");
}

// The greatest distance a forecast puts any robot from where it stands, over every step.
double largest_move(const Forecast& f) {
  double largest = 0.0;
  for (const PredictedStep& step : f.prediction.steps) {
    for (const RobotPrediction& p : step.robots) {
      largest =
          std::max(largest, distance(p.normalised_position, robot_of(f, p.robot_id).position));
    }
  }
  return largest;
}

// A robot creeping along a line at 200 mm/s: in HALT it should not, and its velocity is what an
// extrapolation of running play would carry on.
Point creeping(int id, double t) {
  const Point from = circling(id, 0.0);
  return {from.x + 200.0 * std::fmod(t, 4.0), from.y};
}

TEST(GameRules, AYoungTablePredictsStandingRobotsInHalt) {
  // Learned in running play only: the table has no row of HALT.
  Learning learning;
  play(learning, Script{}, 0.0, 60.0);
  ASSERT_GT(learning.learner->progress(), 0u);

  Script script;
  script.command = [](double t) { return t < 10.0 ? Referee::NORMAL_START : Referee::HALT; };
  script.robot = [](int id, double t) { return t < 10.0 ? circling(id, t) : creeping(id, t); };
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 13.0);

  int halted = 0, running = 0;
  for (const Forecast& f : forecasting.seen) {
    const double t = f.time_s - start_s;
    if (f.state == GameState::running && t > 5.0) {
      // Running play: the circles carry on, a metre in a second and a half.
      EXPECT_GT(largest_move(f), 300.0) << t;
      ++running;
    }
    if (f.state == GameState::halt && t > 11.0) {
      // "No robot is allowed to move": with no HALT row yet, the rules' prior keeps every robot
      // where it is, but for the braking of its 200 mm/s (15 ms of it, 30 mm).
      EXPECT_LT(largest_move(f), 45.0) << t;
      ++halted;
    }
  }
  EXPECT_GT(running, 100);
  EXPECT_GT(halted, 100);
}

// The vision's noise, up to 6 mm each way: a fixed draw per robot and frame.
Point vision_noise(int id, double t) {
  std::uint32_t h = static_cast<std::uint32_t>(std::lround(t * 60.0)) * 2654435761u;
  h ^= static_cast<std::uint32_t>(id + 1) * 40503u;
  h ^= h >> 15;
  h *= 2246822519u;
  h ^= h >> 13;
  const auto unit = [](std::uint32_t bits) { return (bits & 0xffffu) / 65535.0 * 2.0 - 1.0; };
  return {6.0 * unit(h), 6.0 * unit(h >> 16)};
}

TEST(GameRules, InHaltARobotThatHasStoodIsForecastWhereItStandsNotWhereItWasLastSeen) {
  Learning learning;
  play(learning, Script{}, 0.0, 60.0);

  // At the HALT every robot stops dead where it was, and the vision sees it there give or take
  // its noise.
  Script script;
  script.command = [](double t) { return t < 10.0 ? Referee::NORMAL_START : Referee::HALT; };
  script.robot = [](int id, double t) {
    if (t < 10.0) return circling(id, t);
    const Point spot = circling(id, 10.0);
    const Point noise = vision_noise(id, t);
    return Point{spot.x + noise.x, spot.y + noise.y};
  };
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 14.0);

  // After a settle window of standing (half a second, once the tracker calls it standing), the
  // forecast at every step is the mean of its sightings: nearer its spot than the last sighting,
  // which "every robot stays" would forecast.
  std::vector<double> forecast_off(steps, 0.0);
  double sighting_off = 0.0;
  int seen = 0;
  for (const Forecast& f : forecasting.seen) {
    if (f.state != GameState::halt || f.time_s - start_s < 11.5) continue;
    for (const FormationRobot& robot : f.robots) {
      const Point spot = circling(static_cast<int>(robot.robot_id), 10.0);
      sighting_off += distance(robot.position, spot);
      for (std::size_t k = 0; k < f.prediction.steps.size(); ++k) {
        for (const RobotPrediction& p : f.prediction.steps[k].robots) {
          if (p.robot_id == robot.robot_id)
            forecast_off[k] += distance(p.normalised_position, spot);
        }
      }
      ++seen;
    }
  }
  ASSERT_GT(seen, 500);
  sighting_off /= seen;
  EXPECT_GT(sighting_off, 3.0);  // the noise is there to average
  for (int k = 0; k < steps; ++k) {
    EXPECT_LT(forecast_off[static_cast<std::size_t>(k)] / seen, 0.4 * sighting_off)
        << "step " << k + 1;
  }
}

TEST(GameRules, TheHaltRowsOfATeamThatKeepsMovingTakeOverFromThePrior) {
  // A team whose robots creep on through every HALT: its own rows say so, and outweigh the prior.
  Script halted;
  halted.command = [](double t) {
    return std::fmod(t, 20.0) < 10.0 ? Referee::NORMAL_START : Referee::HALT;
  };
  const auto slow_circle = [](int id, double t) {
    const Point centre{-2500.0 + 1000.0 * id, 0.0};
    return Point{centre.x + 1200.0 * std::cos(0.35 * t + id),
                 centre.y + 1200.0 * std::sin(0.35 * t + id)};
  };
  halted.robot = [slow_circle](int id, double t) {
    return std::fmod(t, 20.0) < 10.0 ? circling(id, t) : slow_circle(id, t);
  };
  Learning learning;
  play(learning, halted, 0.0, 200.0);

  Forecasting forecasting(*learning.learner);
  play(forecasting, halted, 200.0, 20.0);
  double moved = 0.0;
  int seen = 0;
  for (const Forecast& f : forecasting.seen) {
    const double into_halt = std::fmod(f.time_s - start_s, 20.0) - 10.0;
    if (f.state != GameState::halt || into_halt < 3.0) continue;
    // Robot 2's forecast 1.5 s ahead: about 0.42 m/s x 1.5 s away, as the team really moves.
    const RobotPrediction& p = f.prediction.steps[2].robots[2];
    moved += distance(p.normalised_position, robot_of(f, p.robot_id).position);
    ++seen;
  }
  ASSERT_GT(seen, 100);
  EXPECT_GT(moved / seen, 400.0);
}

// A robot heading straight for the ball at 2.5 m/s from 1.5 m away, turning back 0.3 m short of it
// (it disregards the rules, the forecast must not).
Point charging(int id, double t) {
  const Point ball{2000.0, 0.0};
  const double angle = id * 1.0472;  // from every side
  const double phase = std::fmod(t, 1.0);
  const double along = 1500.0 - 1200.0 * (phase < 0.5 ? phase * 2.0 : 2.0 - phase * 2.0);
  return {ball.x + along * std::cos(angle), ball.y + along * std::sin(angle)};
}

TEST(GameRules, AStopPredictionKeepsHalfAMetreFromTheBallAndUnderOneAndAHalfMetresASecond) {
  Script script;
  script.robot = charging;  // learned as running play: the table extrapolates into the ball
  Learning learning;
  play(learning, script, 0.0, 60.0);

  script.command = [](double t) { return t < 5.0 ? Referee::NORMAL_START : Referee::STOP; };
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 15.0);
  int checked = 0;
  for (const Forecast& f : forecasting.seen) {
    if (f.state != GameState::stop) continue;
    ASSERT_TRUE(f.ball);
    for (std::size_t k = 0; k < f.prediction.steps.size(); ++k) {
      for (const RobotPrediction& p : f.prediction.steps[k].robots) {
        const Point from = robot_of(f, p.robot_id).position;
        EXPECT_GE(distance(p.normalised_position, *f.ball), 500.0 - 1e-6);
        // A robot already closer than 0.5 m must leave, whatever its speed.
        if (distance(from, *f.ball) >= 500.0) {
          EXPECT_LE(distance(p.normalised_position, from), 1500.0 * (k + 1) * step_s + 1e-6);
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

// Robot 2 runs along y = -2 m at 1.2 m/s for 1.5 s, brakes at 1.5 m/s² to a stand (0.8 s,
// 480 mm), stands 1.2 s, and again; the others circle. The ball (at (2 m, 0)) is far from it.
constexpr double run_s = 1.5, brake_s = 0.8, cycle_s = 3.5;
constexpr double run_speed_mm_s = 1200.0, braking_mm_s2 = 1500.0;
constexpr double cycle_mm = run_speed_mm_s * run_s + 0.5 * run_speed_mm_s * brake_s;
Point running_and_braking(int id, double t) {
  if (id != 2) return circling(id, t);
  const double cycles = std::floor(t / cycle_s);
  const double within = t - cycles * cycle_s;
  double x = -3800.0 + cycles * cycle_mm;
  if (within < run_s) {
    x += run_speed_mm_s * within;
  } else {
    const double braking = std::min(within - run_s, brake_s);
    x +=
        run_speed_mm_s * run_s + run_speed_mm_s * braking - 0.5 * braking_mm_s2 * braking * braking;
  }
  return {x, -2000.0};
}

TEST(GameRules, InStopARobotBrakingToItsPlaceIsForecastNearWhereItsBrakingStopsIt) {
  // An empty table forecasts it as the prior's damped constant velocity would, past where it
  // stops; the braking advice (braking_advice.hpp) brings the forecast to its stand.
  Learning learning;
  Script script;
  script.robot = running_and_braking;
  script.command = [](double) { return Referee::STOP; };
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 3.0 * cycle_s);
  int checked = 0;
  for (const Forecast& f : forecasting.seen) {
    const double t = f.time_s - start_s;
    const double within = t - std::floor(t / cycle_s) * cycle_s;
    // Well into its braking, with more than the last step's 1.5 s to go before the next run.
    if (f.state != GameState::stop || within < run_s + 0.3 || within >= run_s + 0.55) continue;
    const Point stand{running_and_braking(2, t - within + run_s + brake_s).x, -2000.0};
    const Point from = robot_of(f, 2).position;
    ASSERT_EQ(f.prediction.steps.size(), static_cast<std::size_t>(steps));
    const RobotPrediction* last = nullptr;
    for (const RobotPrediction& p : f.prediction.steps.back().robots) {
      if (p.robot_id == 2) last = &p;
    }
    ASSERT_NE(last, nullptr);
    // With the advice the forecast is 54-86 mm from where it stands, without it 184-274 mm.
    EXPECT_LT(distance(last->normalised_position, stand), 120.0)
        << "at " << t << " s, from x " << from.x << ", stands at " << stand.x << ", forecast x "
        << last->normalised_position.x;
    ++checked;
  }
  EXPECT_GT(checked, 40);
}

// The distance from `p` to the segment from `a` to `b`.
double distance_to_segment(Point p, Point a, Point b) {
  const Point along{b.x - a.x, b.y - a.y};
  const double length_squared = along.x * along.x + along.y * along.y;
  const double t =
      length_squared > 0.0
          ? std::clamp(((p.x - a.x) * along.x + (p.y - a.y) * along.y) / length_squared, 0.0, 1.0)
          : 0.0;
  return distance(p, {a.x + t * along.x, a.y + t * along.y});
}

TEST(GameRules, AtOurBallPlacementTheOpponentIsForecastClearOfThePathAtAnySpeed) {
  Script script;
  script.robot = charging;  // learned as running play: 2.5 m/s, into the ball
  Learning learning;
  play(learning, script, 0.0, 60.0);
  // Blue (us) places the ball from (2000, 0) to (0, 1500) from 5 s on; the path passes through
  // where the robots charge.
  script.command = [](double t) {
    return t < 5.0 ? Referee::NORMAL_START : Referee::BALL_PLACEMENT_BLUE;
  };
  script.designated_position = Point{0.0, 1500.0};
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 12.0);
  int checked = 0;
  double fastest_mm_s = 0.0;
  for (const Forecast& f : forecasting.seen) {
    if (f.state != GameState::ball_placement) continue;
    ASSERT_TRUE(f.ball);
    for (std::size_t k = 0; k < f.prediction.steps.size(); ++k) {
      for (const RobotPrediction& p : f.prediction.steps[k].robots) {
        EXPECT_GE(distance_to_segment(p.normalised_position, *f.ball, Point{0.0, 1500.0}),
                  500.0 - 1e-6);
        const Point from = robot_of(f, p.robot_id).position;
        fastest_mm_s =
            std::max(fastest_mm_s, distance(p.normalised_position, from) / ((k + 1) * step_s));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1000);
  // STOP's speed limit is not placement's: "This rule does not apply to ball placement".
  EXPECT_GT(fastest_mm_s, 1500.0);
}

// Every robot standing where it circled from.
Point standing(int id, double) { return circling(id, 0.0); }

TEST(GameRules, AtTheirBallPlacementTheRobotNearestTheBallIsForecastOnItsWayToTheSpot) {
  Script script;
  script.robot = standing;  // learned as running play: nobody moves
  Learning learning;
  play(learning, script, 0.0, 60.0);
  // Yellow (the opponent) places the ball from (2000, 0) to (-1000, -2000) from 5 s on; robot 4
  // stands nearest the ball, about a metre from it.
  script.command = [](double t) {
    return t < 5.0 ? Referee::NORMAL_START : Referee::BALL_PLACEMENT_YELLOW;
  };
  script.designated_position = Point{-1000.0, -2000.0};
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 10.0);
  int checked = 0;
  for (const Forecast& f : forecasting.seen) {
    if (f.state != GameState::ball_placement) continue;
    ASSERT_TRUE(f.ball);
    const std::vector<RobotPrediction>& last = f.prediction.steps.back().robots;
    for (const RobotPrediction& p : last) {
      const Point from = robot_of(f, p.robot_id).position;
      if (p.robot_id == 4) {
        // 1.5 s on, the path has it round the ball's far side from the spot, at (2091, 61), and
        // 591 mm on towards the spot, at (1600, -267): 950 mm from where it stands. The forecast
        // moves 0.4 of the way there.
        EXPECT_NEAR(distance(p.normalised_position, from), 380.0, 20.0);
        EXPECT_LT(distance(p.normalised_position, *f.ball), distance(from, *f.ball));
      } else {
        EXPECT_LT(distance(p.normalised_position, from), 50.0) << p.robot_id;
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 200);
}

TEST(BallPlacementPath, TheNearestRobotDrivesBehindTheBallThenCarriesItToTheSpot) {
  std::vector<MotionRobot> robots(3);
  robots[0].robot_id = 0;
  robots[0].position = {-3000.0, 0.0};
  robots[1].robot_id = 2;
  robots[1].position = {0.0, 0.0};  // 1 m from the ball, standing
  robots[2].robot_id = 4;
  robots[2].position = {500.0, 2000.0};
  SetPlayAdvice advice;
  advise_ball_placement(robots, Point{1000.0, 0.0}, Point{3000.0, 0.0}, 0.5, 3, advice);
  ASSERT_TRUE(advice.any);
  ASSERT_EQ(advice.robots.size(), 3u);
  // From standing, 2 m/s^2 up to 1.5 m/s (0.75 s): 250 mm in 0.5 s, 937.5 in 1 s, 1687.5 in
  // 1.5 s, along (0, 0) to (890, 0), behind the ball, then on to (2890, 0).
  const std::array<double, 3> along{250.0, 937.5, 1687.5};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(advice.robots[1].position[k].x, along[k], 1e-6) << k;
    EXPECT_NEAR(advice.robots[1].position[k].y, 0.0, 1e-6) << k;
    EXPECT_DOUBLE_EQ(advice.robots[1].weight[k], BallPlacementPath::weight);
    EXPECT_EQ(advice.robots[0].weight[k], 0.0);
    EXPECT_EQ(advice.robots[2].weight[k], 0.0);
  }
  // A tenth of a second ahead the path counts a fifth as much as from half a second on.
  advise_ball_placement(robots, Point{1000.0, 0.0}, Point{3000.0, 0.0}, 0.1, 1, advice);
  EXPECT_DOUBLE_EQ(advice.robots[1].weight[0], BallPlacementPath::weight / 5.0);
}

TEST(BallPlacementPath, ABallOnItsSpotIsApproachedStraightAndNoRobotsGetNoAdvice) {
  std::vector<MotionRobot> robots(2);
  robots[0].position = {0.0, 0.0};
  robots[1].robot_id = 1;
  robots[1].position = {1500.0, 0.0};
  SetPlayAdvice advice;
  // The ball within the 0.15 m the rules allow, on its spot: robot 1 goes straight at it (not
  // round it) and stops 110 mm short, 390 mm on; 250 mm in the first 0.5 s from standing.
  for (const Point spot : {Point{1000.0, 0.0}, Point{1100.0, 100.0}}) {
    advise_ball_placement(robots, Point{1000.0, 0.0}, spot, 0.5, 3, advice);
    ASSERT_TRUE(advice.any);
    ASSERT_EQ(advice.robots.size(), 2u);
    EXPECT_NEAR(advice.robots[1].position[0].x, 1250.0, 1e-6);
    EXPECT_NEAR(advice.robots[1].position[2].x, 1110.0, 1e-6);
    EXPECT_NEAR(advice.robots[1].position[2].y, 0.0, 1e-6);
    for (const double w : advice.robots[0].weight) EXPECT_EQ(w, 0.0);
  }
  advise_ball_placement({}, Point{1000.0, 0.0}, Point{3000.0, 0.0}, 0.5, 3, advice);
  EXPECT_FALSE(advice.any);
  EXPECT_TRUE(advice.robots.empty());
  // More steps than an advice holds: the first 16 are advised, for robot 1, nearest the ball.
  advise_ball_placement(robots, Point{1000.0, 0.0}, Point{3000.0, 0.0}, 0.5, 40, advice);
  EXPECT_TRUE(advice.any);
  EXPECT_GT(advice.robots[1].weight.back(), 0.0);
  EXPECT_EQ(advice.robots[0].weight.back(), 0.0);
}

TEST(BallPlacementPath, ARobotWithTheBallCarriesItOnAndStopsBehindTheSpot) {
  std::vector<MotionRobot> robots(1);
  robots[0].robot_id = 1;
  robots[0].position = {890.0, 0.0};  // behind the ball at (1000, 0), already at 1.5 m/s
  robots[0].has_velocity = true;
  robots[0].kinematics.velocity = {1500.0, 0.0};
  SetPlayAdvice advice;
  advise_ball_placement(robots, Point{1000.0, 0.0}, Point{3000.0, 0.0}, 1.0, 2, advice);
  EXPECT_NEAR(advice.robots[0].position[0].x, 2390.0, 1e-6);
  // 2 m of the way in 1.33 s; there it stays, the ball on the spot at its feet.
  EXPECT_NEAR(advice.robots[0].position[1].x, 2890.0, 1e-6);
  EXPECT_NEAR(advice.robots[0].position[1].y, 0.0, 1e-6);
}

TEST(GameRules, AtTheirOpponentsKickoffTheRobotsAreForecastInTheirHalfOutsideTheCentreCircle) {
  Learning learning;
  play(learning, Script{}, 0.0, 60.0);
  Script script;
  script.ball = [](double) { return std::optional<Point>(Point{0.0, 0.0}); };
  // Every robot in its own half by the time of the kick-off, one of them about to cross it.
  script.robot = [](int id, double t) {
    const Point p = circling(id, t);
    return Point{p.x - 3100.0, p.y};
  };
  // Blue (us) kicks off: every yellow robot stays in its half and out of the centre circle.
  script.command = [](double t) {
    return t < 5.0 ? Referee::NORMAL_START : Referee::PREPARE_KICKOFF_BLUE;
  };
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 10.0);
  int checked = 0;
  for (const Forecast& f : forecasting.seen) {
    if (f.state != GameState::kickoff_preparation) continue;
    for (const PredictedStep& step : f.prediction.steps) {
      for (const RobotPrediction& p : step.robots) {
        EXPECT_LE(p.normalised_position.x, 1e-6);
        EXPECT_GE(distance(p.normalised_position, Point{0.0, 0.0}), 500.0 - 1e-6);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(GameRules, AtOurFreeKickTheDefendersKeepTheirDistanceUntilTheBallMoves) {
  Script script;
  script.robot = charging;
  Learning learning;
  play(learning, script, 0.0, 60.0);
  // Blue (us) takes a free kick at 5 s; the ball leaves at 2 m/s from 7 s.
  script.command = [](double t) {
    return t < 5.0 ? Referee::NORMAL_START : Referee::DIRECT_FREE_BLUE;
  };
  script.ball = [](double t) {
    return std::optional<Point>(Point{2000.0 - 2000.0 * std::max(0.0, t - 7.0), 0.0});
  };
  Forecasting forecasting(*learning.learner);
  play(forecasting, script, 0.0, 8.0);
  int kept = 0, free = 0;
  for (const Forecast& f : forecasting.seen) {
    if (f.state != GameState::free_kick) continue;
    const double t = f.time_s - start_s;
    bool all_clear = true;
    for (const PredictedStep& step : f.prediction.steps) {
      for (const RobotPrediction& p : step.robots) {
        all_clear = all_clear && distance(p.normalised_position, *f.ball) >= 500.0 - 1e-6;
      }
    }
    if (t < 6.9) {
      EXPECT_TRUE(all_clear) << t;
      ++kept;
    } else if (t > 7.3 && !all_clear) {
      ++free;  // in play: the rule no longer holds, the table's extrapolation goes on
    }
  }
  EXPECT_GT(kept, 100);
  EXPECT_GT(free, 0);
}

TEST(MotionRules, AnyForecastIsMovedTheLeastThatSatisfiesTheRules) {
  MotionRules rules;
  rules.max_speed_mm_s = 1500.0;
  rules.keep_away_from = Point{0.0, 0.0};
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-2000.0, 2000.0);
  for (int i = 0; i < 10000; ++i) {
    const Point from{coordinate(random), coordinate(random)};
    const Point to{coordinate(random), coordinate(random)};
    const double horizon_s = 0.5 * (1 + i % 4);
    const Point ruled = rules.apply(1, from, horizon_s, to);
    EXPECT_GE(distance(ruled, {0.0, 0.0}), 500.0 - 1e-6);
    if (distance(from, {0.0, 0.0}) >= 500.0) {
      EXPECT_LE(distance(ruled, from), 1500.0 * horizon_s + 1e-6);
    }
    if (distance(to, {0.0, 0.0}) >= 500.0 && distance(to, from) <= 1500.0 * horizon_s) {
      EXPECT_EQ(ruled, to);  // a forecast within the rules is left alone
    }
  }
  // A placement path: the stadium about the segment from the ball to the target, at any speed.
  MotionRules placement;
  placement.keep_away_from = Point{0.0, 0.0};
  placement.keep_away_to = Point{1500.0, 1000.0};
  for (int i = 0; i < 10000; ++i) {
    const Point from{coordinate(random), coordinate(random)};
    const Point to{coordinate(random), coordinate(random)};
    const Point ruled = placement.apply(1, from, 0.5, to);
    EXPECT_GE(distance_to_segment(ruled, {0.0, 0.0}, {1500.0, 1000.0}), 500.0 - 1e-6);
    if (distance_to_segment(to, {0.0, 0.0}, {1500.0, 1000.0}) >= 500.0) {
      EXPECT_EQ(ruled, to);
    } else {  // moved the least: onto the stadium's edge
      EXPECT_NEAR(distance_to_segment(ruled, {0.0, 0.0}, {1500.0, 1000.0}), 500.0, 1e-6);
    }
  }
  // On the path itself: off it sideways.
  const Point off = placement.apply(1, {750.0, 500.0}, 0.5, {750.0, 500.0});
  EXPECT_NEAR(distance_to_segment(off, {0.0, 0.0}, {1500.0, 1000.0}), 500.0, 1e-6);
  // The exempt robot (the one placing the ball) goes where the model says.
  rules.exempt_robot_id = 4;
  EXPECT_EQ(rules.apply(4, {3000.0, 0.0}, 0.5, {10.0, 0.0}), (Point{10.0, 0.0}));
  // A kick-off: its own half.
  MotionRules kickoff;
  kickoff.own_half = true;
  EXPECT_EQ(kickoff.apply(1, {-100.0, 300.0}, 0.5, {800.0, 900.0}), (Point{0.0, 900.0}));
  // A robot still in the other half is on its way back: the model says where it gets to.
  EXPECT_EQ(kickoff.apply(1, {2500.0, 300.0}, 0.5, {1800.0, 300.0}), (Point{1800.0, 300.0}));
}

}  // namespace
}  // namespace ssl_formation
