#include "ssl_formation/trainer/table_store.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "scratch_dir.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::trainer {
namespace {

namespace fs = std::filesystem;

// A fresh folder for each test, removed with everything in it.
class TempDir : public testing::ScratchDir {
 public:
  TempDir() : ScratchDir("sslf-table-store") {}
};

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

SamplerConfig config_of(Grid grid, double step_s = 2.0) {
  SamplerConfig config;
  config.grid = grid;
  config.step_s = step_s;
  return config;
}

struct Robot {
  std::uint32_t id;
  double x;
  double y;
};

// One camera's detection frame of yellow robots (the default opponent).
SSL_WrapperPacket detection(double t_capture, const std::vector<Robot>& robots) {
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(t_capture * 10);
  spec.t_capture = t_capture;
  for (const Robot& robot : robots) {
    spec.yellow.push_back({robot.id, {robot.x, robot.y}});
  }
  return make_detection_packet(spec);
}

SSL_WrapperPacket geometry(int length_mm, int width_mm) {
  return make_geometry_packet(
      FieldSize{static_cast<double>(length_mm), static_cast<double>(width_mm)});
}

// Feeds `n` frames, one per step from `t0`, of two robots walking across the field: samples
// with transitions.
void feed_walk(Training& training, double t0, int n) {
  const double step = training.sampler().config().step_s;
  for (int i = 0; i < n; ++i) {
    const double x = -4000.0 + 2500.0 * (i % 4);
    training.add(detection(t0 + step * i, {{1, x, -1500.0}, {2, -x, 1500.0}}));
  }
}

using Entries = std::vector<std::tuple<StateIndex, StateIndex, TransitionTable::Count>>;
Entries entries(const TransitionTable& table) {
  Entries out;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
    out.emplace_back(from, to, count);
  });
  return out;
}

// The saved table, or a failure naming why it did not load.
StoredTable load(const fs::path& path, Grid grid) {
  auto loaded = load_table(path, grid);
  if (!loaded) throw std::runtime_error(loaded.error().message);
  return std::move(*loaded);
}

// A table file with counts, saved as the trainer saves it.
void save_trained_table(const fs::path& path, const SamplerConfig& config) {
  Training training(config, TransitionTable(config.grid));
  feed_walk(training, 100.0, 6);
  ASSERT_GT(training.stored_table().table.transitions(), 0u);
  ASSERT_TRUE(save_training(path, training));
}

TEST(OpenTraining, NoFileStartsEmpty) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  const auto training = open_training(path, config_of(Grid(3, 2)), false);
  ASSERT_NE(training, nullptr);
  EXPECT_EQ(training->stored_table().table.grid(), Grid(3, 2));
  EXPECT_EQ(training->stored_table().table.transitions(), 0u);
  EXPECT_EQ(training->samples(), 0u);
  EXPECT_FALSE(training->changed_since_save());
  EXPECT_FALSE(fs::exists(path)) << "opening must not create the file";
}

TEST(SaveTraining, RoundTripsCountsAndMetadata) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  SamplerConfig config = config_of(Grid(3, 2), 1.5);
  config.field = FieldSize{10400.0, 7400.0};  // until geometry says otherwise
  auto training = open_training(path, config, false);
  training->add(geometry(12000, 9000));
  feed_walk(*training, 50.0, 7);
  ASSERT_GT(training->stored_table().table.transitions(), 0u);
  ASSERT_GT(training->samples(), 0u);
  EXPECT_TRUE(training->changed_since_save());

  ASSERT_TRUE(save_training(path, *training));
  EXPECT_FALSE(training->changed_since_save()) << "a save marks the training saved";

  const StoredTable stored = load(path, Grid(3, 2));
  EXPECT_EQ(stored.metadata.field, (FieldSize{12000.0, 9000.0})) << "the field from geometry";
  EXPECT_EQ(stored.metadata.step_s, 1.5);
  EXPECT_EQ(stored.metadata.samples, training->samples());
  EXPECT_EQ(stored.table.transitions(), training->stored_table().table.transitions());
  EXPECT_EQ(entries(stored.table), entries(training->stored_table().table));
}

TEST(SaveTraining, TheFieldOfTheOptionsWithoutGeometry) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  SamplerConfig config = config_of(Grid(2, 2));
  config.field = FieldSize{10400.0, 7400.0};
  Training training(config, TransitionTable(config.grid));
  feed_walk(training, 0.0, 3);
  ASSERT_TRUE(save_training(path, training));
  EXPECT_EQ(load(path, Grid(2, 2)).metadata.field, (FieldSize{10400.0, 7400.0}));
}

TEST(SaveTraining, MarkSavedOnlyOnSuccess) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  Training training(config_of(Grid(3, 2)), TransitionTable(Grid(3, 2)));
  feed_walk(training, 0.0, 4);
  ASSERT_TRUE(training.changed_since_save());

  // A folder that cannot exist: its parent is a regular file.
  write_bytes(dir.path() / "file", "x");
  EXPECT_FALSE(save_training(dir.path() / "file" / "table.sslf", training));
  EXPECT_TRUE(training.changed_since_save()) << "a failed save leaves the changes unsaved";

  ASSERT_TRUE(save_training(path, training));
  EXPECT_FALSE(training.changed_since_save());
  feed_walk(training, 100.0, 3);  // more counts: changed again
  EXPECT_TRUE(training.changed_since_save());
  ASSERT_TRUE(save_training(path, training));
  EXPECT_FALSE(training.changed_since_save());
  EXPECT_EQ(load(path, Grid(3, 2)).metadata.samples, training.samples());
}

TEST(OpenTraining, ResumesCountsAndSamples) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  const SamplerConfig config = config_of(Grid(3, 2));
  Entries saved_entries;
  std::uint64_t saved_samples = 0;
  {
    auto first = open_training(path, config, false);
    feed_walk(*first, 100.0, 6);
    ASSERT_TRUE(save_training(path, *first));
    saved_entries = entries(first->stored_table().table);
    saved_samples = first->samples();
  }
  ASSERT_FALSE(saved_entries.empty());
  ASSERT_GT(saved_samples, 0u);

  auto resumed = open_training(path, config, false);
  EXPECT_EQ(entries(resumed->stored_table().table), saved_entries);
  EXPECT_EQ(resumed->samples(), saved_samples);
  EXPECT_FALSE(resumed->changed_since_save()) << "nothing new since the file";

  // Training goes on from there: the samples add up and so do the counts.
  const std::uint64_t transitions_before = resumed->stored_table().table.transitions();
  feed_walk(*resumed, 500.0, 5);
  const std::uint64_t new_samples = resumed->sampler().counters().samples;
  ASSERT_GT(new_samples, 0u);
  EXPECT_EQ(resumed->samples(), saved_samples + new_samples);
  EXPECT_EQ(resumed->stored_table().table.transitions(),
            transitions_before + resumed->sampler().counters().transitions);
  EXPECT_TRUE(resumed->changed_since_save());
  ASSERT_TRUE(save_training(path, *resumed));
  EXPECT_EQ(load(path, Grid(3, 2)).metadata.samples, saved_samples + new_samples);
}

// The refusal names the file and what to do, and leaves the file byte for byte as it was.
void expect_refused(const fs::path& path, const SamplerConfig& config,
                    const std::vector<std::string>& in_message) {
  const std::string before = read_bytes(path);
  try {
    (void)open_training(path, config, false);
    ADD_FAILURE() << "open_training accepted " << path;
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find("--reset"), std::string::npos) << message;
    for (const std::string& part : in_message) {
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' in: " << message;
    }
  }
  EXPECT_EQ(read_bytes(path), before) << "a refused file must be left as it was";
}

TEST(OpenTraining, RefusesATableOfAnotherGrid) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save_trained_table(path, config_of(Grid(3, 2)));
  expect_refused(path, config_of(Grid(4, 3)), {"3x2", "4x3"});
}

TEST(OpenTraining, RefusesATableOfAnotherStep) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save_trained_table(path, config_of(Grid(3, 2), 2.0));
  expect_refused(path, config_of(Grid(3, 2), 1.0), {"--step"});
}

TEST(OpenTraining, RefusesACorruptTable) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save_trained_table(path, config_of(Grid(3, 2)));
  std::string bytes = read_bytes(path);
  ASSERT_GT(bytes.size(), 200u);
  bytes[150] = static_cast<char>(bytes[150] ^ 0x40);  // one flipped bit among the counts
  write_bytes(path, bytes);
  expect_refused(path, config_of(Grid(3, 2)), {"corrupt"});

  write_bytes(path, "not a table at all");
  expect_refused(path, config_of(Grid(3, 2)), {});
}

TEST(OpenTraining, ResetLeavesTheOldFileUntilTheFirstSave) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save_trained_table(path, config_of(Grid(3, 2), 2.0));
  const std::string old_bytes = read_bytes(path);

  // Another grid and another step: refused without --reset, an empty table with it.
  const SamplerConfig config = config_of(Grid(4, 3), 1.0);
  auto training = open_training(path, config, true);
  ASSERT_NE(training, nullptr);
  EXPECT_EQ(training->stored_table().table.grid(), Grid(4, 3));
  EXPECT_EQ(training->stored_table().table.transitions(), 0u);
  EXPECT_EQ(training->samples(), 0u);
  EXPECT_EQ(read_bytes(path), old_bytes) << "--reset must not touch the file before a save";

  feed_walk(*training, 10.0, 5);
  EXPECT_EQ(read_bytes(path), old_bytes);
  ASSERT_TRUE(save_training(path, *training));
  const StoredTable stored = load(path, Grid(4, 3));
  EXPECT_EQ(stored.metadata.step_s, 1.0);
  EXPECT_EQ(stored.metadata.samples, training->samples());
  EXPECT_EQ(entries(stored.table), entries(training->stored_table().table));
}

TEST(OpenTraining, ResetAcceptsACorruptFile) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  write_bytes(path, "garbage");
  auto training = open_training(path, config_of(Grid(3, 2)), true);
  EXPECT_EQ(training->stored_table().table.transitions(), 0u);
  EXPECT_EQ(read_bytes(path), "garbage");
}

// A pid no process has: a child that has exited and been reaped.
pid_t dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  if (child < 0) throw std::runtime_error("fork failed");
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

TEST(OpenTraining, RemovesTheTemporariesOfDeadTrainersOnly) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  const std::string dead = std::to_string(dead_pid());
  const std::string live = std::to_string(::getpid());
  const std::vector<std::string> stale{"table.sslf.tmp-" + dead + "-0",
                                       "table.sslf.tmp-" + dead + "-17"};
  const std::vector<std::string> kept{
      "table.sslf.tmp-" + live + "-0",   // a save under way in a live process
      "table.sslf.tmp-1-3",              // pid 1 always exists
      "table.sslf.tmp-" + dead,          // not the save's pattern: no counter
      "table.sslf.tmp--" + dead + "-0",  // nor this
      "table.sslf.tmp-0-0",              // nor pid 0
      "table.sslf.tmp-x" + dead + "-0",
      "other.sslf.tmp-" + dead + "-0",  // another table's
      "table.sslf.old",
  };
  for (const auto& name : stale) write_bytes(dir.path() / name, "partial");
  for (const auto& name : kept) write_bytes(dir.path() / name, "partial");

  auto training = open_training(path, config_of(Grid(3, 2)), false);
  ASSERT_NE(training, nullptr);
  for (const auto& name : stale) EXPECT_FALSE(fs::exists(dir.path() / name)) << name;
  for (const auto& name : kept) EXPECT_TRUE(fs::exists(dir.path() / name)) << name;
}

TEST(OpenTraining, RemovesStaleTemporariesBesideAnExistingTableAndWithReset) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save_trained_table(path, config_of(Grid(3, 2)));
  const std::string table_bytes = read_bytes(path);
  const fs::path stale = dir.path() / ("table.sslf.tmp-" + std::to_string(dead_pid()) + "-2");
  write_bytes(stale, "partial");
  (void)open_training(path, config_of(Grid(3, 2)), false);
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_EQ(read_bytes(path), table_bytes);

  const fs::path stale_again = dir.path() / ("table.sslf.tmp-" + std::to_string(dead_pid()) + "-3");
  write_bytes(stale_again, "partial");
  (void)open_training(path, config_of(Grid(3, 2)), true);
  EXPECT_FALSE(fs::exists(stale_again));
  EXPECT_EQ(read_bytes(path), table_bytes);
}

}  // namespace
}  // namespace ssl_formation::trainer
