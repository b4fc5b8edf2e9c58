// The three daemons started side by side with their defaults predict: no model, feed, table,
// step or sampling option, only the ready files (and, as in every test, groups of the test's own
// for the four feeds, so that a game controller or vision feed on this machine stays out). And a
// log written with the producer's defaults trains and predicts offline with theirs.

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "child_process.hpp"
#include "feed_groups.hpp"
#include "prediction_rows.hpp"

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

}  // namespace
}  // namespace ssl_formation
