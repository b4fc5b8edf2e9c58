// Pruning a motion table: rows that say nothing their parent does not are folded into it, the
// coarser sums stay exact, and tables still add up.

#include "ssl_formation/motion_model/motion_table_pruning.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "motion_table_sums.hpp"
#include "ssl_formation/motion_model/motion_estimates.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
namespace {

MotionConfig one_horizon() {
  MotionConfig config;
  config.step_s = 0.5;
  config.horizons = 1;
  return config;
}

// `count` instances of a robot at (x, y) moving at `v_x` mm/s along x, whose displacement over
// the horizon is constant velocity's plus `offset_mm` along x, give or take 150 mm;
// only at times that are not held out, so that every one is counted in a row.
void add_robot(MotionTable& table, std::uint32_t robot_id, std::int32_t x, std::int32_t y,
               std::int32_t v_x, int count, std::int32_t offset_mm, std::uint32_t context,
               double& time_s) {
  for (int i = 0; i < count; ++i) {
    while (table.is_held_out(time_s)) time_s += 0.1;
    MotionInstance instance;
    instance.robot_id = robot_id;
    instance.x = x;
    instance.y = y;
    instance.v_x = v_x;
    instance.d_x = v_x / 2 + offset_mm + (i * 37) % 301 - 150;
    instance.d_y = (i * 53) % 301 - 150;
    instance.context = context;
    table.add(0, time_s, instance);
    time_s += 0.1;
  }
}

MotionKey robot_key(std::uint32_t robot_id, std::int32_t x, std::int32_t y, std::int32_t v_x,
                    std::uint32_t context) {
  MotionInstance instance;
  instance.robot_id = robot_id;
  instance.x = x;
  instance.y = y;
  instance.v_x = v_x;
  instance.context = context;
  return encode_motion_key(motion_key_parts(0, instance));
}

using testing::coarse_motion_sums;

constexpr std::uint32_t running = 0;
const std::uint32_t halted = MotionFeatures::context(0, 0, MotionFeatures::halt_game);

// At 1 m/s, zone "alike": two robots that move the same way, and a robot with three instances
// elsewhere. At 2.5 m/s, zone "apart": two robots, one 600 mm ahead of constant velocity, the
// other 600 mm behind it. And a robot in HALT.
struct HandBuilt {
  MotionTable table{one_horizon()};
  MotionKey alike_1 = robot_key(1, -3000, 0, 1000, running);
  MotionKey alike_2 = robot_key(2, -3000, 0, 1000, running);
  MotionKey few = robot_key(5, 3000, 2000, 1000, running);
  MotionKey ahead = robot_key(3, 3000, 0, 2500, running);
  MotionKey behind = robot_key(4, 3000, 0, 2500, running);
  MotionKey halt = robot_key(6, -3000, 2000, 1000, halted);
  HandBuilt() {
    double time_s = 0.0;
    add_robot(table, 1, -3000, 0, 1000, 300, 0, running, time_s);
    add_robot(table, 2, -3000, 0, 1000, 300, 0, running, time_s);
    add_robot(table, 5, 3000, 2000, 1000, 3, 900, running, time_s);
    add_robot(table, 3, 3000, 0, 2500, 300, 600, running, time_s);
    add_robot(table, 4, 3000, 0, 2500, 300, -600, running, time_s);
    add_robot(table, 6, -3000, 2000, 1000, 300, 400, halted, time_s);
  }
};

TEST(MotionTablePruning, KeepsRowsThatDifferAndFoldsRowsThatDoNot) {
  const HandBuilt built;
  ASSERT_NE(coarser_motion_key(built.alike_1), coarser_motion_key(built.ahead))
      << "the two pairs must sit in different zones";
  ASSERT_EQ(coarser_motion_key(built.ahead), coarser_motion_key(built.behind));
  ASSERT_NE(coarser_motion_key(coarser_motion_key(built.alike_1)),
            coarser_motion_key(coarser_motion_key(built.ahead)))
      << "the two pairs must have different velocity classes";
  for (const MotionKey key :
       {built.alike_1, built.alike_2, built.ahead, built.behind, built.few, built.halt}) {
    ASSERT_NE(built.table.row_map().find(key), nullptr);
  }

  // The default threshold is tuned on simulated matches (motion_table_pruning.hpp); on these few
  // hand-built rows a clearer one shows the rule: a row that moves as its zone does gains a few
  // nats (its spread is held a little less towards the wider spread above), one 600 mm off its
  // zone thousands.
  MotionPruning pruning;
  pruning.min_gain_nats = 10.0;
  const MotionPruned pruned = prune_motion_table(built.table, MotionModelSettings{}, pruning);
  const MotionRowMap& rows = pruned.table.row_map();
  EXPECT_NE(rows.find(built.ahead), nullptr) << "600 mm ahead of its zone, 300 times";
  EXPECT_NE(rows.find(built.behind), nullptr);
  EXPECT_EQ(rows.find(built.alike_1), nullptr) << "moves as its zone does";
  EXPECT_EQ(rows.find(built.alike_2), nullptr);
  EXPECT_EQ(rows.find(built.few), nullptr) << "three instances say little";
  EXPECT_EQ(rows.find(built.halt), nullptr) << "HALT reads the velocity level";
  // The folded rows went into their parents: the alike zone holds both robots' instances.
  const MotionRow* zone = rows.find(coarser_motion_key(built.alike_1));
  ASSERT_NE(zone, nullptr);
  EXPECT_EQ(zone->n(), 600);
  EXPECT_LT(pruned.rows_after, pruned.rows_before);
  EXPECT_EQ(pruned.rows_after, pruned.table.rows());

  // Nothing coarser changed, nor what the table counts and holds out.
  EXPECT_EQ(coarse_motion_sums(pruned.table), coarse_motion_sums(built.table));
  EXPECT_EQ(pruned.table.instances(), built.table.instances());
  EXPECT_EQ(pruned.table.held_out(), built.table.held_out());
  EXPECT_EQ(pruned.table.calibration(0), built.table.calibration(0));

  // A pruned table prunes to itself.
  const MotionPruned again = prune_motion_table(pruned.table, MotionModelSettings{}, pruning);
  EXPECT_TRUE(again.table == pruned.table);
  EXPECT_EQ(again.folded, 0u);
}

TEST(MotionTablePruning, ABoundOnRowsFoldsTheLeastUsefulFirst) {
  const HandBuilt built;
  const MotionPruned free = prune_motion_table(built.table, MotionModelSettings{}, {});
  MotionPruning bounded;
  bounded.max_rows = free.rows_after - 1;
  const MotionPruned pruned = prune_motion_table(built.table, MotionModelSettings{}, bounded);
  EXPECT_LE(pruned.rows_after, bounded.max_rows);
  // Ahead and behind differ alike from their zone: one of them goes, and with the last robot
  // row of the zone gone its zone is the next candidate; the sums above stay exact.
  EXPECT_EQ(coarse_motion_sums(pruned.table), coarse_motion_sums(built.table));
  EXPECT_EQ(pruned.table.instances(), built.table.instances());

  // Bounded to a single row: everything but the velocity and `all` levels is folded.
  bounded.max_rows = 1;
  const MotionPruned least = prune_motion_table(built.table, MotionModelSettings{}, bounded);
  least.table.row_map().for_each([](MotionKey key, const MotionRow&) {
    EXPECT_GE(static_cast<int>(decode_motion_key(key).level),
              static_cast<int>(MotionLevel::velocity));
  });
  EXPECT_EQ(least.table.instances(), built.table.instances());
}

// Pruned tables still add up: merged, their coarser sums are those of the tables merged whole,
// and a robot's row kept in both holds both tables' instances.
TEST(MotionTablePruning, PrunedTablesMergeByAddingUp) {
  const HandBuilt a;
  const HandBuilt b;
  MotionTable whole = a.table;
  whole.merge(b.table);
  MotionTable merged = prune_motion_table(a.table, MotionModelSettings{}, {}).table;
  merged.merge(prune_motion_table(b.table, MotionModelSettings{}, {}).table);
  EXPECT_EQ(coarse_motion_sums(merged), coarse_motion_sums(whole));
  EXPECT_EQ(merged.instances(), whole.instances());
  ASSERT_NE(merged.row_map().find(a.ahead), nullptr);
  EXPECT_EQ(merged.row_map().find(a.ahead)->n(), 600);
}

}  // namespace
}  // namespace ssl_formation
