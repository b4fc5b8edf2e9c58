#include "ssl_formation/pipeline/live_score.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace ssl_formation {
namespace {

// Robot 0 drives along x at `speed` mm/s; robot 1 stands at (0, 1000).
Formation formation_at(double t, double speed) {
  Formation f;
  f.time_s = t;
  FormationRobot moving;
  moving.robot_id = 0;
  moving.feed_position = Point{speed * t, 0.0};
  FormationRobot standing;
  standing.robot_id = 1;
  standing.feed_position = Point{0.0, 1000.0};
  f.robots = {moving, standing};
  return f;
}

// A prediction of two steps of `step_s` from `now`: robot 0 at `guess(k)` for step k, robot 1
// where it stands.
template <class Guess>
Prediction predicted(const Formation& now, double step_s, Guess guess) {
  Prediction p;
  for (int k = 1; k <= 2; ++k) {
    PredictedStep step;
    RobotPrediction moving;
    moving.robot_id = 0;
    moving.feed_position = guess(now.time_s + k * step_s);
    RobotPrediction standing;
    standing.robot_id = 1;
    standing.feed_position = Point{0.0, 1000.0};
    step.robots = {moving, standing};
    p.steps.push_back(step);
  }
  return p;
}

TEST(LiveScore, ARightPredictionScoresNothingAndEveryoneStaysScoresTheDistanceTravelled) {
  LiveScore score;
  const double speed = 1200.0;
  const double step_s = 0.5;
  for (int frame = 0; frame <= 60 * 20; ++frame) {
    const Formation f = formation_at(frame / 60.0, speed);
    score.observe(f);
    score.remember(predicted(f, step_s,
                             [&](double t) {
                               return Point{speed * t, 0.0};
                             }),
                   f, step_s);
  }
  ASSERT_EQ(score.horizons().size(), 2u);
  for (const LiveScore::Horizon& h : score.horizons()) {
    EXPECT_NEAR(h.model_mm, 0.0, 1e-6);
    // Half the robots moved speed x horizon, half stood.
    EXPECT_NEAR(h.persistence_mm, speed * h.horizon_s / 2.0, 1e-6) << h.horizon_s;
    EXPECT_GT(h.robots, 30.0);
  }
  EXPECT_EQ(score.nearest(1.0)->horizon_s, 1.0);
  EXPECT_EQ(describe_for_status(score), "0mm at 1.0s (stays 600mm)");
  // Four predictions a second (the remember interval), each robot and step scored once.
  EXPECT_NEAR(static_cast<double>(score.scored()), 4 * 20 * 2 * 2, 8);
}

TEST(LiveScore, OldEvidenceFadesAndMissingRobotsAreNotScored) {
  LiveScore score(LiveScoreSettings{10.0, 0.25, 0.05});
  const double speed = 1000.0;
  const double step_s = 1.0;
  // 60 s of a model that says "it stays", then 60 s of one that is right.
  for (int frame = 0; frame <= 60 * 120; ++frame) {
    const double t = frame / 60.0;
    Formation f = formation_at(t, speed);
    if (frame % 120 == 0) f.robots.pop_back();  // robot 1 missed now and then
    score.observe(f);
    const bool right = t >= 60.0;
    score.remember(predicted(f, step_s,
                             [&](double at) {
                               return right ? Point{speed * at, 0.0} : Point{speed * t, 0.0};
                             }),
                   f, step_s);
  }
  const LiveScore::Horizon* one = score.nearest(1.0);
  ASSERT_NE(one, nullptr);
  // Six half-lives after the change, the old errors weigh 1/64.
  EXPECT_LT(one->model_mm, 0.02 * one->persistence_mm);
  // Robot 0 went 1000 mm a second and robot 1 none; robot 1, missing now and then, counts a
  // little less.
  EXPECT_GT(one->persistence_mm, 500.0);
  EXPECT_LT(one->persistence_mm, 600.0);
  // A clock going back starts over.
  score.observe(formation_at(1.0, speed));
  EXPECT_TRUE(score.horizons().empty());
  EXPECT_EQ(describe_for_status(score), "");
}

}  // namespace
}  // namespace ssl_formation

namespace ssl_formation {
namespace {

TEST(LiveScore, KeepsThePredictionsOfEachPhaseApart) {
  LiveScore score;
  const double speed = 1200.0;
  const double step_s = 0.5;
  // 20 s: the first 10 predicted in STOP by a model that says "it stays", the next 10 in running
  // play by one that is right.
  for (int frame = 0; frame <= 60 * 20; ++frame) {
    const double t = frame / 60.0;
    const Formation f = formation_at(t, speed);
    score.observe(f);
    const bool running = t >= 10.0;
    score.remember(predicted(f, step_s,
                             [&](double at) {
                               return running ? Point{speed * at, 0.0} : Point{speed * t, 0.0};
                             }),
                   f, step_s, running ? GamePhase::running : GamePhase::stop);
  }
  const auto& stop = score.horizons(GamePhase::stop);
  const auto& running = score.horizons(GamePhase::running);
  ASSERT_EQ(stop.size(), 2U);
  ASSERT_EQ(running.size(), 2U);
  EXPECT_TRUE(score.horizons(GamePhase::halt).empty());
  for (std::size_t step = 0; step < 2; ++step) {
    // In STOP the model was as far off as everyone staying; in running play not at all.
    EXPECT_NEAR(stop[step].model_mm, stop[step].persistence_mm, 1e-6);
    EXPECT_GT(stop[step].model_mm, 100.0);
    EXPECT_NEAR(running[step].model_mm, 0.0, 1e-6);
    EXPECT_EQ(running[step].horizon_s, stop[step].horizon_s);
    // All together: between the two, weighted by their robots.
    const LiveScore::Horizon& all = score.horizons()[step];
    EXPECT_NEAR(all.robots, stop[step].robots + running[step].robots, 1e-9);
    EXPECT_NEAR(
        all.model_mm * all.robots,
        stop[step].model_mm * stop[step].robots + running[step].model_mm * running[step].robots,
        1e-6);
  }
  score.clear();
  EXPECT_TRUE(score.horizons(GamePhase::stop).empty());
}

}  // namespace
}  // namespace ssl_formation
