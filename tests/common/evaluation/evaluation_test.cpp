#include "ssl_formation/evaluation/evaluation.hpp"

#include <gtest/gtest.h>

#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation::evaluation {
namespace {

const FieldSize field{9000, 6000};

// 3x2 cells are 3000 x 3000 mm; centres at x = -3000, 0, 3000 and y = -1500, 1500.
Formation formation_at(const StateCodec& codec, const std::vector<Point>& positions,
                       const Formation* previous = nullptr) {
  return FormationSampler::formation_at(codec, field, positions, previous);
}

TEST(Accuracy, ScoresStatesCellsAndDistances) {
  const StateCodec codec(Grid(3, 2));
  Accuracy accuracy;
  const std::vector<RobotStateById> actual{{1, codec.encode({{1, 1}, {2, 1}, {1, 1}})},
                                           {2, codec.encode({{1, 1}, {0, 0}, {0, 0}})},
                                           {3, codec.encode({{1, 1}, {1, 0}, {1, 0}})}};
  const std::vector<RobotStateById> predicted{
      {1, codec.encode({{1, 1}, {2, 1}, {1, 1}})},   // exact
      {2, codec.encode({{1, 0}, {0, 0}, {0, 0}})}};  // cell only
  score(accuracy, codec, predicted, actual);         // robot 3 was not predicted: wrong
  EXPECT_EQ(accuracy.robots, 3u);
  EXPECT_EQ(accuracy.exact_states, 1u);
  EXPECT_EQ(accuracy.exact_cells, 2u);
  EXPECT_EQ(accuracy.cell_distance, 0u);
  EXPECT_NEAR(accuracy.state_accuracy(), 1.0 / 3.0, 1e-12);
}

TEST(Calibration, BrierScoreAndReliabilityBinsOfAWorkedExample) {
  Calibration c;
  c.add(0.05, false);
  c.add(0.15, true);
  c.add(0.95, true);
  c.add(0.95, false);
  c.add(1.0, true);
  // (0.05^2 + 0.85^2 + 0.05^2 + 0.95^2 + 0^2) / 5 = (0.0025 + 0.7225 + 0.0025 + 0.9025) / 5
  EXPECT_NEAR(c.brier(), 1.63 / 5.0, 1e-12);
  EXPECT_EQ(c.bin_count[0], 1u);
  EXPECT_EQ(c.bin_hits[0], 0u);
  EXPECT_EQ(c.bin_count[1], 1u);
  EXPECT_EQ(c.bin_hits[1], 1u);
  EXPECT_EQ(c.bin_count[9], 3u);  // 0.95, 0.95 and 1.0 share the last bin
  EXPECT_EQ(c.bin_hits[9], 2u);
  EXPECT_NEAR(c.bin_confidence[9] / 3.0, (0.95 + 0.95 + 1.0) / 3.0, 1e-12);
  EXPECT_EQ(Calibration::bin_of(0.1), 1);
  EXPECT_EQ(Calibration::bin_of(0.0999), 0);
}

TEST(PaperProtocol, PicksTheClosestPlayPerMeasureAndScoresThreeFormations) {
  const Grid grid(3, 2);
  TransitionTable table(grid);
  const StateCodec& codec = table.codec();
  // Two one-robot plays: A walks along row 0, B stays in cell (2,1).
  const auto play_a = play_states(codec, field, {{{-3000, -1500}}, {{0, -1500}}, {{3000, -1500}}});
  const auto play_b = play_states(codec, field, {{{3000, 1500}}, {{3000, 1500}}, {{3000, 1500}}});
  // Teach the table play A's moves.
  table.add(play_a[0][0].state, play_a[1][0].state, 5);
  table.add(play_a[1][0].state, play_a[2][0].state, 5);
  // A test formation equal to A's first formation: A is closest under both measures and the
  // prediction follows it exactly.
  const PaperTest exact = run_paper_test(table, play_a[0], {play_a, play_b});
  EXPECT_EQ(exact.count_play, 0);
  EXPECT_EQ(exact.distance_play, 0);
  EXPECT_EQ(exact.count, (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(exact.distance, (std::array<int, 3>{0, 0, 0}));
  EXPECT_NEAR(exact.confidence[0], 1.0, 1e-12);
  EXPECT_NEAR(exact.confidence[1], 1.0, 1e-12);

  // A formation in cell (1,1): count is 1 against both plays' first formations (tie: play A);
  // distance is |1-0|+|1-0| = 2 to A's (0,0) and |1-2|+|1-1| = 1 to B's (2,1): B wins.
  const Formation odd = formation_at(codec, {{0, 1500}});
  const PaperTest test = run_paper_test(table, robot_states(odd), {play_a, play_b});
  EXPECT_EQ(test.count_play, 0);
  EXPECT_EQ(test.distance_play, 1);
  EXPECT_EQ(test.count, (std::array<int, 3>{1, 1, 1}));  // unseen: it holds (1,1)
  EXPECT_EQ(test.distance, (std::array<int, 3>{1, 1, 1}));

  PaperSummary summary;
  accumulate(summary, exact);
  accumulate(summary, test);
  EXPECT_EQ(summary.tests, 2);
  EXPECT_NEAR(summary.count_per_play, 1.5, 1e-12);
  EXPECT_NEAR(summary.distance_per_formation, 0.5, 1e-12);
}

}  // namespace
}  // namespace ssl_formation::evaluation
