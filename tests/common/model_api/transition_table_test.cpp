#include "ssl_formation/model_api/transition_table.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>

#include "ssl_formation/paper_model/predictor.hpp"

namespace ssl_formation {
namespace {

// Brute-force view of a table: the sums a prediction relies on, recomputed from the counts.
void expect_totals_match_brute_force(
    const TransitionTable& table,
    const std::map<std::pair<StateIndex, StateIndex>, std::uint64_t>& truth) {
  const StateCodec& codec = table.codec();
  const StateIndex cells = codec.cell_count();
  std::map<StateIndex, std::uint64_t> rows;
  std::vector<std::uint64_t> centroid(static_cast<std::size_t>(cells) * cells, 0);
  std::uint64_t all = 0;
  for (const auto& [key, count] : truth) {
    ASSERT_EQ(table.count(key.first, key.second), count);
    rows[key.first] += count;
    centroid[codec.centroid_id(key.first) * cells + codec.centroid_id(key.second)] += count;
    all += count;
  }
  for (const auto& [from, total] : rows) ASSERT_EQ(table.row_total(from), total);
  for (StateIndex t = 0; t < cells; ++t) {
    std::uint64_t row_sum = 0;
    for (StateIndex c = 0; c < cells; ++c) {
      ASSERT_EQ(table.centroid_count(t, c), centroid[t * cells + c]) << t << "->" << c;
      row_sum += centroid[t * cells + c];
    }
    ASSERT_EQ(table.centroid_total(t), row_sum);
  }
  EXPECT_EQ(table.transitions(), all);
  EXPECT_EQ(table.nonzero_entries(), truth.size());
}

class TransitionTableProperty : public ::testing::TestWithParam<std::pair<Grid, TableStorage>> {};

TEST_P(TransitionTableProperty, TotalsAndCentroidMatrixEqualABruteForceResum) {
  const auto [grid, storage] = GetParam();
  TransitionTable table(grid, storage);
  const StateCodec& codec = table.codec();
  std::mt19937 random(12345);
  std::uniform_int_distribution<StateIndex> any_state(0, codec.state_count() - 1);
  std::uniform_int_distribution<int> amount(1, 5);
  std::map<std::pair<StateIndex, StateIndex>, std::uint64_t> truth;
  // A few hot rows and many scattered ones, so sparse rows get both long and short.
  std::vector<StateIndex> hot{any_state(random), any_state(random), any_state(random)};
  for (int i = 0; i < 5000; ++i) {
    const StateIndex from = i % 3 == 0 ? hot[i % hot.size()] : any_state(random);
    const StateIndex to = any_state(random);
    const auto n = static_cast<TransitionTable::Count>(amount(random));
    table.add(from, to, n);
    truth[{from, to}] += n;
  }
  expect_totals_match_brute_force(table, truth);
}

INSTANTIATE_TEST_SUITE_P(Layouts, TransitionTableProperty,
                         ::testing::Values(std::pair{Grid(3, 2), TableStorage::dense},
                                           std::pair{Grid(3, 2), TableStorage::sparse},
                                           std::pair{Grid(12, 9), TableStorage::automatic}));

TEST(TransitionTable, ChoosesDenseForSmallAndSparseForLargeGrids) {
  EXPECT_TRUE(TransitionTable(Grid(3, 2)).is_dense());
  const TransitionTable large(Grid(12, 9));
  EXPECT_FALSE(large.is_dense());
  // A 12x9 table costs memory in proportion to what it holds, not S^2 (1.6e12 entries).
  EXPECT_LT(large.memory_bytes(), 1u << 20);
}

TEST(TransitionTable, ADenseRequestForAHugeGridGetsSparseStorage) {
  const TransitionTable huge(Grid(16, 16), TableStorage::dense);  // S^2 = 2.8e14 entries
  EXPECT_FALSE(huge.is_dense());
  EXPECT_TRUE(TransitionTable(Grid(4, 3), TableStorage::dense).is_dense());
}

TEST(TransitionTable, SparseMemoryGrowsWithTransitionsSeen) {
  TransitionTable table(Grid(12, 9));
  const std::size_t empty = table.memory_bytes();
  for (StateIndex i = 0; i < 10000; ++i) table.add(i * 97, i * 89 + 1);
  const std::size_t full = table.memory_bytes();
  EXPECT_GT(full, empty);
  EXPECT_LT(full - empty, 10000u * 200u);  // a few hundred bytes per transition at most
}

TEST(TransitionTable, CountsSaturateInsteadOfWrapping) {
  for (const TableStorage storage : {TableStorage::dense, TableStorage::sparse}) {
    TransitionTable table(Grid(3, 2), storage);
    EXPECT_EQ(table.add(5, 7, TransitionTable::max_count - 1), TransitionTable::max_count - 1);
    EXPECT_EQ(table.add(5, 7, 10), 1u);  // only one more fits
    EXPECT_EQ(table.add(5, 7), 0u);
    EXPECT_EQ(table.count(5, 7), TransitionTable::max_count);
    EXPECT_EQ(table.row_total(5), TransitionTable::max_count);
    EXPECT_EQ(table.transitions(), TransitionTable::max_count);
    EXPECT_EQ(table.centroid_total(table.codec().centroid_id(5)), TransitionTable::max_count);
  }
}

TEST(TransitionTable, RejectsIndicesOutsideTheGrid) {
  TransitionTable table(Grid(3, 2));
  EXPECT_THROW(table.add(216, 0), std::out_of_range);
  EXPECT_THROW(table.add(0, 216), std::out_of_range);
  EXPECT_EQ(table.transitions(), 0u);
}

TEST(TransitionTable, MergeEqualsCountingBothStreams) {
  std::mt19937 random(7);
  std::uniform_int_distribution<StateIndex> any_state(0, 215);
  TransitionTable a(Grid(3, 2));
  TransitionTable b(Grid(3, 2), TableStorage::sparse);
  TransitionTable both(Grid(3, 2));
  for (int i = 0; i < 3000; ++i) {
    const StateIndex from = any_state(random);
    const StateIndex to = any_state(random);
    (i % 2 ? a : b).add(from, to);
    both.add(from, to);
  }
  a.merge(b);
  for (StateIndex from = 0; from < 216; ++from) {
    ASSERT_EQ(a.row_total(from), both.row_total(from));
    for (StateIndex to = 0; to < 216; ++to) ASSERT_EQ(a.count(from, to), both.count(from, to));
  }
  EXPECT_EQ(a.transitions(), both.transitions());
  EXPECT_THROW(a.merge(TransitionTable(Grid(6, 4))), std::invalid_argument);
}

// The dense layout keeps counts in (from centroid, to centroid) blocks, not row-major: every
// query must still answer as if it scanned the plain S x S matrix.
TEST(TransitionTable, DenseLayoutAnswersLikeAScanOfThePlainMatrix) {
  for (const Grid grid : {Grid(3, 2), Grid(4, 3)}) {
    TransitionTable table(grid, TableStorage::dense);
    ASSERT_TRUE(table.is_dense());
    const StateCodec& codec = table.codec();
    const StateIndex cells = codec.cell_count();
    std::mt19937 random(7);
    std::uniform_int_distribution<StateIndex> any_state(0, codec.state_count() - 1);
    std::map<std::pair<StateIndex, StateIndex>, std::uint64_t> truth;
    std::vector<StateIndex> rows;
    for (int i = 0; i < 4000; ++i) {
      const StateIndex from =
          i % 2 == 0 && !rows.empty() ? rows[i % rows.size()] : any_state(random);
      const StateIndex to = any_state(random);
      table.add(from, to);
      ++truth[{from, to}];
      if (rows.size() < 40) rows.push_back(from);
    }
    // for_each_nonzero: exactly the counts, in increasing (from, to) order.
    std::vector<std::pair<std::pair<StateIndex, StateIndex>, std::uint64_t>> visited;
    table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count c) {
      visited.push_back({{from, to}, c});
    });
    const std::vector<std::pair<std::pair<StateIndex, StateIndex>, std::uint64_t>> expected(
        truth.begin(), truth.end());
    ASSERT_EQ(visited, expected) << grid.to_string();
    // best_successor: the brute-force best over every position, ties to the lowest index.
    for (const StateIndex from : rows) {
      for (StateIndex to_centroid = 0; to_centroid < cells; ++to_centroid) {
        for (StateIndex previous = 0; previous < cells; ++previous) {
          TransitionTable::BestSuccessor expected;
          for (StateIndex position = 0; position < cells; ++position) {
            const StateIndex to = codec.compose(to_centroid, position, previous);
            const auto it = truth.find({from, to});
            const std::uint64_t c = it == truth.end() ? 0 : it->second;
            expected.candidates_total += c;
            if (c > expected.best_count) {
              expected.best_count = static_cast<TransitionTable::Count>(c);
              expected.state = to;
            }
          }
          const auto best = table.best_successor(from, to_centroid, previous);
          ASSERT_EQ(best.candidates_total, expected.candidates_total);
          ASSERT_EQ(best.best_count, expected.best_count);
          if (expected.best_count > 0) {
            ASSERT_EQ(best.state, expected.state);
          }
        }
      }
    }
  }
}

TEST(TransitionTable, SparseAndDenseGiveIdenticalPredictions) {
  const Grid grid(3, 2);
  TransitionTable dense(grid, TableStorage::dense);
  TransitionTable sparse(grid, TableStorage::sparse);
  const StateCodec& codec = dense.codec();
  std::mt19937 random(99);
  std::uniform_int_distribution<StateIndex> cell(0, 5);
  // Velocity-consistent transitions, the only kind real data produces.
  for (int i = 0; i < 20000; ++i) {
    const StateIndex from = codec.compose(cell(random), cell(random), cell(random));
    const StateIndex to = codec.compose(cell(random), cell(random), codec.position_id(from));
    dense.add(from, to);
    sparse.add(from, to);
  }
  for (int trial = 0; trial < 200; ++trial) {
    const StateIndex centroid = cell(random);
    std::vector<RobotStateById> robots;
    for (std::uint32_t id = 0; id < 6; ++id) {
      robots.push_back({id, codec.compose(centroid, cell(random), cell(random))});
    }
    Prediction from_dense;
    Prediction from_sparse;
    predict(dense, robots, 3, from_dense);
    predict(sparse, robots, 3, from_sparse);
    ASSERT_EQ(from_dense.steps.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
      const PredictedStep& d = from_dense.steps[k];
      const PredictedStep& s = from_sparse.steps[k];
      ASSERT_EQ(d.centroid, s.centroid);
      ASSERT_EQ(d.confidence, s.confidence);
      for (std::size_t r = 0; r < d.robots.size(); ++r) {
        ASSERT_EQ(d.robots[r].state, s.robots[r].state);
        ASSERT_EQ(d.robots[r].probability, s.robots[r].probability);
      }
    }
  }
}

}  // namespace
}  // namespace ssl_formation
