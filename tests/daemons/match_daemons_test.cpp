// The daemons on a live referee feed, as processes on loopback: ssl-predictor finds the opponent
// by our team's name and its side by blue_team_on_positive_half, says the game state in every
// prediction, keeps following the first game controller when a second one speaks up, and shrugs
// off referee messages it cannot use and referee packets sent to its vision port.

#include <gtest/gtest.h>
#include <signal.h>

#include <thread>

#include "child_process.hpp"
#include "match_logs.hpp"
#include "moving_robots.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/files/table_file.hpp"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

constexpr double start_s = 500.0;  // t_capture of the live feed's first frame

// Frame `f` of the live feed: our team yellow (standing in a row), theirs blue, moving as
// moving_robots.hpp's robots turned about the centre (they attack -x).
std::string frame_bytes(int f) {
  const double t = f / 60.0;
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(f);
  spec.t_capture = start_s + t;
  for (int i = 0; i < 6; ++i) {
    spec.yellow.push_back({static_cast<std::uint32_t>(i), Point{-3000.0, -2500.0 + 1000.0 * i}});
    const Point p = testing::moving_robot_position(5, i, t);
    spec.blue.push_back({static_cast<std::uint32_t>(i), Point{-p.x, -p.y}});
  }
  return make_detection_packet(spec).SerializeAsString();
}

// Frames `from` to `to` - 1 to the vision group, a millisecond apart.
void send_frames(const std::string& vision, int from, int to) {
  for (int f = from; f < to; ++f) {
    ASSERT_TRUE(testing::send_to_group(vision, frame_bytes(f)));
    std::this_thread::sleep_for(1ms);
  }
}

testing::RefereeSpec referee_says(Referee::Command command, std::uint32_t counter) {
  testing::RefereeSpec spec;
  spec.command = command;
  spec.command_counter = counter;
  spec.yellow = "Us";
  spec.blue = "Them";
  spec.blue_on_positive_half = true;  // blue's goal on +x: blue attacks -x
  return spec;
}

// Sends a referee message and gives the daemon time to take it before the next frame (the two
// groups are two sockets: nothing orders one's datagrams against the other's).
void send_referee(const std::string& group, const std::string& bytes) {
  ASSERT_TRUE(testing::send_to_group(group, bytes));
  std::this_thread::sleep_for(200ms);
}

TEST(MatchDaemons, PredictorFollowsTheRefereesOpponentSideAndGameStateAndTheFirstGameController) {
  TempDir dir;
  // A table of robots like theirs, trained as the default opponent (yellow attacking +x).
  testing::MovingRobots moving;
  moving.seed = 5;
  moving.seconds = 30.0;
  ASSERT_EQ(testing::write_vision_log(dir / "train.log", testing::moving_robots_packets(moving)),
            "");
  const auto trained =
      testing::run_to_end(trainer_program,
                          {"--from-log", (dir / "train.log").string(), "--table",
                           (dir / "t.table").string()},
                          dir.path(), "train", 60s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;

  const std::string vision = new_group();
  const std::string referee = new_group();
  const std::string predictions = new_group();
  ChildProcess daemon(predictor_program,
                      {"--vision-address", vision, "--referee-address", referee,
                       "--prediction-address", predictions, "--table", (dir / "t.table").string(),
                       "--our-team", "us", "--quiet", "--status-interval", "0.2"},
                      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
  EXPECT_EQ(daemon.ready_fact("referee"), referee);
  testing::PredictionListener listener(predictions);

  // STOP, then frames; a second game controller's FORCE_START, then more frames (still
  // stopped); our game controller's NORMAL_START, then frames in running play.
  send_referee(referee, testing::referee_payload(referee_says(Referee::STOP, 7)));
  send_frames(vision, 0, 90);
  testing::RefereeSpec other = referee_says(Referee::FORCE_START, 1);
  other.source = "another-game-controller";
  send_referee(referee, testing::referee_payload(other));
  send_frames(vision, 90, 180);
  // Messages it cannot use, on both ports: counted, never fatal.
  send_referee(referee, "not a referee message");
  Referee unknown;
  ASSERT_TRUE(unknown.ParseFromString(testing::referee_payload(referee_says(Referee::STOP, 7))));
  unknown.clear_command();
  // Command 99, which a newer game controller might send: field 4, varint 99.
  send_referee(referee, unknown.SerializePartialAsString() + std::string("\x20\x63", 2));
  ASSERT_TRUE(testing::send_to_group(vision,
                                     testing::referee_payload(referee_says(Referee::HALT, 9))));
  send_referee(referee, testing::referee_payload(referee_says(Referee::NORMAL_START, 8)));
  send_frames(vision, 180, 300);

  const auto messages = listener.drain(5s);
  ASSERT_TRUE(messages.has_value());
  ASSERT_GT(messages->size(), 200u) << daemon.stderr_text();
  std::size_t stopped = 0;
  std::size_t running = 0;
  for (const auto& message : *messages) {
    ASSERT_EQ(message.opponent_color(), "blue");
    const int f = static_cast<int>(std::lround((message.t_capture() - start_s) * 60.0));
    ASSERT_EQ(message.game_state(), f < 180 ? "stop" : "running") << "frame " << f;
    (f < 180 ? stopped : running) += 1;
    // Their robots, as the feed has them.
    const std::string bytes = frame_bytes(f);
    SSL_WrapperPacket sent;
    ASSERT_TRUE(sent.ParseFromString(bytes));
    ASSERT_EQ(message.robots_size(), 6);
    for (const auto& robot : message.robots()) {
      const auto& blue = sent.detection().robots_blue(static_cast<int>(robot.robot_id()));
      ASSERT_NEAR(robot.position().x(), blue.x(), 0.5);
      ASSERT_NEAR(robot.position().y(), blue.y(), 0.5);
    }
  }
  EXPECT_GT(stopped, 100u);
  EXPECT_GT(running, 60u);
  EXPECT_TRUE(daemon.wait_for_stderr("opponent: 'Them' blue (referee), attacks -x (referee)", 2s))
      << daemon.stderr_text();
  EXPECT_TRUE(daemon.wait_for_stderr("a second game controller", 2s)) << daemon.stderr_text();
  EXPECT_TRUE(daemon.wait_for_stderr("a command this program does not know", 2s))
      << daemon.stderr_text();
  EXPECT_TRUE(daemon.wait_for_stderr("not referee messages", 2s)) << daemon.stderr_text();

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(5s), 0) << daemon.stderr_text();
  EXPECT_NE(daemon.stderr_text().find("attacks=-x (referee) opponent=blue (referee) game=running"),
            std::string::npos)
      << daemon.stderr_text();
  const testing::Status status = testing::last_status(daemon.stderr_text());
  // STOP, the other's FORCE_START, garbage, the unknown command, NORMAL_START: 2 used.
  EXPECT_EQ(status.at("referee_messages"), 5u) << daemon.stderr_text();
  EXPECT_EQ(status.at("referee_unused"), 3u) << daemon.stderr_text();
  // The referee packet on the vision port decodes as a wrapper packet without detection or
  // geometry (protobuf skips fields of the wrong wire type): counted as such, nothing more.
  EXPECT_EQ(status.at("empty_packets"), 1u) << daemon.stderr_text();
  EXPECT_EQ(status.at("formations"), 300u) << daemon.stderr_text();
}

// The referee names the opponent "Alpha" for 2 s of play, then "Beta" (the next match).
testing::RefereeSpec match_against(const std::string& them) {
  testing::RefereeSpec spec = referee_says(Referee::NORMAL_START, 1);
  spec.blue = them;
  return spec;
}

bool wait_for_file(const std::filesystem::path& path, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (std::filesystem::exists(path)) return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

TEST(MatchDaemons, ATablePerOpponentTheTrainerSwitchesAndThePredictorFollows) {
  TempDir dir;
  const auto tables = dir / "tables";
  const std::string vision = new_group();
  const std::string referee = new_group();
  ChildProcess trainer(trainer_program,
                       {"--vision-address", vision, "--referee-address", referee, "--table-dir",
                        tables.string(), "--our-team", "Us", "--flush-interval", "1000",
                        "--status-interval", "0.2"},
                       dir.path(), "trainer", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  send_referee(referee, testing::referee_payload(match_against("Alpha")));
  send_frames(vision, 0, 150);
  // Alpha's table is written as Beta comes, while the trainer runs on.
  send_referee(referee, testing::referee_payload(match_against("Beta")));
  ASSERT_TRUE(wait_for_file(tables / "alpha.bin", 5s)) << trainer.stderr_text();
  send_frames(vision, 1000, 1150);  // later on the data clock: a new stream
  ASSERT_TRUE(testing::wait_for_status_where(
      trainer, [](const testing::Status& s) { return s.contains("packets") && s.at("packets") >= 300; },
      10s))
      << trainer.stderr_text();
  trainer.signal(SIGTERM);
  ASSERT_EQ(trainer.wait(5s), 0) << trainer.stderr_text();
  const auto alpha = load_table(tables / "alpha.bin", Grid(3, 2));
  const auto beta = load_table(tables / "beta.bin", Grid(3, 2));
  ASSERT_TRUE(alpha) << alpha.error().message;
  ASSERT_TRUE(beta) << beta.error().message;
  EXPECT_GT(alpha->table.transitions(), 100u);
  EXPECT_GT(beta->table.transitions(), 100u);
  // About as many frames each: neither table took the other's.
  EXPECT_LT(alpha->metadata.samples, 160u);
  EXPECT_LT(beta->metadata.samples, 160u);
  // Nothing was learned before the referee named anyone: no table for an unnamed team.
  EXPECT_FALSE(std::filesystem::exists(tables / "unknown.bin"));

  // The predictor loads the table of the opponent the referee names, and switches with it.
  const std::string predictions = new_group();
  ChildProcess predictor(predictor_program,
                         {"--vision-address", vision, "--referee-address", referee,
                          "--prediction-address", predictions, "--table-dir", tables.string(),
                          "--our-team", "Us", "--quiet"},
                         dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  EXPECT_EQ(predictor.ready_fact("table_loaded"), "0");  // no opponent named yet
  send_referee(referee, testing::referee_payload(match_against("BETA")));
  EXPECT_TRUE(predictor.wait_for_stderr("loaded table " + (tables / "beta.bin").string(), 5s))
      << predictor.stderr_text();
  send_referee(referee, testing::referee_payload(match_against("Alpha")));
  EXPECT_TRUE(predictor.wait_for_stderr("loaded table " + (tables / "alpha.bin").string(), 5s))
      << predictor.stderr_text();
  predictor.signal(SIGTERM);
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();
}

}  // namespace
}  // namespace ssl_formation
