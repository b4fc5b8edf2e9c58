// A table file kept within its budget: the motion table is pruned until the file fits, and the
// file saved is the size the budget was checked against.

#include "ssl_formation/models/table_budget.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "ssl_formation/models/table_file.hpp"
#include "table_bytes.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;
using namespace ssl_formation::testing;

// Many robots over the whole field, each with its own habit, in running play and in HALT:
// a table whose rows mostly say something, so that only a budget cuts it down.
MotionTable busy_table() {
  MotionConfig config;
  config.step_s = 0.5;
  config.horizons = 2;
  MotionTable table(config);
  std::uint64_t x = 12345;
  const auto next = [&x] {
    x = x * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::int32_t>((x >> 33) % 2001) - 1000;
  };
  double time_s = 0.0;
  for (int i = 0; i < 60000; ++i) {
    MotionInstance instance;
    instance.robot_id = static_cast<std::uint32_t>(i % 11);
    instance.x = (i / 11 % 2) * 9000 - 4500;
    instance.y = (i / 22 % 2) * 6000 - 3000;
    instance.v_x = next() * 2;
    instance.v_y = next() * 2;
    // Each robot overshoots constant velocity by its own amount.
    instance.d_x =
        instance.v_x / 2 + 150 * static_cast<std::int32_t>(instance.robot_id) + next() / 10;
    instance.d_y = instance.v_y / 2 + next() / 10;
    instance.context = i % 7 == 0 ? MotionFeatures::context(0, 0, MotionFeatures::halt_game) : 0;
    table.add(i % 2, time_s, instance);
    time_s += 0.05;
  }
  return table;
}

TEST(TableBudget, TheFileSavedFitsTheBudget) {
  const fs::path dir =
      fs::temp_directory_path() / ("sslf-table-budget-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  ASSERT_TRUE(fs::create_directory(dir));
  const MotionTable motion = busy_table();
  const TransitionTable counts(Grid(3, 2));
  TableMetadata metadata;
  metadata.step_s = 0.5;

  // Without a bound only the rows that add nothing go.
  const auto unbounded = fit_table_to_budget(counts, metadata, motion, table_budget_mb(0));
  ASSERT_TRUE(unbounded) << unbounded.error().message;
  ASSERT_TRUE(save_table(dir / "unbounded.bin", counts, metadata, unbounded->pruned.table));
  EXPECT_EQ(fs::file_size(dir / "unbounded.bin"), unbounded->file_bytes);

  // Everything but the velocity and `all` levels folded: what no budget can cut.
  const auto floor = fit_table_to_budget(counts, metadata, motion, table_budget_mb(0.001));
  ASSERT_TRUE(floor);
  ASSERT_LT(floor->file_bytes + 20000, unbounded->file_bytes) << "too few rows kept to cut";

  // Halfway: fewer rows, the same instances, and a file no larger than the budget.
  const double half_mb =
      static_cast<double>(floor->file_bytes + (unbounded->file_bytes - floor->file_bytes) / 2) /
      1e6;
  const auto bounded = fit_table_to_budget(counts, metadata, motion, table_budget_mb(half_mb));
  ASSERT_TRUE(bounded) << bounded.error().message;
  EXPECT_TRUE(bounded->within_budget);
  EXPECT_LT(bounded->pruned.rows_after, unbounded->pruned.rows_after);
  EXPECT_EQ(bounded->pruned.table.instances(), motion.instances());
  ASSERT_TRUE(save_table(dir / "bounded.bin", counts, metadata, bounded->pruned.table));
  EXPECT_EQ(fs::file_size(dir / "bounded.bin"), bounded->file_bytes);
  EXPECT_LE(bounded->file_bytes, static_cast<std::uint64_t>(half_mb * 1e6) + 1);
  const auto loaded = load_table(dir / "bounded.bin");
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_TRUE(*loaded->motion == bounded->pruned.table);

  // A budget below what the calibration sample alone takes is reported, not met by dropping it.
  EXPECT_FALSE(floor->within_budget);
  EXPECT_EQ(floor->pruned.table.calibration(0), motion.calibration(0));
  EXPECT_EQ(floor->pruned.table.instances(), motion.instances());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ssl_formation
