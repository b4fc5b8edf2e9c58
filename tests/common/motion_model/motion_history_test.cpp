// The training side of the motion model (common/motion_model/src/motion_history.cpp and
// motion_features.cpp): whole_mm's rounding (one value or a point's two at once), on which every
// learned row depends, kept bit for bit through its speed-ups.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <tuple>
#include <vector>

#include "ssl_formation/motion_model/motion_model.hpp"

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
  // The two-at-a-time form training uses (SSE2 where there is one), each value in each place and
  // next to each of a few others.
  const std::array<double, 6> partners{
      0.0, -0.5, 2.5, -1.0e12, 1.0e9 - 0.5, std::numeric_limits<double>::infinity()};
  for (const double value : values) {
    for (const double partner : partners) {
      const sf::WholePoint first = sf::whole_mm(sf::Point{value, partner});
      const sf::WholePoint second = sf::whole_mm(sf::Point{partner, value});
      ASSERT_EQ(first.x, whole_mm_as_trained(value)) << value << " beside " << partner;
      ASSERT_EQ(first.y, whole_mm_as_trained(partner)) << partner << " beside " << value;
      ASSERT_EQ(second.x, whole_mm_as_trained(partner)) << partner << " beside " << value;
      ASSERT_EQ(second.y, whole_mm_as_trained(value)) << value << " beside " << partner;
    }
  }
}

// Real logs' camera packets each cover part of the field: a robot carried over from an earlier
// packet (FormationRobot::observed false) is no new observation.
sf::Formation formation_at(double time_s, std::vector<std::pair<sf::Point, bool>> robots) {
  sf::Formation formation;
  formation.time_s = time_s;
  for (std::size_t id = 0; id < robots.size(); ++id) {
    sf::FormationRobot& robot = formation.robots.emplace_back();
    robot.robot_id = static_cast<std::uint32_t>(id);
    robot.position = robot.feed_position = robots[id].first;
    robot.observed = robots[id].second;
  }
  return formation;
}

TEST(MotionHistory, ARobotCarriedOverKeepsItsLastEntryAndItsVelocityCountsForTheTeam) {
  sf::MotionConfig config;
  config.step_s = 0.5;
  sf::MotionHistory history(config);
  // Robot 0 drives along x at 1 m/s, robot 1 along y at 1 m/s, both seen at 50 Hz for a second.
  for (int i = 0; i <= 50; ++i) {
    const double t = i / 50.0;
    history.add(formation_at(t, {{{1000.0 * t, 0.0}, true}, {{0.0, 1000.0 * t}, true}}));
  }
  // Then a packet sees robot 0 only; robot 1 is where it was last seen.
  history.add(formation_at(1.02, {{{1020.0, 0.0}, true}, {{0.0, 1000.0}, false}}));
  const sf::MotionHistory::Entry* carried = history.latest(1);
  ASSERT_NE(carried, nullptr);
  EXPECT_DOUBLE_EQ(carried->time_s, 1.0);  // no entry stamped 1.02 at its 1.0 position
  EXPECT_NEAR(carried->kinematics.velocity.y, 1000.0, 1e-6);
  const sf::MotionHistory::Entry* seen = history.latest(0);
  ASSERT_NE(seen, nullptr);
  EXPECT_DOUBLE_EQ(seen->time_s, 1.02);
  EXPECT_NEAR(seen->kinematics.velocity.x, 1000.0, 1e-6);
  // The team's mean velocity is both robots' latest: (1000, 0) and (0, 1000).
  EXPECT_NEAR(seen->kinematics.team_velocity.x, 500.0, 1e-6);
  EXPECT_NEAR(seen->kinematics.team_velocity.y, 500.0, 1e-6);
  // Seen again, it continues its track at the right spacing: the velocity is still 1 m/s.
  history.add(formation_at(1.04, {{{1040.0, 0.0}, true}, {{0.0, 1040.0}, true}}));
  EXPECT_NEAR(history.latest(1)->kinematics.velocity.y, 1000.0, 1e-6);
}

TEST(MotionHistory, ARobotCarriedOverLearnsNothingMoreThanOneLeftOut) {
  sf::MotionConfig config;
  config.step_s = 0.5;
  config.horizons = 2;
  config.calibration_one_in = 1000000;  // every instance counted in rows
  // Two streams: robot 1 vanishes from the packets at 2 s; in one it is carried over (as a
  // sampler does within its freshness window), in the other it leaves the formations.
  const auto train = [&](bool carry_over) {
    sf::MotionTable table(config);
    sf::MotionHistory history(config);
    for (int i = 0; i <= 150; ++i) {
      const double t = i / 50.0;
      const double seen_t = std::min(t, 2.0);
      std::vector<std::pair<sf::Point, bool>> robots{{{1000.0 * t, 0.0}, true}};
      if (t <= 2.0 || carry_over) robots.push_back({{0.0, 800.0 * seen_t}, t <= 2.0});
      const sf::Formation now = formation_at(t, robots);
      history.add(now);
      sf::learn_motion(table, history, now);
    }
    return table;
  };
  // Instances learned per robot (the team velocity in robot 0's differs: the carried robot's
  // last velocity still counts in it).
  const auto per_robot = [](const sf::MotionTable& table) {
    std::array<std::int64_t, 2> n{};
    for (const auto& [key, row] : table.sorted_rows()) {
      n.at(static_cast<std::size_t>(sf::decode_motion_key(key).robot_slot)) += row.n();
    }
    return n;
  };
  const std::array<std::int64_t, 2> carried = per_robot(train(true));
  const std::array<std::int64_t, 2> left_out = per_robot(train(false));
  EXPECT_GT(carried[0], carried[1]);  // robot 0 learns on after 2 s
  EXPECT_GT(carried[1], 15);
  EXPECT_EQ(carried, left_out);
}

TEST(MotionHistory, LaterHorizonsAreLearnedAtEverySecondLearningInstant) {
  sf::MotionConfig config;
  config.step_s = 0.5;
  config.horizons = 3;
  config.calibration_one_in = 1000000;  // every instance counted in rows
  sf::MotionTable table(config);
  sf::MotionHistory history(config);
  // One robot driving along x at 1 m/s, seen at 50 Hz for 10 s: learning instants every 0.1 s.
  for (int i = 0; i <= 500; ++i) {
    const double t = i / 50.0;
    const sf::Formation now = formation_at(t, {{{1000.0 * t - 4000.0, 0.0}, true}});
    history.add(now);
    sf::learn_motion(table, history, now);
  }
  std::array<std::int64_t, 3> per_horizon{};
  for (const auto& [key, row] : table.sorted_rows()) {
    per_horizon.at(static_cast<std::size_t>(sf::decode_motion_key(key).horizon_index)) += row.n();
  }
  // Horizon k is learnable from (k x 0.5 s + the velocity window) on: about 10 a second for the
  // first, 5 for the others.
  EXPECT_NEAR(static_cast<double>(per_horizon[0]), 10 * (10.0 - 0.6), 2.0);
  EXPECT_NEAR(static_cast<double>(per_horizon[1]), 5 * (10.0 - 1.1), 2.0);
  EXPECT_NEAR(static_cast<double>(per_horizon[2]), 5 * (10.0 - 1.6), 2.0);
}

// A vision ghost carrying a robot's id (real logs have them, docs/simulation.md): robot 0 drives
// along x at 1 m/s and for 5 frames is reported 3 m away.
TEST(MotionHistory, ARobotThatJumpsStartsItsTrackAgainAndNothingIsLearnedAcrossTheJump) {
  sf::MotionConfig config;
  config.step_s = 0.5;
  config.horizons = 2;
  config.calibration_one_in = 1000000;  // every instance counted in rows
  const auto ghost_from = [](int frame) { return frame >= 150 && frame < 155; };
  const auto train = [&](bool with_ghost) {
    sf::MotionTable table(config);
    sf::MotionHistory history(config);
    std::optional<sf::Point> velocity_at_ghost;
    for (int i = 0; i <= 300; ++i) {
      const double t = i / 50.0;
      const bool ghost = with_ghost && ghost_from(i);
      const sf::Point at =
          ghost ? sf::Point{1000.0 * t, 3000.0} : sf::Point{1000.0 * t - 3000.0, 0.0};
      const sf::Formation now = formation_at(t, {{at, true}});
      history.add(now);
      if (i == 152 && history.latest(0)->has_velocity) {
        velocity_at_ghost = history.latest(0)->kinematics.velocity;
      }
      sf::learn_motion(table, history, now);
    }
    // The largest mean square displacement of a row: no row holds the ghost's 3 m moves.
    std::int64_t largest_square = 0;
    for (const auto& [key, row] : table.sorted_rows()) {
      largest_square = std::max(largest_square, row.dd() / std::max<std::int64_t>(row.n(), 1));
    }
    return std::tuple(table.instances(), largest_square, velocity_at_ghost);
  };
  const auto [clean_instances, clean_largest, clean_velocity] = train(false);
  const auto [instances, largest, velocity] = train(true);
  // The ghost's frames have no velocity (a track started there 2 frames before) ...
  ASSERT_TRUE(clean_velocity.has_value());
  EXPECT_FALSE(velocity.has_value());
  // ... and the instances learned across them are left out, not learned as 3 m moves: fewer
  // instances, none larger than a clean stream's.
  EXPECT_LT(instances, clean_instances);
  EXPECT_GT(instances, clean_instances / 2);
  EXPECT_EQ(largest, clean_largest);
}

TEST(MotionFeatures, AJumpIsFurtherThanARobotCanMove) {
  // 4 m/s for 0.1 s is 400 mm: motion. Half a metre in 11 ms: a jump. Vision noise is not.
  EXPECT_FALSE(sf::MotionFeatures::is_jump({0.0, 0.0}, 1.0, {400.0, 0.0}, 1.1));
  EXPECT_TRUE(sf::MotionFeatures::is_jump({0.0, 0.0}, 1.0, {0.0, 500.0}, 1.011));
  EXPECT_FALSE(sf::MotionFeatures::is_jump({0.0, 0.0}, 1.0, {30.0, -30.0}, 1.011));
  // Unseen for a second, a robot may turn up metres away.
  EXPECT_FALSE(sf::MotionFeatures::is_jump({0.0, 0.0}, 1.0, {3000.0, 3000.0}, 2.0));
}

}  // namespace

TEST(MotionHistory, AnEntrysContextIsItsStandingTimeAndWhereItsTeamIs) {
  sf::MotionConfig config;
  config.step_s = 0.5;
  sf::MotionHistory history(config);
  // Robot 0 stands still, robots 1 and 2 drive along x at 0.4 m/s: the team's mean velocity is
  // 267 mm/s, on the move. The team's centroid is 2 m into its own half for 1.5 s, then 2 m into
  // the half it attacks.
  const auto at = [](double t, double centroid_x) {
    sf::Formation formation = formation_at(t, {{{-2000.0, 500.0}, true},
                                               {{-2000.0 + 400.0 * t, -500.0}, true},
                                               {{-2000.0 + 400.0 * t, 1500.0}, true}});
    formation.centroid = {centroid_x, 0.0};
    return formation;
  };
  for (int i = 0; i <= 75; ++i) history.add(at(i / 50.0, -2000.0));
  // The team's mean velocity is 267 mm/s: on the move.
  const std::uint32_t stood_1_5_s = sf::MotionFeatures::standing_context(1.5);
  const int behind_moving = sf::MotionFeatures::team_phase({-2000.0, 0.0}, {267.0, 0.0});
  EXPECT_EQ(history.latest(0)->context, sf::MotionFeatures::context(stood_1_5_s, behind_moving));
  EXPECT_EQ(history.latest(1)->context, sf::MotionFeatures::context(0, behind_moving));
  history.add(at(1.52, 2000.0));
  // The team moved on; the standing robot's clock did not restart.
  const int ahead_moving = sf::MotionFeatures::team_phase({2000.0, 0.0}, {267.0, 0.0});
  EXPECT_NE(ahead_moving, behind_moving);
  EXPECT_EQ(history.latest(0)->context, sf::MotionFeatures::context(stood_1_5_s, ahead_moving));
  EXPECT_EQ(history.latest(1)->context, sf::MotionFeatures::context(0, ahead_moving));
  // When robot 2 stops, the team's mean falls to 133 mm/s (its sum, 400 mm/s, would not): the
  // team stands, another phase.
  for (int i = 77; i <= 150; ++i) {
    const double t = i / 50.0;
    sf::Formation formation = formation_at(t, {{{-2000.0, 500.0}, true},
                                               {{-2000.0 + 400.0 * t, -500.0}, true},
                                               {{-1392.0, 1500.0}, true}});
    formation.centroid = {2000.0, 0.0};
    history.add(formation);
  }
  const int ahead_standing = sf::MotionFeatures::team_phase({2000.0, 0.0}, {0.0, 0.0});
  EXPECT_NE(ahead_standing, ahead_moving);
  EXPECT_EQ(history.latest(0)->context,
            sf::MotionFeatures::context(sf::MotionFeatures::standing_context(3.0), ahead_standing));
  EXPECT_EQ(history.latest(1)->context, sf::MotionFeatures::context(0, ahead_standing));
  // A robot carried over (not observed) keeps the context of its last observation.
  sf::Formation carried = formation_at(3.02, {{{-2000.0, 500.0}, true},
                                              {{-2000.0 + 400.0 * 3.02, -500.0}, false},
                                              {{-1392.0, 1500.0}, true}});
  carried.centroid = {-2000.0, 0.0};
  history.add(carried);
  EXPECT_EQ(history.latest(1)->context, sf::MotionFeatures::context(0, ahead_standing));
  EXPECT_NE(history.latest(0)->context,
            sf::MotionFeatures::context(sf::MotionFeatures::standing_context(3.0), ahead_standing));
}

TEST(MotionHistory, ABallInFlightGoesIntoTheContextAndTheCoarseLevelsLeaveItOut) {
  sf::MotionConfig config;
  config.step_s = 0.5;
  sf::MotionHistory history(config);
  const auto at = [](double t) {
    sf::Formation formation = formation_at(t, {{{-2000.0 + 400.0 * t, 0.0}, true}});
    formation.centroid = {-2000.0 + 400.0 * t, 0.0};
    return formation;
  };
  const std::uint32_t halt = sf::MotionFeatures::halt_game;
  // A pass at 3 m/s, then the ball at rest (0.6 m/s is rolling out, not a pass).
  for (int i = 0; i <= 25; ++i) history.add(at(i / 50.0), halt, {0.0, 3000.0});
  const int team_phase = sf::MotionFeatures::team_phase({-1800.0, 0.0}, {400.0, 0.0});
  const std::uint32_t flying = history.latest(0)->context;
  EXPECT_EQ(flying, sf::MotionFeatures::context(0, team_phase, halt, true));
  EXPECT_TRUE(sf::MotionFeatures::ball_in_flight_of(flying));
  history.add(at(0.52), halt, {600.0, 0.0});
  const std::uint32_t resting = history.latest(0)->context;
  EXPECT_EQ(resting, sf::MotionFeatures::context(0, team_phase, halt, false));
  EXPECT_EQ(sf::MotionFeatures::game_context_of(flying), halt);
  EXPECT_EQ(sf::MotionFeatures::game_context_of(resting), halt);
  // The robot's and the zone's rows tell the two apart; the coarse levels pool them.
  sf::MotionKeyParts parts{0, sf::MotionLevel::robot, 0, 10, 3, flying};
  sf::MotionKeyParts other = parts;
  other.context = resting;
  sf::MotionKey a = sf::encode_motion_key(parts), b = sf::encode_motion_key(other);
  for (int level = 0; level < sf::motion_levels; ++level) {
    const auto at_level = static_cast<sf::MotionLevel>(level);
    EXPECT_EQ(a == b, at_level == sf::MotionLevel::velocity || at_level == sf::MotionLevel::all)
        << level;
    a = sf::coarser_motion_key(a);
    b = sf::coarser_motion_key(b);
  }
}
