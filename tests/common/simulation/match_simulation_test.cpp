#include "ssl_formation/simulation/match_simulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <set>

namespace ssl_formation::simulation {
namespace {

MatchSimulationConfig config_with(const std::string& playbook, Division division,
                                  std::uint64_t seed = 1) {
  MatchSimulationConfig config;
  config.seed = seed;
  config.division = division;
  auto book = parse_playbook(*builtin_playbook_text(playbook), playbook);
  EXPECT_TRUE(book) << book.error().message;
  config.playbook = std::move(*book);
  return config;
}

double length(Point p) { return std::hypot(p.x, p.y); }

// Every robot of both teams, frame by frame for three minutes, against SSL robots' limits.
TEST(MatchSimulation, EveryRobotKeepsToItsSpeedAndAccelerationNeverJumpsAndNeverTouchesAnother) {
  for (const Division division : {Division::a, Division::b}) {
    SCOPED_TRACE(division == Division::a ? "Division A" : "Division B");
    MatchSimulation match(config_with("wings", division, 3));
    const MotionLimits& limits = match.config().limits;
    const double dt = 1.0 / match.config().frame_rate_hz;
    const int team = team_size_of(division);
    MatchFrame before = match.next();
    ASSERT_EQ(before.opponent.size(), static_cast<std::size_t>(team));
    ASSERT_EQ(before.ours.size(), static_cast<std::size_t>(team));
    std::vector<Point> velocity_before(2 * static_cast<std::size_t>(team), Point{0.0, 0.0});
    double fastest = 0.0;
    double hardest = 0.0;
    double closest = 1e9;
    double travelled = 0.0;
    const int frames = 60 * 180;
    for (int f = 1; f < frames; ++f) {
      const MatchFrame frame = match.next();
      ASSERT_NEAR(frame.t_capture - before.t_capture, dt, 1e-9);
      std::vector<Point> all = frame.opponent;
      all.insert(all.end(), frame.ours.begin(), frame.ours.end());
      std::vector<Point> all_before = before.opponent;
      all_before.insert(all_before.end(), before.ours.begin(), before.ours.end());
      for (std::size_t i = 0; i < all.size(); ++i) {
        const Point v{(all[i].x - all_before[i].x) / dt, (all[i].y - all_before[i].y) / dt};
        fastest = std::max(fastest, length(v));
        hardest = std::max(
            hardest, length(Point{v.x - velocity_before[i].x, v.y - velocity_before[i].y}) / dt);
        velocity_before[i] = v;
        travelled += length(v) * dt;
        // Targets are on the field; making way for one another may take a robot into the
        // boundary area (300 mm), never beyond.
        ASSERT_LE(std::abs(all[i].x), match.field().length_mm / 2 + 300.0) << "robot " << i;
        ASSERT_LE(std::abs(all[i].y), match.field().width_mm / 2 + 300.0) << "robot " << i;
        for (std::size_t j = i + 1; j < all.size(); ++j) {
          closest = std::min(closest, length(Point{all[i].x - all[j].x, all[i].y - all[j].y}));
        }
      }
      before = frame;
    }
    // Speeds measured from positions: a little rounding over the limits' own figures.
    EXPECT_LE(fastest, limits.max_speed_mm_s * 1.000001);
    EXPECT_LE(hardest, limits.max_acceleration_mm_s2 * 1.0001);
    EXPECT_GE(closest, 2.0 * limits.robot_radius_mm) << "two robots touched";
    // And they play: on average a third of a metre a second each (keepers and waiting robots
    // included: 0.33-0.36 m/s with the built-in playbooks), and fast at times.
    EXPECT_GT(travelled / (2.0 * team) / 180.0, 250.0);
    EXPECT_GT(fastest, 2000.0);
  }
}

TEST(MatchSimulation, TheOpponentRunsThePlaybooksPlaysWithPassesAndShots) {
  MatchSimulation match(config_with("wings", Division::a, 5));
  std::set<std::string> plays;
  for (int f = 0; f < 60 * 300; ++f) {
    const MatchFrame frame = match.next();
    if (!frame.play.empty()) plays.insert(frame.play);
  }
  EXPECT_GE(plays.size(), 5u);
  EXPECT_TRUE(plays.count("kick-off"));
  EXPECT_GT(match.plays_started(), 25u);
  EXPECT_GT(match.passes(), 25u);
  EXPECT_GT(match.shots(), 5u);
  EXPECT_GT(match.goals(), 0u);
  EXPECT_LT(match.goals(), match.shots());
  EXPECT_TRUE(plays.count("corner from the left") || plays.count("corner from the right"))
      << "free kicks after shots wide";
}

TEST(MatchSimulation, ThePacketsAreWholeSslVisionFramesOnEveryCameraWithTheGeometry) {
  MatchSimulationConfig config = config_with("centre", Division::a, 2);
  config.opponent_color = TeamColor::blue;
  config.opponent_attacks = AttackDirection::negative_x;
  config.jitter_mm = 5.0;
  MatchSimulation match(config);
  int geometry = 0;
  std::set<std::uint32_t> cameras;
  for (int f = 0; f < 600; ++f) {
    const MatchFrame frame = match.next();
    int blue = 0;
    int yellow = 0;
    for (const SSL_WrapperPacket& packet : frame.packets) {
      ASSERT_TRUE(packet.IsInitialized()) << packet.InitializationErrorString();
      SSL_WrapperPacket parsed;
      ASSERT_TRUE(parsed.ParseFromString(packet.SerializeAsString()));
      if (packet.has_geometry()) {
        ++geometry;
        EXPECT_EQ(packet.geometry().field().field_length(), 12000);
        continue;
      }
      cameras.insert(packet.detection().camera_id());
      EXPECT_DOUBLE_EQ(packet.detection().t_capture(), frame.t_capture);
      blue += packet.detection().robots_blue_size();
      yellow += packet.detection().robots_yellow_size();
      // The opponent (blue) attacks -x: in the feed its keeper stands near +x.
      for (const auto& robot : packet.detection().robots_blue()) {
        if (robot.robot_id() == 0) {
          EXPECT_GT(robot.x(), 5000.0);
        }
      }
    }
    // Every robot is seen by at least one camera (overlaps see some twice).
    EXPECT_GE(blue, 11);
    EXPECT_GE(yellow, 11);
  }
  EXPECT_EQ(cameras.size(), 4u);
  EXPECT_EQ(geometry, 4) << "one every 3 s of 10 s";
}

TEST(MatchSimulation, TheSameSeedGivesTheSameBytesAndAnotherSeedOthers) {
  const auto bytes = [](std::uint64_t seed) {
    MatchSimulationConfig config = config_with("wings", Division::b, seed);
    config.jitter_mm = 3.0;
    config.drop_rate = 0.05;
    MatchSimulation match(config);
    std::string all;
    for (int f = 0; f < 1200; ++f) {
      for (const SSL_WrapperPacket& packet : match.next().packets) {
        all += packet.SerializeAsString();
      }
    }
    return all;
  };
  const std::string first = bytes(8);
  EXPECT_EQ(first, bytes(8));
  EXPECT_NE(first, bytes(9));
}

MatchSimulationConfig refereed(Division division, std::uint64_t seed, double half_s) {
  MatchSimulationConfig config = config_with("wings", division, seed);
  GameControllerConfig game;
  game.half_s = half_s;
  config.game = game;
  return config;
}

Point feed(Point normalised, AttackDirection attacks) { return normalise(normalised, attacks); }

// With the game controller: halves, stoppages and the change of ends, every robot still within
// its limits on the wire (feed coordinates), where the change of ends moves nothing.
TEST(MatchSimulation, WithTheRefereeEveryRobotStillKeepsToItsLimitsThroughHalfTime) {
  MatchSimulation match(refereed(Division::b, 4, 60.0));
  const MotionLimits& limits = match.config().limits;
  const double dt = 1.0 / match.config().frame_rate_hz;
  MatchFrame before = match.next();
  std::vector<Point> velocity_before(12, Point{0.0, 0.0});
  double fastest = 0.0;
  double hardest = 0.0;
  double closest = 1e9;
  std::set<bool> sides;
  for (int f = 1; f < 60 * 400; ++f) {
    const MatchFrame frame = match.next();
    ASSERT_TRUE(frame.referee.has_value());
    sides.insert(frame.referee->blue_team_on_positive_half());
    std::vector<Point> all;
    std::vector<Point> all_before;
    for (const auto* robots : {&frame.opponent, &frame.ours}) {
      for (const Point p : *robots) all.push_back(feed(p, frame.opponent_attacks));
    }
    for (const auto* robots : {&before.opponent, &before.ours}) {
      for (const Point p : *robots) all_before.push_back(feed(p, before.opponent_attacks));
    }
    for (std::size_t i = 0; i < all.size(); ++i) {
      const Point v{(all[i].x - all_before[i].x) / dt, (all[i].y - all_before[i].y) / dt};
      fastest = std::max(fastest, length(v));
      hardest = std::max(
          hardest, length(Point{v.x - velocity_before[i].x, v.y - velocity_before[i].y}) / dt);
      velocity_before[i] = v;
      for (std::size_t j = i + 1; j < all.size(); ++j) {
        closest = std::min(closest, length(Point{all[i].x - all[j].x, all[i].y - all[j].y}));
      }
    }
    before = frame;
  }
  EXPECT_LE(fastest, limits.max_speed_mm_s * 1.000001);
  EXPECT_LE(hardest, limits.max_acceleration_mm_s2 * 1.0001);
  EXPECT_GE(closest, 2.0 * limits.robot_radius_mm);
  EXPECT_EQ(sides.size(), 2u) << "the teams changed ends";
}

// What the referee says and where the ball is agree: kick-offs from the centre, free kicks
// from where the ball was placed (most are placed first), goals when the ball crossed the goal
// line, and while the game is stopped the robots keep away from the ball.
TEST(MatchSimulation, TheRefereesCommandsAndTheBallAgreeWithThePlay) {
  MatchSimulation match(refereed(Division::a, 6, 120.0));
  const double half_length = match.field().length_mm / 2;
  std::uint32_t counter = 0;
  int command = -1;
  int kickoffs = 0;
  int free_kicks = 0;
  int placed_free_kicks = 0;
  int goals = 0;
  int stops_checked = 0;
  int stops_clear = 0;
  std::uint32_t score = 0;
  Point placed;  // feed coordinates, from the last placement command
  bool have_placed = false;
  MatchFrame before = match.next();
  for (int f = 1; f < 60 * 900; ++f) {
    const MatchFrame frame = match.next();
    const Referee& referee = *frame.referee;
    const Point ball = feed(frame.ball, frame.opponent_attacks);
    if (referee.command_counter() != counter) {
      // The last frame of a STOP before a restart (not the 2 s one that ends a half, nor one a
      // HALT or a timeout cuts short): everybody but the keepers has made way for the ball.
      if (command == Referee::STOP && referee.command() != Referee::HALT &&
          referee.command() != Referee::TIMEOUT_YELLOW &&
          referee.command() != Referee::TIMEOUT_BLUE) {
        const Point before_ball = before.ball;
        bool clear = true;
        for (std::size_t id = 1; id < before.opponent.size(); ++id) {
          clear = clear && length(Point{before.opponent[id].x - before_ball.x,
                                        before.opponent[id].y - before_ball.y}) >= 500.0;
          clear = clear && length(Point{before.ours[id].x - before_ball.x,
                                        before.ours[id].y - before_ball.y}) >= 500.0;
        }
        ++stops_checked;
        stops_clear += clear ? 1 : 0;
      }
      counter = referee.command_counter();
      command = referee.command();
      if (command == Referee::BALL_PLACEMENT_YELLOW || command == Referee::BALL_PLACEMENT_BLUE) {
        ASSERT_TRUE(referee.has_designated_position());
        placed = Point{referee.designated_position().x(), referee.designated_position().y()};
        have_placed = true;
      }
      if (command == Referee::NORMAL_START &&
          (before.referee->command() == Referee::PREPARE_KICKOFF_YELLOW ||
           before.referee->command() == Referee::PREPARE_KICKOFF_BLUE)) {
        ++kickoffs;
        EXPECT_LT(length(frame.ball), 1.0) << "a kick-off from the centre, t=" << frame.t_capture;
      }
      if (command == Referee::DIRECT_FREE_YELLOW || command == Referee::DIRECT_FREE_BLUE) {
        ++free_kicks;
        if (have_placed) {
          ++placed_free_kicks;
          EXPECT_LT(length(Point{ball.x - placed.x, ball.y - placed.y}), 50.0)
              << "a free kick from where the ball was placed, t=" << frame.t_capture;
        }
        have_placed = false;
      }
      if (command == Referee::STOP) have_placed = false;
      // A goal adds one to the score (a new match starts again at 0:0).
      const std::uint32_t now_score = referee.yellow().score() + referee.blue().score();
      if (now_score > score) {
        ++goals;
        EXPECT_EQ(command, Referee::STOP);
        EXPECT_GE(before.ball.x, half_length - 1.0) << "the ball was over the goal line";
      }
      score = now_score;
    }
    before = frame;
  }
  EXPECT_GT(kickoffs, 3);
  EXPECT_GT(free_kicks, 3);
  EXPECT_GT(placed_free_kicks * 10, free_kicks * 7);
  EXPECT_GT(goals, 1);
  EXPECT_GT(stops_checked, 5);
  EXPECT_GE(stops_clear * 10, stops_checked * 9) << stops_clear << " of " << stops_checked;
}

TEST(MatchSimulation, ConfigsItCannotRunAreRefused) {
  MatchSimulationConfig config = config_with("wings", Division::a);
  config.playbook.plays.clear();
  EXPECT_THROW(MatchSimulation{config}, std::invalid_argument);
  config = config_with("wings", Division::a);
  config.frame_rate_hz = 0.0;
  EXPECT_THROW(MatchSimulation{config}, std::invalid_argument);
  config = config_with("wings", Division::a);
  config.cameras = 9;
  EXPECT_THROW(MatchSimulation{config}, std::invalid_argument);
}

}  // namespace
}  // namespace ssl_formation::simulation
