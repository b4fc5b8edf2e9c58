#include "ssl_formation/paper_model/predictor.hpp"

#include <gtest/gtest.h>

#include "ssl_formation/paper_model/measures.hpp"

namespace ssl_formation {
namespace {

// 3x2 grid, cells numbered x*2 + y: (0,0)=0 (0,1)=1 (1,0)=2 (1,1)=3 (2,0)=4 (2,1)=5.
class PredictorTest : public ::testing::Test {
 protected:
  TransitionTable table{Grid(3, 2)};
  const StateCodec& codec = table.codec();
  StateIndex state(int t, int p, int v) const {
    return codec.compose(static_cast<StateIndex>(t), static_cast<StateIndex>(p),
                         static_cast<StateIndex>(v));
  }
};

TEST_F(PredictorTest, HandBuiltTableGivesTheKnownAnswer) {
  // Two robots, centroid cell 3. Robot A at cell 2, robot B at cell 5.
  const StateIndex a = state(3, 2, 2);
  const StateIndex b = state(3, 5, 4);
  // Centroid 3 -> 5 is counted 6 times, 3 -> 1 four times: c* = 5 with P = 6/10.
  table.add(a, state(5, 4, 2), 3);  // velocity-consistent candidate for A in block 5
  table.add(a, state(5, 3, 2), 1);  // another candidate for A: P(A) = 3/4
  table.add(b, state(5, 5, 5), 2);  // B's only candidate in block 5: P(B) = 2/2
  table.add(b, state(1, 0, 5), 4);  // into block 1: feeds the centroid choice only
  // A count that is not velocity-consistent (previous != A's cell) must be ignored.
  table.add(a, state(5, 0, 0), 0);

  const std::vector<RobotStateById> robots{{7, a}, {9, b}};
  Prediction prediction;
  predict(table, robots, 1, prediction);
  ASSERT_EQ(prediction.steps.size(), 1u);
  const PredictedStep& step = prediction.steps[0];
  EXPECT_EQ(step.centroid, (Cell{2, 1}));
  EXPECT_NEAR(step.centroid_probability, 6.0 / 10.0, 1e-12);
  EXPECT_FALSE(step.centroid_unseen);
  ASSERT_EQ(step.robots.size(), 2u);
  EXPECT_EQ(step.robots[0].robot_id, 7u);
  EXPECT_EQ(step.robots[0].state, state(5, 4, 2));
  EXPECT_EQ(step.robots[0].position, (Cell{2, 0}));
  EXPECT_EQ(step.robots[0].previous, (Cell{1, 0}));
  EXPECT_NEAR(step.robots[0].probability, 3.0 / 4.0, 1e-12);
  EXPECT_EQ(step.robots[1].state, state(5, 5, 5));
  EXPECT_NEAR(step.robots[1].probability, 1.0, 1e-12);
  EXPECT_NEAR(step.formation_probability, 0.6 * 0.75 * 1.0, 1e-12);
  EXPECT_NEAR(step.confidence, 0.45, 1e-12);
}

TEST_F(PredictorTest, VelocityInconsistentCountsAreNotCandidates) {
  const StateIndex a = state(3, 2, 2);
  table.add(a, state(3, 4, 0), 50);  // previous cell 0 != A's cell 2: cannot happen for A
  table.add(a, state(3, 1, 2), 1);
  const auto prediction = predict(table, Formation{}, 1);
  EXPECT_TRUE(prediction.steps.empty());  // nothing to predict from an empty formation
  Prediction out;
  predict(table, {{1, a}}, 1, out);
  EXPECT_EQ(out.steps[0].robots[0].state, state(3, 1, 2));
  EXPECT_NEAR(out.steps[0].robots[0].probability, 1.0, 1e-12);
  EXPECT_NEAR(out.steps[0].centroid_probability, 1.0, 1e-12);
}

TEST_F(PredictorTest, UnseenRowsHoldWithUniformProbability) {
  Prediction out;
  const StateIndex a = state(3, 2, 0);
  predict(table, {{1, a}}, 1, out);
  const PredictedStep& step = out.steps[0];
  EXPECT_TRUE(step.centroid_unseen);
  EXPECT_EQ(step.centroid, (Cell{1, 1}));  // the centroid stays
  EXPECT_NEAR(step.centroid_probability, 1.0 / 6.0, 1e-12);
  EXPECT_TRUE(step.robots[0].unseen);
  EXPECT_EQ(step.robots[0].state, state(3, 2, 2));  // holds its cell, velocity 0
  EXPECT_NEAR(step.robots[0].probability, 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(step.confidence, 1.0 / 36.0, 1e-12);
}

TEST_F(PredictorTest, UnseenRobotInASeenCentroidBlock) {
  const StateIndex a = state(3, 2, 2);
  const StateIndex stranger = state(3, 0, 1);
  table.add(a, state(4, 4, 2), 2);
  Prediction out;
  predict(table, {{1, a}, {2, stranger}}, 1, out);
  const PredictedStep& step = out.steps[0];
  EXPECT_FALSE(step.centroid_unseen);
  EXPECT_EQ(step.centroid, (Cell{2, 0}));
  EXPECT_FALSE(step.robots[0].unseen);
  EXPECT_TRUE(step.robots[1].unseen);
  EXPECT_EQ(step.robots[1].state, state(4, 0, 0));
  EXPECT_NEAR(step.formation_probability, 1.0 * 1.0 * (1.0 / 6.0), 1e-12);
}

TEST_F(PredictorTest, TiesBreakTowardsTheLowestIndex) {
  const StateIndex a = state(0, 3, 3);
  table.add(a, state(2, 5, 3), 4);
  table.add(a, state(1, 4, 3), 4);  // centroid tie 1 vs 2: 1 wins
  table.add(a, state(1, 2, 3), 4);  // robot tie in block 1: position 2 < 4 wins
  Prediction out;
  predict(table, {{1, a}}, 1, out);
  EXPECT_EQ(out.steps[0].centroid, (Cell{0, 1}));
  EXPECT_NEAR(out.steps[0].centroid_probability, 8.0 / 12.0, 1e-12);
  EXPECT_EQ(out.steps[0].robots[0].state, state(1, 2, 3));
  EXPECT_NEAR(out.steps[0].robots[0].probability, 0.5, 1e-12);
}

TEST_F(PredictorTest, HorizonTwoChainsFromThePredictedFormation) {
  const StateIndex a0 = state(0, 0, 0);
  const StateIndex a1 = state(2, 2, 0);
  const StateIndex a2 = state(4, 4, 2);
  table.add(a0, a1, 3);
  table.add(a0, state(2, 3, 0), 1);  // P(step 1) = 3/4
  table.add(a1, a2, 1);
  table.add(a1, state(5, 5, 2), 1);  // centroid tie 4 vs 5 -> 4; P(centroid) = 1/2, P(robot) = 1
  Prediction out;
  predict(table, {{3, a0}}, 2, out);
  ASSERT_EQ(out.steps.size(), 2u);
  EXPECT_EQ(out.steps[0].robots[0].state, a1);
  EXPECT_NEAR(out.steps[0].confidence, 0.75, 1e-12);
  EXPECT_EQ(out.steps[1].robots[0].state, a2);
  EXPECT_NEAR(out.steps[1].formation_probability, 0.5, 1e-12);
  EXPECT_NEAR(out.steps[1].confidence, 0.75 * 0.5, 1e-12);
  EXPECT_EQ(out.steps[1].robots[0].previous, (Cell{1, 0}));
}

TEST_F(PredictorTest, CountAndDistanceMeasures) {
  const std::vector<RobotStateById> reference{
      {1, state(3, 2, 2)}, {2, state(3, 5, 4)}, {3, state(3, 0, 0)}};
  std::vector<RobotStateById> predicted{
      {1, state(3, 2, 2)}, {2, state(3, 0, 4)}, {3, state(3, 0, 1)}};
  EXPECT_EQ(count_measure(predicted, reference), 2);  // robot 2 moved, robot 3 other velocity
  // Robot 2: cell (0,0) vs (2,1) -> 3; robot 3 same cell -> 0.
  EXPECT_EQ(distance_measure(codec, predicted, reference), 3);
  predicted.pop_back();
  EXPECT_EQ(count_measure(predicted, reference), 2);  // missing robot 3 still counts as wrong
  EXPECT_EQ(distance_measure(codec, predicted, reference), 3);
  EXPECT_EQ(count_measure(reference, reference), 0);
}

}  // namespace
}  // namespace ssl_formation
