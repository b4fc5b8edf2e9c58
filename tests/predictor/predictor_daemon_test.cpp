// The predictor's daemon driven in-process: events in the order a test chooses, a clock it moves,
// the predictions kept in memory. What the process tests could only do with sleeps between two
// sockets (the referee and the vision have no order on the network) is exact here.

#include "ssl_formation/predictor/predictor_daemon.hpp"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <thread>

#include "match_logs.hpp"
#include "moving_robots.hpp"
#include "recorded_output.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::predictor {
namespace {

constexpr double start_s = 500.0;  // t_capture of the feed's first frame
// Generous: a loaded machine may take seconds to read and prepare a small table.
constexpr std::chrono::seconds load_timeout{30};

// Frame `f` of the feed: our team yellow (standing in a row), theirs blue, moving as
// moving_robots.hpp's robots turned about the centre (they attack -x).
SSL_WrapperPacket frame_packet(int f) {
  const double t = f / 60.0;
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(f);
  spec.t_capture = start_s + t;
  for (int i = 0; i < 6; ++i) {
    spec.yellow.push_back({static_cast<std::uint32_t>(i), Point{-3000.0, -2500.0 + 1000.0 * i}});
    const Point p = testing::moving_robot_position(5, i, t);
    spec.blue.push_back({static_cast<std::uint32_t>(i), Point{-p.x, -p.y}});
  }
  return make_detection_packet(spec);
}

testing::RefereeSpec referee_says(Referee::Command command, std::uint32_t counter,
                                  const std::string& them = "Them") {
  testing::RefereeSpec spec;
  spec.command = command;
  spec.command_counter = counter;
  spec.yellow = "Us";
  spec.blue = them;
  spec.blue_on_positive_half = true;  // blue's goal on +x: blue attacks -x
  return spec;
}

// A daemon with its own io_context (never run: no timers fire) and a clock the test moves.
struct InProcess {
  explicit InProcess(PredictorOptions o, TableFileLoader load_file = {}) : options(std::move(o)) {
    daemon.emplace(io, options, prediction_config(options), clock, output, std::move(load_file));
    daemon->start();
  }
  void frames(int from, int to) {
    VisionFrame frame;
    for (int f = from; f < to; ++f) {
      to_vision_frame(frame_packet(f), frame);
      clock.advance(1.0 / 60.0);
      daemon->on_event(MatchEvent::vision(frame, clock.steady_s()));
    }
  }
  void referee(const std::string& payload) {
    daemon->on_event(MatchEvent::referee(payload, clock.steady_s()));
  }
  // The game controller says `payload` ten times a second for 1.2 s: long enough for new team
  // names to take over (RefereeFollower::name_hold_s).
  void referee_held(const std::string& payload) {
    for (int i = 0; i <= 12; ++i) {
      if (i > 0) clock.advance(0.1);
      referee(payload);
    }
  }

  PredictorOptions options;
  boost::asio::io_context io;
  app::ManualClock clock;
  testing::RecordedOutput output;
  std::optional<PredictorDaemon> daemon;
};

// A table of robots like theirs, trained as the default opponent (yellow attacking +x) on
// `seconds` of play: tables of other lengths tell themselves apart by their transitions.
void train_table(const std::filesystem::path& path, double seconds = 30.0) {
  testing::MovingRobots moving;
  moving.seed = 5;
  moving.seconds = seconds;
  SamplerConfig config = sampler_config_for(ModelKind::motion);
  MotionConfig motion;
  motion.step_s = config.step_s;
  Training training(config, TransitionTable(config.grid), 0, MotionTable(motion));
  for (const SSL_WrapperPacket& packet : testing::moving_robots_packets(moving)) {
    training.add(packet);
  }
  ASSERT_TRUE(save_table(path, training.stored_table()));
}

TEST(PredictorDaemon, FollowsTheRefereesOpponentSideAndGameStateAndTheFirstGameController) {
  testing::ScratchDir dir;
  train_table(dir.path() / "t.table");
  PredictorOptions options;
  options.table = (dir.path() / "t.table").string();
  options.model.our_team = "us";
  options.quiet = true;
  InProcess predictor(options);
  ASSERT_TRUE(predictor.daemon->pipeline().table());

  // STOP, then frames; a second game controller's FORCE_START, then more frames (still
  // stopped); our game controller's NORMAL_START, then frames in running play.
  predictor.referee(testing::referee_payload(referee_says(Referee::STOP, 7)));
  predictor.frames(0, 90);
  testing::RefereeSpec other = referee_says(Referee::FORCE_START, 1);
  other.source = "another-game-controller";
  predictor.referee(testing::referee_payload(other));
  predictor.frames(90, 180);
  // Messages it cannot use: counted, never fatal.
  predictor.referee("not a referee message");
  Referee unknown;
  ASSERT_TRUE(unknown.ParseFromString(testing::referee_payload(referee_says(Referee::STOP, 7))));
  unknown.clear_command();
  // Command 99, which a newer game controller might send: field 4, varint 99.
  predictor.referee(unknown.SerializePartialAsString() + std::string("\x20\x63", 2));
  predictor.referee(testing::referee_payload(referee_says(Referee::NORMAL_START, 8)));
  predictor.frames(180, 300);

  const auto messages = predictor.output.messages();
  ASSERT_EQ(messages.size(), 300u);
  for (const auto& message : messages) {
    ASSERT_EQ(message.opponent_color(), "blue");
    const int f = static_cast<int>(std::lround((message.t_capture() - start_s) * 60.0));
    ASSERT_EQ(message.game_state(), f < 180 ? "stop" : "running") << "frame " << f;
    // Their robots, as the feed has them.
    const SSL_WrapperPacket sent = frame_packet(f);
    ASSERT_EQ(message.robots_size(), 6);
    for (const auto& robot : message.robots()) {
      const auto& blue = sent.detection().robots_blue(static_cast<int>(robot.robot_id()));
      ASSERT_NEAR(robot.position().x(), blue.x(), 0.5);
      ASSERT_NEAR(robot.position().y(), blue.y(), 0.5);
    }
  }
  const PredictionPipeline& pipeline = predictor.daemon->pipeline();
  EXPECT_EQ(pipeline.match().opponent().name, "Them");
  EXPECT_EQ(pipeline.match().opponent().color, TeamColor::blue);
  EXPECT_EQ(pipeline.sampler().attacks(), AttackDirection::negative_x);
  const RefereeCounters& counters = pipeline.match().referee().counters();
  // STOP, the other's FORCE_START, garbage, the unknown command, NORMAL_START: 2 used.
  EXPECT_EQ(counters.messages, 5u);
  EXPECT_EQ(counters.used, 2u);
  EXPECT_EQ(counters.other_source, 1u);
  EXPECT_EQ(counters.undecodable, 1u);
  EXPECT_EQ(counters.unknown_command, 1u);
  EXPECT_EQ(pipeline.sampler().counters().samples, 300u);
}

// Reads table files as load_table does, but holds each read, once hold() is called, until the
// test calls release(): a slow disk or a 40 MB table, on the test's schedule.
class HeldLoads {
 public:
  TableFileLoader loader() {
    return [this](const std::filesystem::path& path, Grid grid) {
      {
        std::unique_lock lock(mutex_);
        ++started_;
        changed_.notify_all();
        // Bounded, so that a daemon that waited for its loader would fail rather than hang.
        if (!changed_.wait_for(lock, load_timeout, [this] { return !holding_; })) {
          released_by_timeout_ = true;
        }
      }
      return load_table(path, grid);
    };
  }
  void hold() {
    const std::lock_guard lock(mutex_);
    holding_ = true;
  }
  void release() {
    {
      const std::lock_guard lock(mutex_);
      holding_ = false;
    }
    changed_.notify_all();
  }
  // Until `reads` reads have started.
  bool wait_started(int reads) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, load_timeout, [&] { return started_ >= reads; });
  }
  bool released_by_timeout() {
    const std::lock_guard lock(mutex_);
    return released_by_timeout_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool holding_ = false;
  int started_ = 0;
  bool released_by_timeout_ = false;
};

// Saves a table over `path` as the trainer does: written beside it, then renamed over it.
void replace_table(const std::filesystem::path& path, double seconds) {
  const std::filesystem::path next = path.string() + ".new";
  train_table(next, seconds);
  std::filesystem::rename(next, path);
}

std::uint64_t transitions_of(const PredictorDaemon& daemon) {
  return daemon.pipeline().table() ? daemon.pipeline().table()->table.transitions() : 0;
}

// A daemon predicting from a table of 30 s of play, which it reads through `loads`.
struct FollowingATable {
  FollowingATable() : path(dir.path() / "t.table") {
    train_table(path, 30.0);
    PredictorOptions options;
    options.table = path.string();
    options.model.our_team = "us";
    options.quiet = true;
    predictor.emplace(options, loads.loader());  // the table there at start: read unheld
  }
  // The trainer saves a longer table, and the daemon's read of it starts and is held; false if
  // it did not start.
  bool start_held_reload() {
    replace_table(path, 60.0);
    loads.hold();
    predictor->daemon->check_table();
    return loads.wait_started(2);
  }
  PredictorDaemon& daemon() { return *predictor->daemon; }

  testing::ScratchDir dir;
  std::filesystem::path path;
  HeldLoads loads;
  std::optional<InProcess> predictor;
};

TEST(PredictorDaemon, PredictsEveryFrameWhileATableLoadsAndSwitchesTablesBetweenTwoFrames) {
  FollowingATable following;
  InProcess& predictor = *following.predictor;
  const std::uint64_t old_table = transitions_of(following.daemon());
  ASSERT_GT(old_table, 0u);
  ASSERT_TRUE(following.start_held_reload());
  // Meanwhile every frame is predicted, from the old table, and the reload timer's checks
  // return at once.
  predictor.frames(0, 60);
  following.daemon().check_table();
  predictor.frames(60, 120);
  auto messages = predictor.output.messages();
  ASSERT_EQ(messages.size(), 120u);
  for (const auto& message : messages) ASSERT_EQ(message.table_transitions(), old_table);
  EXPECT_EQ(following.daemon().table_reloads(), 1u);

  // Read and prepared: not put in use behind a prediction's back, but before the next frame.
  following.loads.release();
  ASSERT_TRUE(following.daemon().wait_for_table_loader(load_timeout));
  EXPECT_EQ(transitions_of(following.daemon()), old_table);
  predictor.frames(120, 121);
  const std::uint64_t new_table = transitions_of(following.daemon());
  ASSERT_NE(new_table, old_table);
  EXPECT_EQ(following.daemon().table_reloads(), 2u);
  predictor.frames(121, 180);
  messages = predictor.output.messages();
  ASSERT_EQ(messages.size(), 180u);
  for (std::size_t i = 120; i < messages.size(); ++i) {
    ASSERT_EQ(messages[i].table_transitions(), new_table) << "frame " << i;
  }
  EXPECT_FALSE(following.loads.released_by_timeout());
}

TEST(PredictorDaemon, FramesFedWhileTheLoaderPreparesATableSwitchTablesAtOneFrame) {
  FollowingATable following;
  InProcess& predictor = *following.predictor;
  const std::uint64_t old_table = transitions_of(following.daemon());
  replace_table(following.path, 60.0);
  following.daemon().check_table();
  // Frames as fast as they come while the loader reads and prepares the table on its thread,
  // until one is predicted from the new table.
  const auto deadline = std::chrono::steady_clock::now() + load_timeout;
  int frames = 0;
  while (transitions_of(following.daemon()) == old_table &&
         std::chrono::steady_clock::now() < deadline) {
    predictor.frames(frames, frames + 1);
    ++frames;
  }
  const std::uint64_t new_table = transitions_of(following.daemon());
  ASSERT_NE(new_table, old_table);
  predictor.frames(frames, frames + 10);
  // Every frame predicted, each from one table: the old one up to a frame, the new one after.
  const auto messages = predictor.output.messages();
  ASSERT_EQ(messages.size(), static_cast<std::size_t>(frames + 10));
  std::size_t first_new = messages.size();
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const std::uint64_t used = messages[i].table_transitions();
    ASSERT_TRUE(used == old_table || used == new_table) << "frame " << i;
    if (used == new_table && first_new == messages.size()) first_new = i;
    if (i > first_new) {
      ASSERT_EQ(used, new_table) << "frame " << i;
    }
  }
  EXPECT_LT(first_new, messages.size());
}

TEST(PredictorDaemon, ABadTableFileOnTheLoaderKeepsTheTableAndTheDaemon) {
  FollowingATable following;
  const std::uint64_t table = transitions_of(following.daemon());
  ASSERT_GT(table, 0u);
  const std::string written = following.path.string() + ".new";
  {
    std::ofstream garbage(written, std::ios::binary);
    garbage << "not a table";
  }
  std::filesystem::rename(written, following.path);
  following.daemon().check_table();
  ASSERT_TRUE(following.daemon().wait_for_table_loader(load_timeout));
  following.predictor->frames(0, 30);
  EXPECT_NE(following.daemon().table_error().find(following.path.string()), std::string::npos)
      << following.daemon().table_error();
  EXPECT_EQ(transitions_of(following.daemon()), table);
  const auto messages = following.predictor->output.messages();
  ASSERT_EQ(messages.size(), 30u);
  EXPECT_EQ(messages.back().table_transitions(), table);
}

TEST(PredictorDaemon, StopsWithATableLoadUnderWay) {
  FollowingATable following;
  ASSERT_TRUE(following.start_held_reload());
  // stop() waits for the file read under way (it cannot be cut short), then joins the loader;
  // the table it read is dropped. Released from another thread, as a disk would finish it.
  std::thread disk([&] { following.loads.release(); });
  following.daemon().stop();
  disk.join();
  EXPECT_EQ(following.daemon().table_reloads(), 1u);
  following.predictor.reset();
  EXPECT_FALSE(following.loads.released_by_timeout());
}

TEST(PredictorDaemon, BaselinesPredictFromTheFirstFormationWithoutATable) {
  testing::ScratchDir dir;
  PredictorOptions options;
  options.table = (dir.path() / "never-written.bin").string();
  options.model.model = "constant-velocity";
  options.print_predictions = true;
  InProcess predictor(options);
  predictor.frames(0, 30);
  ASSERT_EQ(predictor.output.sent(), 30u);
  ASSERT_EQ(predictor.output.lines.size(), 30u);
  const auto messages = predictor.output.messages();
  EXPECT_EQ(messages.back().model(), "constant-velocity");
  EXPECT_EQ(predictor.daemon->ready_facts().at(4),
            (std::pair<std::string, std::string>{"model", "constant-velocity"}));
}

TEST(PredictorDaemon, AFeedItCannotPredictFromIsNamedOnceWithTheOptionThatFixesIt) {
  testing::ScratchDir dir;
  PredictorOptions options;
  options.table = (dir.path() / "t.bin").string();
  options.model.model = "persistence";
  InProcess predictor(options);
  // One formation every 2 s of data time, as the paper's simulation sends them.
  VisionFrame frame;
  for (int f = 0; f < 6; ++f) {
    to_vision_frame(frame_packet(f * 120), frame);
    predictor.daemon->on_event(MatchEvent::vision(frame, predictor.clock.steady_s()));
  }
  const auto problem = predictor.daemon->pipeline().feed_problem();
  ASSERT_TRUE(problem);
  EXPECT_NE(problem->find("2 s apart"), std::string::npos) << *problem;
  EXPECT_NE(problem->find("--model paper"), std::string::npos) << *problem;
}

TEST(PredictorDaemon, ATablePerOpponentIsLoadedAsTheRefereeNamesIt) {
  testing::ScratchDir dir;
  const auto tables = dir.path() / "tables";
  std::filesystem::create_directories(tables);
  train_table(tables / "alpha.bin");
  train_table(tables / "beta.bin");
  PredictorOptions options;
  options.table_dir = tables.string();
  options.model.our_team = "Us";
  options.quiet = true;
  InProcess predictor(options);
  EXPECT_FALSE(predictor.daemon->pipeline().table());  // no opponent named yet
  // The table is read on the loader's thread: settle_table_loads waits for it.
  predictor.referee(testing::referee_payload(referee_says(Referee::NORMAL_START, 1, "BETA")));
  EXPECT_EQ(predictor.daemon->table_file(), tables / "beta.bin");
  ASSERT_TRUE(predictor.daemon->settle_table_loads(load_timeout));
  EXPECT_TRUE(predictor.daemon->pipeline().table());
  predictor.referee_held(testing::referee_payload(referee_says(Referee::NORMAL_START, 1, "Alpha")));
  EXPECT_EQ(predictor.daemon->table_file(), tables / "alpha.bin");
  ASSERT_TRUE(predictor.daemon->settle_table_loads(load_timeout));
  EXPECT_TRUE(predictor.daemon->pipeline().table());
  predictor.referee_held(testing::referee_payload(referee_says(Referee::NORMAL_START, 1, "Gamma")));
  EXPECT_EQ(predictor.daemon->table_file(), tables / "gamma.bin");
  // Alpha's is dropped at once, not when the loader has looked for Gamma's.
  EXPECT_FALSE(predictor.daemon->pipeline().table());
  ASSERT_TRUE(predictor.daemon->settle_table_loads(load_timeout));
  EXPECT_FALSE(predictor.daemon->pipeline().table());  // waits for Gamma's table
}

TEST(PredictorDaemon, ATableFolderThatDoesNotExistIsRefusedAtStart) {
  PredictorOptions options;
  options.table = "/nonexistent-sslf-folder/x.bin";
  boost::asio::io_context io;
  app::ManualClock clock;
  testing::RecordedOutput output;
  try {
    PredictorDaemon daemon(io, options, prediction_config(options), clock, output);
    FAIL() << "a --table in a folder that does not exist was taken";
  } catch (const app::UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent-sslf-folder does not exist"),
              std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace ssl_formation::predictor
