// The block bootstrap behind every interval of ssl-evaluate: blocks of data time, intervals of
// known width, ratios that keep the pairing of methods scored on the same robots, a fixed seed,
// and no interval where too few blocks leave nothing to resample. The intervals of a whole
// evaluation are checked against its means in position_evaluation_test.cpp.

#include "ssl_formation/evaluation/block_bootstrap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace ssl_formation::evaluation {
namespace {

// One robot per block, block i with these errors for the model and one baseline.
BlockedErrors blocks_of(int count, double (*model)(int), double (*baseline)(int)) {
  BlockedErrors blocks;
  for (int i = 0; i < count; ++i) {
    add_to_block(blocks, DataBlock{0, i}, {model(i), baseline(i)});
  }
  return blocks;
}

std::vector<DataBlock> keys(const BlockedErrors& blocks) {
  std::vector<DataBlock> out;
  for (const auto& [block, sums] : blocks) out.push_back(block);
  return out;
}

TEST(BlockBootstrap, BlocksCutEachStreamsClockIntoEqualSpans) {
  EXPECT_EQ(data_block(0, 0.0, 10.0), (DataBlock{0, 0}));
  EXPECT_EQ(data_block(0, 9.999, 10.0), (DataBlock{0, 0}));
  EXPECT_EQ(data_block(0, 10.0, 10.0), (DataBlock{0, 1}));
  EXPECT_EQ(data_block(0, -0.5, 10.0), (DataBlock{0, -1}));
  EXPECT_EQ(data_block(3, 25.0, 5.0), (DataBlock{3, 5}));
  EXPECT_NE(data_block(0, 1.0, 10.0), data_block(1, 1.0, 10.0));  // each stream its own clock
}

TEST(BlockBootstrap, ABlocksSumsCountEveryRobotAddedToIt) {
  BlockedErrors blocks;
  add_to_block(blocks, {0, 2}, {1.0, 4.0});
  add_to_block(blocks, {0, 2}, {2.0, 5.0});
  add_to_block(blocks, {1, 2}, {7.0, 7.0});
  ASSERT_EQ(blocks.size(), 2u);
  const BlockSums& first = blocks.at({0, 2});
  EXPECT_EQ(first.robots, 2u);
  EXPECT_DOUBLE_EQ(first.error_sums[0], 3.0);
  EXPECT_DOUBLE_EQ(first.error_sums[1], 9.0);
  EXPECT_THROW(add_to_block(blocks, {0, 2}, {1.0}), std::invalid_argument);
}

TEST(BlockBootstrap, EqualBlocksGiveAnIntervalOfTheMeanAlone) {
  const BlockedErrors blocks = blocks_of(
      20, [](int) { return 30.0; }, [](int) { return 40.0; });
  const BlockResamples draws(keys(blocks), BootstrapConfig{});
  const RowIntervals row = bootstrap_row(blocks, draws, 1);
  ASSERT_EQ(row.mean.size(), 2u);
  EXPECT_DOUBLE_EQ(row.mean[0].low, 30.0);
  EXPECT_DOUBLE_EQ(row.mean[0].high, 30.0);
  EXPECT_DOUBLE_EQ(row.mean[1].low, 40.0);
  ASSERT_EQ(row.ratio.size(), 2u);
  EXPECT_DOUBLE_EQ(row.ratio[0].low, 0.75);
  EXPECT_DOUBLE_EQ(row.ratio[0].high, 0.75);
  EXPECT_DOUBLE_EQ(row.ratio[1].low, 1.0);  // the best baseline against itself
  EXPECT_EQ(row.blocks, 20u);
}

TEST(BlockBootstrap, TheMeansIntervalIsAsWideAsTheBlocksSpreadSays) {
  // Blocks with errors 0..19: mean 9.5, standard deviation of the mean of 20 draws
  // sqrt(33.25 / 20) = 1.289, so a 95% interval of about 9.5 -+ 2.53.
  const BlockedErrors blocks = blocks_of(
      20, [](int i) { return double(i); }, [](int i) { return 2.0 * i; });
  const BlockResamples draws(keys(blocks), BootstrapConfig{});
  const RowIntervals row = bootstrap_row(blocks, draws, 1);
  ASSERT_EQ(row.mean.size(), 2u);
  EXPECT_NEAR(row.mean[0].low, 9.5 - 2.53, 0.4);
  EXPECT_NEAR(row.mean[0].high, 9.5 + 2.53, 0.4);
  EXPECT_LT(row.mean[0].low, 9.5);
  EXPECT_GT(row.mean[0].high, 9.5);
  // The baseline is twice the model in every block: resampled together, the ratio never moves,
  // though each mean does.
  EXPECT_NEAR(row.ratio[0].low, 0.5, 1e-12);
  EXPECT_NEAR(row.ratio[0].high, 0.5, 1e-12);
}

TEST(BlockBootstrap, ARatioKeepsThePairingOfMethodsScoredOnTheSameRobots) {
  // Both methods share each block's difficulty (a busy or a quiet stretch of play); the model is
  // 10 mm better throughout. Drawn apart the two means' intervals would overlap; drawn together
  // the ratio stays clear of 1.
  const BlockedErrors blocks = blocks_of(
      30, [](int i) { return 100.0 + 50.0 * (i % 5); },
      [](int i) { return 110.0 + 50.0 * (i % 5); });
  const BlockResamples draws(keys(blocks), BootstrapConfig{});
  const RowIntervals row = bootstrap_row(blocks, draws, 1);
  ASSERT_EQ(row.mean.size(), 2u);
  EXPECT_GT(row.mean[0].high, row.mean[1].low);  // the means' intervals overlap
  EXPECT_LT(row.ratio[0].high, 1.0);             // the ratio's does not reach 1
  EXPECT_GT(row.ratio[0].low, 200.0 / 220.0 - 0.05);
}

TEST(BlockBootstrap, TheSameSeedDrawsTheSameIntervalsAndAnotherSeedOthers) {
  const BlockedErrors blocks = blocks_of(
      25, [](int i) { return double(i * i % 17); }, [](int i) { return 10.0 + i; });
  BootstrapConfig config;
  const RowIntervals a = bootstrap_row(blocks, BlockResamples(keys(blocks), config), 1);
  const RowIntervals b = bootstrap_row(blocks, BlockResamples(keys(blocks), config), 1);
  EXPECT_EQ(a.mean[0].low, b.mean[0].low);
  EXPECT_EQ(a.mean[0].high, b.mean[0].high);
  EXPECT_EQ(a.ratio[0].low, b.ratio[0].low);
  config.seed += 1;
  const RowIntervals c = bootstrap_row(blocks, BlockResamples(keys(blocks), config), 1);
  EXPECT_TRUE(a.mean[0].low != c.mean[0].low || a.mean[0].high != c.mean[0].high);
}

TEST(BlockBootstrap, ARowOverFewBlocksHasNoIntervalButSaysHowManyItHad) {
  const BlockedErrors blocks = blocks_of(
      4, [](int i) { return double(i); }, [](int i) { return 1.0 + i; });
  const BlockResamples draws(keys(blocks), BootstrapConfig{});  // at least 5 blocks
  const RowIntervals row = bootstrap_row(blocks, draws, 1);
  EXPECT_TRUE(row.mean.empty());
  EXPECT_TRUE(row.ratio.empty());
  EXPECT_EQ(row.blocks, 4u);
  EXPECT_TRUE(bootstrap_row(BlockedErrors{}, draws, 1).mean.empty());
}

TEST(BlockBootstrap, ARowsResamplesLeaveOutDrawsWithoutItsBlocks) {
  // A state played in 6 of 60 blocks: its resamples draw 6 blocks on average and some none. The
  // interval still holds its mean and stays within its blocks' extremes.
  BlockedErrors all;
  BlockedErrors rare;
  for (int i = 0; i < 60; ++i) {
    add_to_block(all, {0, i}, {1.0, 2.0});
    if (i % 10 == 0) add_to_block(rare, {0, i}, {10.0 + i, 20.0 + i});
  }
  const BlockResamples draws(keys(all), BootstrapConfig{});
  const RowIntervals row = bootstrap_row(rare, draws, 1);
  ASSERT_EQ(row.mean.size(), 2u);
  EXPECT_GE(row.mean[0].low, 10.0);
  EXPECT_LE(row.mean[0].high, 60.0);
  EXPECT_LT(row.mean[0].low, 35.0);  // the row's mean
  EXPECT_GT(row.mean[0].high, 35.0);
  // A row whose blocks the draws never saw is a caller's mistake.
  BlockedErrors stray;
  for (int i = 0; i < 5; ++i) add_to_block(stray, {7, i}, {1.0, 1.0});
  EXPECT_THROW(bootstrap_row(stray, draws, 1), std::invalid_argument);
}

TEST(BlockBootstrap, RefusesBlocksOfNoTimeAndLevelsOutsideZeroToOne) {
  BootstrapConfig config;
  config.block_s = 0.0;
  EXPECT_THROW(BlockResamples({}, config), std::invalid_argument);
  config = BootstrapConfig{};
  config.level = 1.0;
  EXPECT_THROW(BlockResamples({}, config), std::invalid_argument);
  config = BootstrapConfig{};
  config.resamples = -1;
  EXPECT_THROW(BlockResamples({}, config), std::invalid_argument);
}

}  // namespace
}  // namespace ssl_formation::evaluation
