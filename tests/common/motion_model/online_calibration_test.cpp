#include "ssl_formation/motion_model/online_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace sf = ssl_formation;

namespace {

// A prediction of one step per entry: robot `id` in `cell` with `probability`.
struct Stated {
  std::uint32_t id;
  sf::Cell cell;
  double probability;
};

sf::Prediction prediction_of(const std::vector<std::vector<Stated>>& steps) {
  sf::Prediction prediction;
  for (const auto& robots : steps) {
    sf::PredictedStep step;
    for (const Stated& s : robots) {
      sf::RobotPrediction robot;
      robot.robot_id = s.id;
      robot.position = s.cell;
      robot.probability = s.probability;
      step.robots.push_back(robot);
    }
    prediction.steps.push_back(step);
  }
  return prediction;
}

// A formation at `time_s` with robot `id` seen (or carried over) in `cell`.
sf::Formation formation_at(double time_s, std::uint32_t id, sf::Cell cell, bool observed = true,
                           sf::AttackDirection attacks = sf::AttackDirection::positive_x) {
  sf::Formation formation;
  formation.time_s = time_s;
  formation.opponent_attacks = attacks;
  sf::FormationRobot robot;
  robot.robot_id = id;
  robot.cell = cell;
  robot.observed = observed;
  formation.robots.push_back(robot);
  return formation;
}

// A small prior weight: eight checks a second of one robot are a tenth of what a match gives.
sf::OnlineCalibrationSettings settings(double half_life_s, double prior_weight) {
  sf::OnlineCalibrationSettings settings;
  settings.half_life_s = half_life_s;
  settings.prior_weight = prior_weight;
  return settings;
}
const sf::OnlineCalibrationSettings quick = settings(60.0, 20.0);

constexpr sf::Cell home{2, 3};
constexpr sf::Cell elsewhere{5, 1};

// Eight predictions a second of robot 1 in `home` at `stated`, for `seconds` from `from_s`, each
// checked one step (0.5 s) later against the robot's cell `actual`. Every time is a multiple of
// 1/8 s, exact in binary, so that each prediction falls due exactly at a later frame.
void play(sf::OnlineCalibration& calibration, double from_s, double seconds, double stated,
          sf::Cell actual) {
  for (int i = 0; i < static_cast<int>(seconds * 8.0); ++i) {
    const double t = from_s + 0.125 * i;
    calibration.observe(formation_at(t, 1, actual));
    calibration.remember(prediction_of({{{1, home, stated}}}), t, 0.5,
                         sf::AttackDirection::positive_x);
  }
}

}  // namespace

TEST(OnlineCalibration, BeforeAnyCheckTheStatedProbabilitiesStand) {
  sf::OnlineCalibration calibration;
  sf::Prediction prediction = prediction_of({{{1, home, 0.3}, {2, elsewhere, 0.6}}});
  prediction.steps[0].formation_probability = 0.18;
  prediction.steps[0].confidence = 0.18;
  calibration.remember(prediction, 10.0, 0.5, sf::AttackDirection::positive_x);
  calibration.adjust(prediction);
  EXPECT_EQ(prediction.steps[0].robots[0].probability, 0.3);
  EXPECT_EQ(prediction.steps[0].robots[1].probability, 0.6);
  EXPECT_EQ(prediction.steps[0].formation_probability, 0.18);
  EXPECT_EQ(calibration.adjusted(0, 0.3), 0.3);
  EXPECT_EQ(calibration.adjusted(4, 0.3), 0.3);  // a step never predicted
  EXPECT_EQ(calibration.pending(), 2u);
}

TEST(OnlineCalibration, ARobotThatAlwaysStaysRaisesAStatedThirdAndTheFormationWithIt) {
  // A long stoppage: the table says 0.33 (running play), the robot never leaves its cell.
  sf::OnlineCalibration calibration(quick);
  play(calibration, 100.0, 60.0, 0.33, home);
  EXPECT_GT(calibration.checked(), 400u);  // 8 a second for a minute
  EXPECT_GT(calibration.adjusted(0, 0.33), 0.9);
  EXPECT_LE(calibration.adjusted(0, 0.33), sf::OnlineCalibration::max_probability);
  // Other tenths of probability have seen nothing and stand.
  EXPECT_EQ(calibration.adjusted(0, 0.75), 0.75);

  sf::Prediction prediction =
      prediction_of({{{1, home, 0.35}, {2, elsewhere, 0.8}}, {{1, home, 0.35}}});
  calibration.adjust(prediction);
  const double p = prediction.steps[0].robots[0].probability;
  EXPECT_GT(p, 0.9);
  EXPECT_EQ(prediction.steps[0].robots[1].probability, 0.8);
  EXPECT_DOUBLE_EQ(prediction.steps[0].formation_probability, p * 0.8);
  EXPECT_DOUBLE_EQ(prediction.steps[0].confidence, p * 0.8);
  // The second step was never checked: its probability stands, the confidence chains on.
  EXPECT_EQ(prediction.steps[1].robots[0].probability, 0.35);
  EXPECT_DOUBLE_EQ(prediction.steps[1].confidence, p * 0.8 * 0.35);
}

TEST(OnlineCalibration, ARobotThatAlwaysLeavesLowersAStatedNineTenths) {
  sf::OnlineCalibration calibration(quick);
  play(calibration, 100.0, 60.0, 0.92, elsewhere);
  EXPECT_LT(calibration.adjusted(0, 0.92), 0.1);
  EXPECT_GE(calibration.adjusted(0, 0.92), sf::OnlineCalibration::min_probability);
}

TEST(OnlineCalibration, WhatHappensAsStatedChangesNothing) {
  // Hits at the rate stated: the correction stays near zero.
  sf::OnlineCalibration calibration;
  for (int i = 0; i < 600; ++i) {
    const double t = 0.125 * i;
    calibration.observe(formation_at(t, 1, i % 2 == 0 ? home : elsewhere));
    calibration.remember(prediction_of({{{1, home, 0.5}}}), t, 0.5,
                         sf::AttackDirection::positive_x);
  }
  EXPECT_GT(calibration.checked(), 500u);
  EXPECT_NEAR(calibration.adjusted(0, 0.5), 0.5, 0.02);
}

TEST(OnlineCalibration, AProbabilityOnATenthIsCheckedAndAdjustedInTheSameBin) {
  // 0.7 and 0.9 are a hair below their tenth as floats: the evidence must still go to the bin
  // adjust() reads for them.
  for (const double stated : {0.3, 0.7, 0.9}) {
    sf::OnlineCalibration calibration(quick);
    play(calibration, 100.0, 60.0, stated, home);
    EXPECT_GT(calibration.adjusted(0, stated), 0.95) << stated;
  }
}

TEST(OnlineCalibration, ANonFiniteProbabilityIsLeftAsItIsAndLearnsNothing) {
  sf::OnlineCalibration calibration(quick);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  calibration.remember(prediction_of({{{1, home, nan}, {2, home, 0.5}}}), 10.0, 0.5,
                       sf::AttackDirection::positive_x);
  EXPECT_EQ(calibration.pending(), 1u);
  play(calibration, 100.0, 20.0, 0.5, home);
  EXPECT_GT(calibration.adjusted(0, 0.5), 0.5);
  EXPECT_TRUE(std::isnan(calibration.adjusted(0, nan)));
}

TEST(OnlineCalibration, OnlyPredictionsWhoseInstantHasComeAreChecked) {
  sf::OnlineCalibration calibration;
  calibration.remember(prediction_of({{{1, home, 0.3}}, {{1, home, 0.3}}}), 10.0, 0.5,
                       sf::AttackDirection::positive_x);
  calibration.observe(formation_at(10.49, 1, home));
  EXPECT_EQ(calibration.checked(), 0u);
  EXPECT_EQ(calibration.adjusted(0, 0.3), 0.3);
  calibration.observe(formation_at(10.5, 1, home));
  EXPECT_EQ(calibration.checked(), 1u);  // the first step; the second is due at 11.0
  // The corrections are worked out again a tenth of a second later.
  calibration.observe(formation_at(10.6, 2, home));
  EXPECT_GT(calibration.adjusted(0, 0.3), 0.3);
  EXPECT_EQ(calibration.adjusted(1, 0.3), 0.3);
  calibration.observe(formation_at(11.0, 1, elsewhere));
  EXPECT_EQ(calibration.checked(), 2u);
  calibration.observe(formation_at(11.1, 2, home));
  EXPECT_LT(calibration.adjusted(1, 0.3), 0.3);
  EXPECT_EQ(calibration.pending(), 0u);
}

TEST(OnlineCalibration, PredictionsAreRememberedATenthOfASecondApart) {
  // Frames 16 ms apart say almost the same thing: one in six is checked at 60 Hz.
  sf::OnlineCalibration calibration;
  const auto attacks = sf::AttackDirection::positive_x;
  for (int i = 0; i < 60; ++i) {
    calibration.remember(prediction_of({{{1, home, 0.3}, {2, home, 0.3}}}), 10.0 + i / 60.0, 2.0,
                         attacks);
  }
  EXPECT_EQ(calibration.pending(), 2u * 10u);
}

TEST(OnlineCalibration, ARobotNotSeenWhenDueWaitsWithinTheToleranceOnly) {
  sf::OnlineCalibration calibration;
  const auto attacks = sf::AttackDirection::positive_x;
  calibration.remember(prediction_of({{{1, home, 0.3}}}), 10.0, 0.5, attacks);
  calibration.remember(prediction_of({{{1, home, 0.3}}}), 20.0, 0.5, attacks);
  // Carried over from an earlier frame: not a sighting. Seen 30 ms later: checked.
  calibration.observe(formation_at(10.5, 1, home, /*observed=*/false));
  EXPECT_EQ(calibration.checked(), 0u);
  EXPECT_EQ(calibration.pending(), 2u);
  calibration.observe(formation_at(10.53, 1, home));
  EXPECT_EQ(calibration.checked(), 1u);
  // The second is missing until past the tolerance (50 ms): dropped unchecked.
  calibration.observe(formation_at(20.5, 2, home));
  calibration.observe(formation_at(20.56, 1, home));
  EXPECT_EQ(calibration.checked(), 1u);
  EXPECT_EQ(calibration.pending(), 0u);
}

TEST(OnlineCalibration, PredictionsMadeBeforeAChangeOfEndsAreNotCheckedAfterIt) {
  // The cells of a formation normalised the other way mean other places on the field.
  sf::OnlineCalibration calibration;
  calibration.remember(prediction_of({{{1, home, 0.3}}}), 10.0, 0.5,
                       sf::AttackDirection::positive_x);
  calibration.observe(formation_at(10.5, 1, home, true, sf::AttackDirection::negative_x));
  EXPECT_EQ(calibration.checked(), 0u);
  EXPECT_EQ(calibration.pending(), 0u);
}

TEST(OnlineCalibration, EvidenceFadesWithTheDataClock) {
  sf::OnlineCalibration calibration(settings(10.0, 20.0));
  play(calibration, 100.0, 30.0, 0.33, home);
  const double fresh = calibration.adjusted(0, 0.33);
  EXPECT_GT(fresh, 0.8);
  // A minute without predictions: six half-lives, the evidence is 1/64 of what it was.
  calibration.observe(formation_at(190.0, 1, home));
  const double faded = calibration.adjusted(0, 0.33);
  EXPECT_LT(faded, fresh);
  EXPECT_LT(faded, 0.6);
  EXPECT_GT(faded, 0.33);
}

TEST(OnlineCalibration, AClockGoingBackStartsOver) {
  sf::OnlineCalibration calibration;
  play(calibration, 100.0, 20.0, 0.33, home);
  ASSERT_GT(calibration.adjusted(0, 0.33), 0.5);
  calibration.observe(formation_at(5.0, 1, home));
  EXPECT_EQ(calibration.checked(), 0u);
  EXPECT_EQ(calibration.pending(), 0u);
  EXPECT_EQ(calibration.adjusted(0, 0.33), 0.33);
}

TEST(OnlineCalibration, AFormationWhoseRobotsMoveTogetherIsStatedAsLikelyAsItTurnsOut) {
  // Four robots each stated at 0.5, and always all four in their cells or all four out (they
  // move together), half the time each way: every robot's 0.5 is right, but the formation's
  // product, 1/16, is far below the 0.5 it hits.
  sf::OnlineCalibration calibration(quick);
  const std::vector<Stated> robots{{1, home, 0.5}, {2, home, 0.5}, {3, home, 0.5}, {4, home, 0.5}};
  for (int i = 0; i < 8 * 120; ++i) {
    const double t = 0.125 * i;
    sf::Formation formation;
    formation.time_s = t;
    const bool in_cells = (i / 4) % 2 == 0;
    for (std::uint32_t id = 1; id <= 4; ++id) {
      sf::FormationRobot robot;
      robot.robot_id = id;
      robot.cell = in_cells ? home : elsewhere;
      formation.robots.push_back(robot);
    }
    calibration.observe(formation);
    calibration.remember(prediction_of({robots}), t, 0.5, sf::AttackDirection::positive_x);
  }
  EXPECT_GT(calibration.formations_checked(), 800u);
  sf::Prediction prediction = prediction_of({robots});
  calibration.adjust(prediction);
  for (const sf::RobotPrediction& robot : prediction.steps[0].robots) {
    EXPECT_NEAR(robot.probability, 0.5, 0.05);
  }
  EXPECT_NEAR(prediction.steps[0].formation_probability, 0.5, 0.06);
  EXPECT_NEAR(prediction.steps[0].confidence, prediction.steps[0].formation_probability, 1e-12);
}

TEST(OnlineCalibration, AFormationWithARobotUnseenWhenDueDecidesNothing) {
  sf::OnlineCalibration calibration(quick);
  const std::vector<Stated> robots{{1, home, 0.5}, {2, home, 0.5}};
  for (int i = 0; i < 8 * 30; ++i) {
    const double t = 0.125 * i;
    // Robot 2 is never seen: every robot 1 is checked, no formation is.
    calibration.observe(formation_at(t, 1, home));
    calibration.remember(prediction_of({robots}), t, 0.5, sf::AttackDirection::positive_x);
  }
  EXPECT_GT(calibration.checked(), 200u);
  EXPECT_EQ(calibration.formations_checked(), 0u);
  sf::Prediction prediction = prediction_of({robots});
  calibration.adjust(prediction);
  // No formation evidence: the product of the adjusted robots'.
  EXPECT_NEAR(prediction.steps[0].formation_probability,
              prediction.steps[0].robots[0].probability * prediction.steps[0].robots[1].probability,
              1e-12);
}

namespace {

// Robot 1 predicted at (0, 0) with radii 100 mm (50%) and 300 mm (90%) in `phase`, eight times a
// second for `seconds` from `from_s`, and found one step (0.5 s) later `off_mm` away along x
// (each instance's own distance from `offs`, in turn).
void play_radii(sf::OnlineCalibration& calibration, double from_s, double seconds,
                sf::GamePhase phase, const std::vector<double>& offs, bool preparing = false) {
  for (int i = 0; i < static_cast<int>(seconds * 8.0); ++i) {
    const double t = from_s + 0.125 * i;
    sf::Formation formation = formation_at(t, 1, home);
    // The robot found where the prediction made 0.5 s (4 frames) ago sent it, plus its offset.
    formation.robots[0].position = {offs[static_cast<std::size_t>(i) % offs.size()], 0.0};
    calibration.observe(formation);
    sf::Prediction prediction = prediction_of({{{1, home, 0.5}}});
    prediction.steps[0].robots[0].radius50_mm = 100.0;
    prediction.steps[0].robots[0].radius90_mm = 300.0;
    calibration.remember(prediction, t, 0.5, sf::AttackDirection::positive_x, phase, preparing);
  }
}

// 20 distances, `first_mm` then every `step_mm`: how far off a phase's robots land.
std::vector<double> evenly_spread(double first_mm, double step_mm) {
  std::vector<double> offs;
  for (int k = 0; k < 20; ++k) offs.push_back(first_mm + step_mm * k);
  return offs;
}

// The share of `offs` within `radius`.
double within(const std::vector<double>& offs, double radius) {
  double inside = 0.0;
  for (const double off : offs) inside += off <= radius ? 1.0 : 0.0;
  return inside / static_cast<double>(offs.size());
}

}  // namespace

TEST(OnlineCalibration, EachPhasesRadiiComeToHoldTheRobotHalfAndNineTenthsOfTheTime) {
  sf::OnlineCalibration calibration(quick);
  // At the opponent's kick-offs the robots land from 0 to 1 m away (the table's radii are far too
  // small); in HALT within 40 mm (far too large).
  const std::vector<double> kickoff = evenly_spread(25.0, 50.0), halt = evenly_spread(1.0, 2.0);
  // 12,000 checks of each: what a team of 11 remembered 10 times a second gives in two minutes.
  // The kick-offs' evidence is 25 minutes old when it is used: it fades with checks of its own
  // phase, not with time (kick-offs are minutes apart).
  play_radii(calibration, 100.0, 1500.0, sf::GamePhase::kickoff_opponent, kickoff);
  play_radii(calibration, 1600.0, 1500.0, sf::GamePhase::halt, halt);
  sf::Prediction prediction = prediction_of({{{1, home, 0.5}}});
  sf::RobotPrediction& robot = prediction.steps[0].robots[0];
  robot.radius50_mm = 100.0;
  robot.radius90_mm = 300.0;
  sf::Prediction at_kickoff = prediction;
  calibration.adjust(at_kickoff, sf::GamePhase::kickoff_opponent);
  EXPECT_NEAR(within(kickoff, at_kickoff.steps[0].robots[0].radius50_mm), 0.5, 0.1);
  EXPECT_NEAR(within(kickoff, at_kickoff.steps[0].robots[0].radius90_mm), 0.9, 0.1);
  sf::Prediction in_halt = prediction;
  calibration.adjust(in_halt, sf::GamePhase::halt);
  EXPECT_NEAR(within(halt, in_halt.steps[0].robots[0].radius50_mm), 0.5, 0.1);
  EXPECT_NEAR(within(halt, in_halt.steps[0].robots[0].radius90_mm), 0.9, 0.1);
  EXPECT_LT(in_halt.steps[0].robots[0].radius90_mm, 50.0);
  // A phase that saw nothing keeps the table's radii.
  sf::Prediction running = prediction;
  calibration.adjust(running, sf::GamePhase::running);
  EXPECT_DOUBLE_EQ(running.steps[0].robots[0].radius50_mm, 100.0);
  EXPECT_DOUBLE_EQ(running.steps[0].robots[0].radius90_mm, 300.0);
  // So does a step never checked.
  EXPECT_EQ(calibration.radius90_scale(3, sf::GamePhase::halt), 1.0);
}

TEST(OnlineCalibration, RobotsStandingWithinAMillimetreInALongHaltGetRadiiOfAMillimetre) {
  // The real logs' halts: every robot within a millimetre of where it was (docs/simulation.md),
  // where the table states radii of 100 and 300 mm. A running quantile that moved the radius a
  // small step per check was still far too wide at the end of such a halt.
  sf::OnlineCalibration calibration(quick);
  const std::vector<double> standing = evenly_spread(0.025, 0.05);      // 0.025 to 0.975 mm
  play_radii(calibration, 100.0, 25.0, sf::GamePhase::halt, standing);  // 200 checks
  sf::Prediction prediction = prediction_of({{{1, home, 0.5}}});
  sf::RobotPrediction& robot = prediction.steps[0].robots[0];
  robot.radius50_mm = 100.0;
  robot.radius90_mm = 300.0;
  calibration.adjust(prediction, sf::GamePhase::halt);
  // Held towards the stated radii by the prior weight (20 checks here) on a log scale: within
  // a few millimetres after 200 checks, not the 5 and 15 mm a clamp at 20 times would allow.
  EXPECT_LT(robot.radius50_mm, 3.0);
  EXPECT_LT(robot.radius90_mm, 5.0);
  EXPECT_GT(robot.radius90_mm, robot.radius50_mm);
  EXPECT_GE(within(standing, robot.radius90_mm), 0.85);
}

TEST(OnlineCalibration, TheOpponentsKickOffPreparationDoesNotNarrowTheRadiiAfterTheKick) {
  // Its robots walking to their places, remembered from earlier kick-offs, land within 20 mm;
  // after the kick they run the routine and land up to 1 m away.
  sf::OnlineCalibration calibration(quick);
  const std::vector<double> walking = evenly_spread(0.5, 1.0), running = evenly_spread(25.0, 50.0);
  play_radii(calibration, 100.0, 60.0, sf::GamePhase::kickoff_opponent, running);
  play_radii(calibration, 200.0, 60.0, sf::GamePhase::kickoff_opponent, walking, true);
  sf::Prediction prediction = prediction_of({{{1, home, 0.5}}});
  prediction.steps[0].robots[0].radius50_mm = 100.0;
  prediction.steps[0].robots[0].radius90_mm = 300.0;
  sf::Prediction taken = prediction, prepared = prediction;
  calibration.adjust(taken, sf::GamePhase::kickoff_opponent);
  calibration.adjust(prepared, sf::GamePhase::kickoff_opponent, true);
  EXPECT_NEAR(within(running, taken.steps[0].robots[0].radius90_mm), 0.9, 0.1);
  EXPECT_NEAR(within(walking, prepared.steps[0].robots[0].radius90_mm), 0.9, 0.1);
  EXPECT_LT(prepared.steps[0].robots[0].radius90_mm, 40.0);
  // Our own kick-off's preparation is one with the rest of our kick-off.
  EXPECT_EQ(calibration.radius90_scale(0, sf::GamePhase::kickoff_us, true),
            calibration.radius90_scale(0, sf::GamePhase::kickoff_us));
}
