// ssl-trainer without the network: --from-log and merge, as processes on real files. The logs are
// the simulated producer's, whose opponent jumps between formations every 2 s (the paper's
// scenario): the trainer runs --model paper on them, and the library's reference is the paper's
// model. motion_daemons_test.cpp trains the default motion model from a log of moving robots.

#include <gtest/gtest.h>
#include <signal.h>

#include "child_process.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;

// Writes the simulated stream of `seed` as an official log, as a recorder would.
void write_simulated_log(const std::filesystem::path& path, std::uint64_t seed, int formations,
                         int cameras = 1) {
  simulation::SimulationConfig config;
  config.seed = seed;
  config.cameras = cameras;
  simulation::SimulatedVision vision(config);
  auto writer = LogWriter::create(path);
  ASSERT_TRUE(writer) << writer.error().message;
  for (int i = 0; i < formations; ++i) {
    const simulation::SimulatedFormation f = vision.next();
    for (const auto& packet : f.packets) {
      ASSERT_TRUE(writer->write_vision(packet, static_cast<std::int64_t>(f.t_capture * 1e9)));
    }
    // Referee and tracker messages are in real logs too: they must be skipped.
    ASSERT_TRUE(writer->write(3, static_cast<std::int64_t>(f.t_capture * 1e9), "referee"));
    ASSERT_TRUE(writer->write(5, static_cast<std::int64_t>(f.t_capture * 1e9), "tracker"));
  }
  ASSERT_TRUE(writer->close());
}

// What the library computes from the same files, one stream per file, with the paper's model
// (SamplerConfig's defaults: step sampling every 2 s, no motion table).
TransitionTable library_table(const std::vector<std::filesystem::path>& logs,
                              std::uint64_t* samples = nullptr) {
  Training training(SamplerConfig{}, TransitionTable(Grid(3, 2)));
  for (const auto& log : logs) {
    training.start_new_stream();
    const LogVisionPackets read = read_vision_log(log).value();
    for (const auto& packet : read.packets) training.add(packet);
  }
  if (samples) *samples = training.samples();
  return training.stored_table().table;
}

const auto entries = testing::table_entries;

// `ssl-trainer ARGS --model paper` (merge takes tables of either model, and no --model).
testing::RunResult trainer(const TempDir& dir, std::vector<std::string> args,
                           const std::string& name) {
  if (args.empty() || args.front() != "merge") {
    args.push_back("--model");
    args.push_back("paper");
  }
  return testing::run_to_end(trainer_program, std::move(args), dir.path(), name, 60s);
}

TEST(OfflineTraining, FromLogTrainsWhatTheLibraryComputes) {
  TempDir dir;
  write_simulated_log(dir / "a.log.gz", 1, 400, 4);
  const auto run =
      trainer(dir, {"--from-log", (dir / "a.log.gz").string(), "--table", (dir / "t.bin").string()},
              "train");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("400 referee, skipped 400 tracker"), std::string::npos) << run.err;
  const auto loaded = load_table(dir / "t.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  std::uint64_t samples = 0;
  const TransitionTable expected = library_table({dir / "a.log.gz"}, &samples);
  EXPECT_EQ(samples, 400u);
  EXPECT_EQ(entries(loaded->table), entries(expected));
  EXPECT_EQ(loaded->metadata.samples, 400u);
}

TEST(OfflineTraining, MergeEqualsTrainingOnBothLogsTogether) {
  TempDir dir;
  write_simulated_log(dir / "a.log", 1, 300);
  write_simulated_log(dir / "b.log.gz", 2, 500);
  ASSERT_EQ(
      trainer(dir, {"--from-log", (dir / "a.log").string(), "--table", (dir / "ta.bin").string()},
              "a")
          .exit_code,
      0);
  ASSERT_EQ(
      trainer(dir,
              {"--from-log", (dir / "b.log.gz").string(), "--table", (dir / "tb.bin").string()},
              "b")
          .exit_code,
      0);
  const auto both = trainer(dir,
                            {"--from-log", (dir / "a.log").string(), (dir / "b.log.gz").string(),
                             "--table", (dir / "tab.bin").string()},
                            "ab");
  ASSERT_EQ(both.exit_code, 0) << both.err;
  const auto merge = trainer(dir,
                             {"merge", (dir / "ta.bin").string(), (dir / "tb.bin").string(), "-o",
                              (dir / "merged.bin").string()},
                             "merge");
  ASSERT_EQ(merge.exit_code, 0) << merge.err;

  const auto merged = load_table(dir / "merged.bin", Grid(3, 2));
  const auto together = load_table(dir / "tab.bin", Grid(3, 2));
  ASSERT_TRUE(merged && together);
  EXPECT_EQ(entries(merged->table), entries(together->table));
  EXPECT_EQ(merged->metadata.samples, 800u);
  EXPECT_EQ(together->metadata.samples, 800u);
  EXPECT_EQ(entries(together->table), entries(library_table({dir / "a.log", dir / "b.log.gz"})));
}

TEST(OfflineTraining, MergeRefusesDifferentGridsClearly) {
  TempDir dir;
  write_simulated_log(dir / "a.log", 1, 50);
  ASSERT_EQ(
      trainer(dir,
              {"--from-log", (dir / "a.log").string(), "--table", (dir / "small.bin").string()},
              "a")
          .exit_code,
      0);
  ASSERT_EQ(trainer(dir,
                    {"--from-log", (dir / "a.log").string(), "--table",
                     (dir / "large.bin").string(), "--grid", "12x9"},
                    "b")
                .exit_code,
            0);
  const auto merge = trainer(dir,
                             {"merge", (dir / "small.bin").string(), (dir / "large.bin").string(),
                              "-o", (dir / "out.bin").string()},
                             "merge");
  EXPECT_EQ(merge.exit_code, 1);
  EXPECT_NE(merge.err.find("12x9"), std::string::npos) << merge.err;
  EXPECT_NE(merge.err.find("3x2"), std::string::npos) << merge.err;
  EXPECT_NE(merge.err.find("different grids"), std::string::npos) << merge.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.bin"));
  EXPECT_EQ(trainer(dir, {"merge", "-o", (dir / "out.bin").string()}, "none").exit_code, 2);
}

TEST(OfflineTraining, ADamagedLogSaysWhereAndFailsTheRunWhichWritesNothing) {
  TempDir dir;
  write_simulated_log(dir / "a.log", 1, 200);
  const auto size = std::filesystem::file_size(dir / "a.log");
  std::filesystem::resize_file(dir / "a.log", size / 2);
  const auto run = trainer(dir,
                           {"--from-log", (dir / "a.log").string(), (dir / "missing.log").string(),
                            "--table", (dir / "t.bin").string()},
                           "damaged");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("truncated message at byte"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("missing.log: cannot open"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("no table written"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "t.bin"));
  // The missing log left out, the cut log's packets before the cut are learned (a cut in the
  // last message is a warning without --strict).
  const auto rest =
      trainer(dir, {"--from-log", (dir / "a.log").string(), "--table", (dir / "t.bin").string()},
              "cut-alone");
  EXPECT_EQ(rest.exit_code, 0) << rest.err;
  const auto loaded = load_table(dir / "t.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(entries(loaded->table), entries(library_table({dir / "a.log"})));
  EXPECT_GT(loaded->table.transitions(), 300u);
}

// The live path and the offline path are the same code: a paced replay of a log into a live
// trainer counts exactly what --from-log counts from the file.
TEST(OfflineTraining, LiveTrainingOnAPacedReplayEqualsOfflineTraining) {
  TempDir dir;
  write_simulated_log(dir / "match.log.gz", 17, 300, 4);
  const auto offline = trainer(
      dir,
      {"--from-log", (dir / "match.log.gz").string(), "--table", (dir / "offline.bin").string()},
      "offline");
  ASSERT_EQ(offline.exit_code, 0) << offline.err;

  const std::string group = testing::new_group();
  testing::ChildProcess live(trainer_program,
                             {"--vision-address", group, "--table", (dir / "live.bin").string(),
                              "--status-interval", "0.1", "--model", "paper"},
                             dir.path(), "live", testing::Readiness::ready_file);
  ASSERT_TRUE(live.wait_until_ready(10s)) << live.stderr_text();
  // 300 formations of 2 s of data time at 300x: 2 s of wall time, with the recorded spacing.
  const auto replay = testing::run_to_end(
      producer_program,
      // The log's (made-up) referee and tracker messages kept off the default groups, which
      // other tests' daemons join.
      {"--replay", (dir / "match.log.gz").string(), "--speed", "300", "--vision-address", group,
       "--referee-address", "none", "--tracker-address", "none"},
      dir.path(), "replay", 60s);
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  ASSERT_TRUE(testing::wait_for_status(live, "formations", 300, 10s)) << live.stderr_text();
  live.signal(SIGTERM);
  ASSERT_EQ(live.wait(5s), 0);

  const auto a = load_table(dir / "offline.bin", Grid(3, 2));
  const auto b = load_table(dir / "live.bin", Grid(3, 2));
  ASSERT_TRUE(a && b);
  EXPECT_GT(a->table.transitions(), 1500u);
  EXPECT_EQ(entries(a->table), entries(b->table));
  EXPECT_EQ(a->metadata.samples, b->metadata.samples);
}

TEST(OfflineTraining, ResumesAnExistingTable) {
  TempDir dir;
  write_simulated_log(dir / "a.log", 1, 100);
  for (int run = 0; run < 2; ++run) {
    ASSERT_EQ(
        trainer(dir, {"--from-log", (dir / "a.log").string(), "--table", (dir / "t.bin").string()},
                "run")
            .exit_code,
        0);
  }
  const auto loaded = load_table(dir / "t.bin", Grid(3, 2));
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->table.transitions(), 2 * library_table({dir / "a.log"}).transitions());
}

}  // namespace
}  // namespace ssl_formation
