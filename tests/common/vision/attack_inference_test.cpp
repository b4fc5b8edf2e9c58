// --opponent-attacks auto: the direction from where the goalkeeper stands, switching when the
// teams change ends, never on an attacker lingering at the other goal.

#include "ssl_formation/vision/attack_inference.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
namespace {

const FieldSize division_a{12000, 9000};

// Six robots: a goalkeeper on the goal line at `keeper_x`, five field players moving about.
std::vector<AttackInference::Robot> team(double t, double keeper_x) {
  std::vector<AttackInference::Robot> robots{{0, {keeper_x, 100.0 * std::sin(t)}}};
  for (std::uint32_t id = 1; id < 6; ++id) {
    robots.push_back({id, {2000.0 * std::sin(0.3 * t + id), 2500.0 * std::cos(0.2 * t + id)}});
  }
  return robots;
}

TEST(AttackInference, DecidesOnceAGoalkeeperHeldAGoalForAWindowAndSwitchesAtHalfTime) {
  AttackInference inference(10.0);
  std::vector<double> decided_at;
  for (int i = 0; i <= 60 * 60; ++i) {  // 60 s at 60 Hz
    const double t = i / 60.0;
    // First half: the keeper guards the -x goal (the opponent attacks +x); from 30 s on, the
    // +x goal (after the change of ends).
    const double keeper_x = t < 30.0 ? -5900.0 : 5900.0;
    if (inference.add(t, team(t, keeper_x), division_a)) decided_at.push_back(t);
    if (t < 10.0 - 1e-9) {
      EXPECT_FALSE(inference.direction()) << t;
    }
  }
  ASSERT_EQ(decided_at.size(), 2u);
  EXPECT_NEAR(decided_at[0], 10.0, 0.05);
  // The keeper reaches the other goal at 30 s; that goal must hold him a whole window first.
  // (his average position takes a few seconds to get there).
  EXPECT_GE(decided_at[1], 40.0 - 1e-9);
  EXPECT_LE(decided_at[1], 45.0);
  EXPECT_EQ(inference.direction(), AttackDirection::negative_x);
  EXPECT_EQ(inference.switches(), 1u);
}

TEST(AttackInference, AnAttackerAtTheOtherGoalForACornerDoesNotFlipIt) {
  AttackInference inference(10.0);
  for (int i = 0; i <= 40 * 60; ++i) {
    const double t = i / 60.0;
    auto robots = team(t, -5900.0);
    // From 20 to 26 s an attacker stands right at the +x goal for a corner, nearer than the
    // keeper is to his.
    if (t > 20.0 && t < 26.0) robots[1].position = {5980.0, 0.0};
    inference.add(t, robots, division_a);
  }
  EXPECT_EQ(inference.direction(), AttackDirection::positive_x);
  EXPECT_EQ(inference.switches(), 0u);
}

TEST(AttackInference, TheSamplerWaitsForTheDirectionThenBreaksTheChainWhenEndsChange) {
  SamplerConfig config;
  config.grid = Grid(3, 2);
  config.step_s = 1.0;
  config.field = division_a;
  config.infer_attacks = true;
  config.attack_window_s = 5.0;
  std::vector<FormationSample> samples;
  FormationSampler sampler(config, [&](const FormationSample& s) { samples.push_back(s); });
  for (int i = 0; i <= 30 * 20; ++i) {  // 30 s at 20 Hz, ends changed at 15 s
    const double t = i / 20.0;
    DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = t;
    for (const auto& robot : team(t, t < 15.0 ? -5900.0 : 5900.0)) {
      spec.yellow.push_back({robot.robot_id, robot.position});
    }
    sampler.add(make_detection_packet(spec));
  }
  ASSERT_FALSE(samples.empty());
  // Nothing before the first window has passed.
  EXPECT_GE(samples.front().formation.time_s, 5.0 - 1e-9);
  EXPECT_GT(sampler.counters().samples_undirected, 0u);
  EXPECT_EQ(sampler.counters().attack_switches, 1u);
  EXPECT_EQ(sampler.attacks(), AttackDirection::negative_x);
  double switched_at = 0.0;
  for (const FormationSample& sample : samples) {
    if (sample.formation.opponent_attacks == AttackDirection::negative_x) {
      switched_at = sample.formation.time_s;
      // The sample right after the switch follows nothing.
      EXPECT_FALSE(sample.formation.continues_previous);
      EXPECT_TRUE(sample.transitions.empty());
      break;
    }
  }
  EXPECT_GT(switched_at, 20.0 - 1e-9);
  EXPECT_LT(switched_at, 25.0);
  for (const FormationSample& sample : samples) {
    const Formation& f = sample.formation;
    // Normalised, the keeper is at the opponent's own goal (-x) whenever the direction is
    // right: before the change of ends and once it is inferred.
    if (f.time_s < 15.0 || f.time_s >= switched_at) {
      ASSERT_NE(f.find(0), nullptr);
      EXPECT_LT(f.find(0)->position.x, -5000.0) << f.time_s;
    }
  }
}

}  // namespace
}  // namespace ssl_formation
