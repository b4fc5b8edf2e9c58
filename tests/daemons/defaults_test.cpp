// The three daemons started side by side with their defaults predict: no model, feed, table,
// step or sampling option, only the ready files (and, as in every test, groups of the test's own
// for the four feeds, so that a game controller or vision feed on this machine stays out). And a
// log written with the producer's defaults trains and predicts offline with theirs.

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "child_process.hpp"
#include "feed_groups.hpp"
#include "prediction_rows.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

std::size_t lines_in(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

TEST(Defaults, TheThreeDaemonsSideBySidePredictWithinTenSecondsOfTheFirstPacket) {
  TempDir dir;
  const testing::FeedGroups groups;  // shared: the three talk on the same four groups
  ChildProcess trainer(trainer_program, groups.complete(trainer_program, {}), dir.path(), "trainer",
                       Readiness::ready_file);
  ChildProcess predictor(predictor_program, groups.complete(predictor_program, {}), dir.path(),
                         "predictor", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  EXPECT_EQ(predictor.ready_fact("model"), "motion");
  ChildProcess producer(producer_program, groups.complete(producer_program, {}), dir.path(),
                        "producer");
  const auto first_packet = std::chrono::steady_clock::now();
  bool predicted = false;
  while (std::chrono::steady_clock::now() - first_packet < 10s) {
    if (lines_in(predictor.stdout_text()) > 0) {
      predicted = true;
      break;
    }
    std::this_thread::sleep_for(50ms);  // polling the output file, not ordering events
  }
  ASSERT_TRUE(predicted) << "trainer:\n"
                         << trainer.stderr_text() << "\npredictor:\n"
                         << predictor.stderr_text();
  // Predictions in millimetres, from the motion model, on the simulated match.
  const std::string out = predictor.stdout_text();
  // One short line a second by default (the full lines are --print-predictions').
  EXPECT_NE(out.find("+0.5s r90 "), std::string::npos) << out.substr(0, 400);
  for (const std::string& line : testing::split(out, '\n')) EXPECT_LT(line.size(), 200u) << line;
  // Nothing had to be explained: the feed suits the model.
  EXPECT_EQ(predictor.stderr_text().find("needs frames"), std::string::npos);
  EXPECT_EQ(trainer.stderr_text().find("needs frames"), std::string::npos);
  producer.signal(SIGTERM);
  trainer.signal(SIGTERM);
  predictor.signal(SIGTERM);
  EXPECT_EQ(producer.wait(5s), 0);
  EXPECT_EQ(trainer.wait(5s), 0) << trainer.stderr_text();
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();
}

TEST(Defaults, ALogWrittenWithTheProducersDefaultsTrainsAndPredictsOffline) {
  TempDir dir;
  const auto log = (dir / "match.log").string();
  const auto written = testing::run_to_end(
      producer_program, {"--write-log", log, "--duration", "30"}, dir.path(), "write");
  ASSERT_EQ(written.exit_code, 0) << written.err;
  const auto trained =
      testing::run_to_end(trainer_program, {"--from-log", log}, dir.path(), "train");
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  ASSERT_TRUE(std::filesystem::exists(dir / "formation-table.bin"));  // the default, in its folder
  EXPECT_EQ(trained.err.find(" 0 formations"), std::string::npos) << trained.err;
  const auto predicted = testing::run_to_end(
      predictor_program, {"--from-log", log, "--output", (dir / "p.csv").string()}, dir.path(),
      "predict");
  ASSERT_EQ(predicted.exit_code, 0) << predicted.err;
  std::ifstream csv(dir / "p.csv");
  std::stringstream text;
  text << csv.rdbuf();
  // One row per robot and step: 30 s at 60 frames, 11 robots, 2 steps, and the header.
  EXPECT_GT(lines_in(text.str()), 30u * 60u * 11u) << predicted.err;
}

TEST(Defaults, ARunThatCouldReadNoLogWritesNoTable) {
  TempDir dir;
  {
    std::ofstream text(dir / "notes.txt");
    text << "root:x:0:0:root:/root:/bin/bash\n";
  }
  const auto trained = testing::run_to_end(
      trainer_program, {"--from-log", (dir / "notes.txt").string()}, dir.path(), "train");
  EXPECT_EQ(trained.exit_code, 1) << trained.err;
  EXPECT_NE(trained.err.find("not an SSL log file"), std::string::npos) << trained.err;
  EXPECT_NE(trained.err.find("no table written"), std::string::npos) << trained.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "formation-table.bin"));
}

TEST(Defaults, AFeedTheModelCannotLearnFromIsNamedWithTheOptionThatFixesIt) {
  TempDir dir;
  const testing::FeedGroups groups;
  ChildProcess trainer(trainer_program, groups.complete(trainer_program, {}), dir.path(), "trainer",
                       Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  // The paper's simulated opponent: one formation every 2 s of data time, ten a second.
  ChildProcess producer(
      producer_program,
      groups.complete(producer_program, {"--simulation", "paper", "--period", "0.1"}), dir.path(),
      "producer");
  EXPECT_TRUE(trainer.wait_for_stderr("--model paper", 10s)) << trainer.stderr_text();
  const std::string err = trainer.stderr_text();
  EXPECT_NE(err.find("2 s apart"), std::string::npos) << err;
  // Said once.
  const auto first = err.find("needs frames");
  EXPECT_EQ(err.find("needs frames", first + 1), std::string::npos) << err;
}

// The producer's default feed is the demo's: four cameras, each frame's robots split among them.
TEST(Defaults, TheProducerSendsFourCamerasAsTheDemoDoes) {
  TempDir dir;
  const auto run = testing::run_to_end(producer_program, {"-o", "d.log", "--duration", "1"},
                                       dir.path(), "producer");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const LogVisionPackets log = read_vision_log(dir / "d.log").value();
  std::set<std::uint32_t> cameras;
  for (const auto& packet : log.packets) {
    if (packet.has_detection()) cameras.insert(packet.detection().camera_id());
  }
  EXPECT_EQ(cameras, (std::set<std::uint32_t>{0, 1, 2, 3}));
}

// The demo's match opens in running play: a newcomer's first half minute is play, not a HALT.
TEST(Defaults, TheDemosMatchOpensInRunningPlay) {
  TempDir dir;
  std::ifstream demo(std::filesystem::path(SSLF_SCRIPTS_DIR) / "demo.sh");
  std::string seed;
  const std::regex seed_line(R"(^seed=(\d+)$)");
  for (std::string line; std::getline(demo, line);) {
    std::smatch match;
    if (std::regex_match(line, match, seed_line)) seed = match[1];
  }
  ASSERT_FALSE(seed.empty()) << "scripts/demo.sh sets no seed=";
  const auto run =
      testing::run_to_end(producer_program, {"-o", "demo.log", "--duration", "30", "--seed", seed},
                          dir.path(), "producer");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  auto reader = LogReader::open(dir / "demo.log");
  ASSERT_TRUE(reader) << reader.error().message;
  LogMessage message;
  std::int64_t first_ns = -1;
  int running_from_3s = 0;
  while (reader->next(message)) {
    if (message.type != static_cast<std::int32_t>(LogMessageType::referee)) continue;
    Referee referee;
    ASSERT_TRUE(referee.ParseFromString(message.payload));
    if (first_ns < 0) first_ns = message.receive_time_ns;
    // The kick-off is prepared in the first 2 s; from the third second on, play runs.
    if (message.receive_time_ns - first_ns < 3'000'000'000) continue;
    EXPECT_EQ(referee.command(), Referee::NORMAL_START)
        << "at " << (message.receive_time_ns - first_ns) / 1e9 << " s";
    if (referee.command() != Referee::NORMAL_START) break;
    ++running_from_3s;
  }
  EXPECT_GT(running_from_3s, 60 * 26);  // every frame's message from 3 s to the end
}

}  // namespace
}  // namespace ssl_formation
