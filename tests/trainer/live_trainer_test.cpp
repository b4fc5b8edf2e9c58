// The trainer's live mode driven in-process: events in the order a test chooses and a clock it
// moves, the table files on disk. When it saves (the first time as soon as it has something),
// a table per opponent as the referee names them, and what it refuses at start.

#include "ssl_formation/trainer/live_trainer.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>

#include "match_logs.hpp"
#include "moving_robots.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::trainer {
namespace {

constexpr double start_s = 500.0;

// Frame `f`: our team yellow standing in a row, theirs blue moving (moving_robots.hpp).
VisionFrame frame_at(int f) {
  const double t = f / 60.0;
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(f);
  spec.t_capture = start_s + t;
  for (int i = 0; i < 6; ++i) {
    spec.yellow.push_back({static_cast<std::uint32_t>(i), Point{-3000.0, -2500.0 + 1000.0 * i}});
    spec.blue.push_back({static_cast<std::uint32_t>(i), testing::moving_robot_position(7, i, t)});
  }
  VisionFrame frame;
  to_vision_frame(make_detection_packet(spec), frame);
  return frame;
}

std::string match_against(const std::string& them) {
  testing::RefereeSpec spec;
  spec.command = Referee::NORMAL_START;
  spec.yellow = "Us";
  spec.blue = them;
  spec.blue_on_positive_half = false;
  return testing::referee_payload(spec);
}

struct InProcess {
  explicit InProcess(TrainerOptions o, SaveHooks hooks = {})
      : options(std::move(o)), trainer(options, clock, std::move(hooks)) {}
  // Frames `from` to `to` - 1, 1/60 s apart on both clocks, the timers ticking as they would.
  void frames(int from, int to) {
    for (int f = from; f < to; ++f) {
      const VisionFrame frame = frame_at(f);
      clock.advance(1.0 / 60.0);
      trainer.on_event(MatchEvent::vision(frame, clock.steady_s()));
      if (f % 12 == 0) trainer.tick();
    }
  }
  void referee(const std::string& payload) {
    trainer.on_event(MatchEvent::referee(payload, clock.steady_s()));
  }
  // The game controller says `payload` ten times a second for 1.2 s: long enough for new team
  // names to take over (RefereeFollower::name_hold_s).
  void referee_held(const std::string& payload) {
    for (int i = 0; i <= 12; ++i) {
      if (i > 0) clock.advance(0.1);
      referee(payload);
    }
  }

  TrainerOptions options;
  app::ManualClock clock;
  LiveTrainer trainer;
};

TEST(LiveTrainer, SavesAsSoonAsItHasSomethingThenEveryFlushInterval) {
  testing::ScratchDir dir;
  TrainerOptions options;
  options.table = (dir.path() / "t.bin").string();
  options.model.opponent_color = "blue";
  options.flush_interval_s = 10.0;
  InProcess live(options);
  EXPECT_FALSE(std::filesystem::exists(options.table));
  live.trainer.tick();  // nothing learned: nothing written
  EXPECT_EQ(live.trainer.saves(), 0u);
  EXPECT_FALSE(std::filesystem::exists(options.table));
  live.frames(0, 60);  // one second
  ASSERT_EQ(live.trainer.saves(), 1u);
  ASSERT_TRUE(live.trainer.wait_for_saves());  // made on the saver's thread
  ASSERT_TRUE(std::filesystem::exists(options.table));
  live.frames(60, 9 * 60);  // nine seconds on: within the flush interval of the first save
  EXPECT_EQ(live.trainer.saves(), 1u);
  live.frames(9 * 60, 12 * 60);
  EXPECT_EQ(live.trainer.saves(), 2u);
  ASSERT_TRUE(live.trainer.save_at_exit());
  const auto saved = load_table(options.table, Grid(3, 2));
  ASSERT_TRUE(saved) << saved.error().message;
  EXPECT_EQ(saved->metadata.samples, 12u * 60u);
  ASSERT_TRUE(saved->motion);
  EXPECT_GT(saved->motion->instances(), 1000u);
}

// A save is made on a thread of its own: while one is held at its end (a slow disk, a big table),
// the trainer goes on taking frames and learning from them, and the file appears once the save
// is let go.
TEST(LiveTrainer, TrainsOnWhileATableIsBeingSaved) {
  testing::ScratchDir dir;
  TrainerOptions options;
  options.table = (dir.path() / "t.bin").string();
  options.model.opponent_color = "blue";
  options.flush_interval_s = 10.0;
  std::mutex mutex;
  std::condition_variable changed;
  bool saving = false;
  bool released = false;
  SaveHooks hooks;
  hooks.before_rename = [&] {
    std::unique_lock lock(mutex);
    saving = true;
    changed.notify_all();
    changed.wait(lock, [&] { return released; });
    return true;
  };
  InProcess live(options, std::move(hooks));
  live.frames(0, 60);
  ASSERT_EQ(live.trainer.saves(), 1u);
  {
    std::unique_lock lock(mutex);
    ASSERT_TRUE(changed.wait_for(lock, std::chrono::seconds(60), [&] { return saving; }))
        << "the first save never began";
  }
  // Held: ten more seconds of frames are taken and learned from meanwhile.
  const std::uint64_t before = live.trainer.training().samples();
  live.frames(60, 11 * 60);
  EXPECT_EQ(live.trainer.training().samples(), before + 10 * 60);
  EXPECT_FALSE(std::filesystem::exists(options.table)) << "written before it was let go";
  {
    const std::lock_guard lock(mutex);
    released = true;
  }
  changed.notify_all();
  ASSERT_TRUE(live.trainer.wait_for_saves());
  ASSERT_TRUE(std::filesystem::exists(options.table));
  // The second save (at 11 s) is the latest; at exit everything is in the file.
  ASSERT_TRUE(live.trainer.save_at_exit());
  const auto saved = load_table(options.table, Grid(3, 2));
  ASSERT_TRUE(saved) << saved.error().message;
  EXPECT_EQ(saved->metadata.samples, 11u * 60u);
}

TEST(LiveTrainer, ATablePerOpponentAsTheRefereeNamesThem) {
  testing::ScratchDir dir;
  const auto tables = dir.path() / "tables";
  TrainerOptions options;
  options.table_dir = tables.string();
  options.model.our_team = "Us";
  options.flush_interval_s = 1000.0;
  InProcess live(options);
  live.referee(match_against("Alpha"));
  live.frames(0, 150);
  // Alpha's table is written as Beta comes, while the trainer runs on.
  live.referee_held(match_against("Beta"));
  ASSERT_TRUE(live.trainer.wait_for_saves());
  EXPECT_TRUE(std::filesystem::exists(tables / "alpha.bin"));
  live.frames(1000, 1150);  // later on the data clock: a new stream
  ASSERT_TRUE(live.trainer.save_at_exit());
  const auto alpha = load_table(tables / "alpha.bin", Grid(3, 2));
  const auto beta = load_table(tables / "beta.bin", Grid(3, 2));
  ASSERT_TRUE(alpha) << alpha.error().message;
  ASSERT_TRUE(beta) << beta.error().message;
  EXPECT_GT(alpha->table.transitions(), 100u);
  EXPECT_GT(beta->table.transitions(), 100u);
  // As many frames each: neither table took the other's.
  EXPECT_EQ(alpha->metadata.samples, 150u);
  EXPECT_EQ(beta->metadata.samples, 150u);
  // Nothing was learned before the referee named anyone: no table for an unnamed team.
  EXPECT_FALSE(std::filesystem::exists(tables / "unknown.bin"));
}

TEST(LiveTrainer, AFeedOfFormationsSecondsApartIsNamedAsWhyNothingIsLearned) {
  testing::ScratchDir dir;
  TrainerOptions options;
  options.table = (dir.path() / "t.bin").string();
  options.model.opponent_color = "blue";
  InProcess live(options);
  for (int f = 0; f < 8; ++f) {
    const VisionFrame frame = frame_at(f * 120);  // 2 s of data time apart
    live.trainer.on_event(MatchEvent::vision(frame, live.clock.steady_s()));
  }
  const auto problem = live.trainer.training().feed_problem();
  ASSERT_TRUE(problem);
  EXPECT_NE(problem->find("--model paper"), std::string::npos) << *problem;
  EXPECT_EQ(live.trainer.training().stored_table().motion->instances(), 0u);
}

TEST(LiveTrainer, ATableFolderThatDoesNotExistIsRefusedAtStart) {
  TrainerOptions options;
  options.table = "/nonexistent-sslf-folder/x.bin";
  app::ManualClock clock;
  EXPECT_THROW(LiveTrainer(options, clock), app::UsageError);
}

}  // namespace
}  // namespace ssl_formation::trainer
