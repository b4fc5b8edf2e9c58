// scripts/ssl-prediction-client.py, the Python reader a team can start from: joined to the live
// predictor's group on loopback, it decodes every message the daemon sends, with the project's
// .proto, and its CSV is ssl-predictor --from-log's for the same log, line for line.

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <fstream>
#include <set>
#include <span>

#include "child_process.hpp"
#include "formation_prediction.pb.h"
#include "moving_robots.hpp"
#include "prediction_rows.hpp"
#include "ssl_formation/net/multicast.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::read_text;
using testing::Readiness;
using testing::split;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;
const std::filesystem::path client_script =
    std::filesystem::path(SSLF_SCRIPTS_DIR) / "ssl-prediction-client.py";
// The schema as the first release had it (the paper's model only): a reader built against it
// must keep decoding what today's predictor sends, skipping the fields appended since.
constexpr const char* first_release_proto = R"(syntax = "proto2";
package ssl_formation.proto;
message GridCell { required uint32 x = 1; required uint32 y = 2; }
message FieldPoint { required float x = 1; required float y = 2; }
message CurrentRobot {
  required uint32 robot_id = 1; required uint32 state_index = 2;
  required GridCell position_cell = 3; required GridCell previous_cell = 4;
}
message PredictedRobot {
  required uint32 robot_id = 1; required uint32 state_index = 2;
  required GridCell position_cell = 3; required GridCell previous_cell = 4;
  required FieldPoint cell_centre = 5; required double probability = 6; required bool unseen = 7;
}
message PredictedStep {
  required uint32 step = 1; required GridCell centroid_cell = 2;
  required double centroid_probability = 3; required bool centroid_unseen = 4;
  repeated PredictedRobot robots = 5; required double formation_probability = 6;
  required double confidence = 7;
}
message FormationPrediction {
  required uint32 frame_number = 1; required double t_capture = 2;
  required GridCell centroid_cell = 3; repeated CurrentRobot robots = 4;
  repeated PredictedStep steps = 5;
}
)";

// Debian's Python, where Debian's python3-protobuf is (a python3 earlier on the PATH, such as a
// pyenv's, may not have it).
const std::filesystem::path python = "/usr/bin/python3";

TEST(PredictionClient, DecodesEveryMessageOfTheLivePredictorAndWritesTheFromLogCsv) {
  TempDir dir;
  const auto train_log = dir / "train.log";
  const auto test_log = dir / "test.log";
  ASSERT_EQ(testing::write_vision_log(train_log,
                                      testing::moving_robots_packets(
                                          {.seed = 1, .seconds = 30.0, .start_time_s = 100.0})),
            "");
  ASSERT_EQ(
      testing::write_vision_log(test_log, testing::moving_robots_packets(
                                              {.seed = 2, .seconds = 5.0, .start_time_s = 1000.0})),
      "");
  const auto table = dir / "table.bin";
  const auto trained = testing::run_to_end(
      trainer_program, {"--from-log", train_log.string(), "--table", table.string()}, dir.path(),
      "train", 60s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  const auto offline_csv = dir / "from-log.csv";
  const auto offline =
      testing::run_to_end(predictor_program,
                          {"--from-log", test_log.string(), "--table", table.string(), "--horizon",
                           "3", "--output", offline_csv.string()},
                          dir.path(), "from-log", 60s);
  ASSERT_EQ(offline.exit_code, 0) << offline.err;
  std::vector<std::string> lines = split(read_text(offline_csv), '\n');
  ASSERT_GT(lines.size(), 1u);
  std::set<std::string> instants;
  for (std::size_t i = 1; i < lines.size(); ++i) instants.insert(split(lines[i], ',').front());
  ASSERT_EQ(instants.size(), 300u);  // 5 s at 60 Hz

  // The client first, on the test's own group, then the daemon, then the log replayed to it.
  const std::string vision = new_group();
  const std::string predictions = new_group();
  const auto client_csv = dir / "client.csv";
  ChildProcess client(
      python,
      {client_script.string(), "--group", predictions, "--interface", "127.0.0.1", "--csv",
       client_csv.string(), "--count", std::to_string(instants.size()), "--duration", "60"},
      dir.path(), "client");
  ASSERT_TRUE(client.wait_for_stderr("listening on " + predictions, 20s)) << client.stderr_text();
  // And one that prints, as a team would watch it.
  ChildProcess printer(python,
                       {client_script.string(), "--group", predictions, "--count",
                        std::to_string(instants.size()), "--duration", "60"},
                       dir.path(), "printer");
  ASSERT_TRUE(printer.wait_for_stderr("listening on", 20s)) << printer.stderr_text();
  // And one built against the first release's schema.
  std::filesystem::create_directories(dir / "old");
  {
    std::ofstream old_proto(dir / "old" / "formation_prediction.proto");
    old_proto << first_release_proto;
  }
  ChildProcess old_reader(
      python,
      {client_script.string(), "--group", predictions, "--proto", (dir / "old").string(), "--count",
       std::to_string(instants.size()), "--duration", "60"},
      dir.path(), "old-reader");
  ASSERT_TRUE(old_reader.wait_for_stderr("listening on", 20s)) << old_reader.stderr_text();
  ChildProcess daemon(predictor_program,
                      {"--vision-address", vision, "--prediction-address", predictions, "--table",
                       table.string(), "--horizon", "3", "--quiet"},
                      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
  const auto replayed = testing::run_to_end(
      producer_program, {"--replay", test_log.string(), "--vision-address", vision, "--speed", "5"},
      dir.path(), "replay", 30s);
  ASSERT_EQ(replayed.exit_code, 0) << replayed.err;

  // It stops by itself after as many messages as the daemon sent predictions.
  ASSERT_EQ(client.wait(30s), 0) << client.stderr_text();
  EXPECT_NE(client.stderr_text().find("300 predictions received, 0 datagrams that did not decode"),
            std::string::npos)
      << client.stderr_text();
  const std::vector<std::string> written = split(read_text(client_csv), '\n');
  ASSERT_EQ(written.size(), lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) ASSERT_EQ(written[i], lines[i]) << "line " << i;

  // A line per message and step: the instant, the horizon, every robot's position, 90% radius
  // and probability.
  ASSERT_EQ(printer.wait(30s), 0) << printer.stderr_text();
  const std::vector<std::string> printed = split(printer.stdout_text(), '\n');
  EXPECT_EQ(printed.size(), 3 * instants.size());
  const std::string& first = printed.front();
  EXPECT_NE(first.find("t=1000."), std::string::npos) << first;
  EXPECT_NE(first.find(" +0.5s "), std::string::npos) << first;
  EXPECT_NE(first.find(" r90="), std::string::npos) << first;
  EXPECT_NE(printed[2].find(" +1.5s "), std::string::npos) << printed[2];

  // The old reader decodes every message too; it knows no positions or radii, only cells.
  ASSERT_EQ(old_reader.wait(30s), 0) << old_reader.stderr_text();
  EXPECT_NE(
      old_reader.stderr_text().find("300 predictions received, 0 datagrams that did not decode"),
      std::string::npos)
      << old_reader.stderr_text();
  const std::string old_printed = old_reader.stdout_text();
  EXPECT_NE(old_printed.find(" step 1 "), std::string::npos) << old_printed.substr(0, 500);
  EXPECT_EQ(old_printed.find(" r90="), std::string::npos) << old_printed.substr(0, 500);

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(5s), 0) << daemon.stderr_text();
}

TEST(PredictionClient, SkipsWhatIsNotAPredictionAndStopsOnSigterm) {
  TempDir dir;
  const std::string group = new_group();
  ChildProcess client(python, {client_script.string(), "--group", group, "--count", "2"},
                      dir.path(), "client");
  ASSERT_TRUE(client.wait_for_stderr("listening on " + group, 20s)) << client.stderr_text();
  // Text, nothing, a truncated message: none is a prediction, and none uses up --count. A
  // prediction after them says, once printed, that the client has read them all (one sender on
  // loopback: they arrive in order).
  boost::asio::io_context io;
  net::MulticastSender sender(io, net::parse_multicast_endpoint(group).value());
  sender.open();
  proto::FormationPrediction whole;
  whole.set_frame_number(7);
  whole.set_t_capture(1.5);
  whole.mutable_centroid_cell()->set_x(1);
  whole.mutable_centroid_cell()->set_y(0);
  proto::PredictedStep& step = *whole.add_steps();
  step.set_step(1);
  step.mutable_centroid_cell()->set_x(1);
  step.mutable_centroid_cell()->set_y(0);
  step.set_centroid_probability(1.0);
  step.set_centroid_unseen(false);
  step.set_formation_probability(0.25);
  step.set_confidence(0.5);
  const std::string bytes = whole.SerializeAsString();
  const std::string hello = "hello world";
  for (const std::string& junk : {hello, std::string(), bytes.substr(0, 3)}) {
    ASSERT_TRUE(sender.send(std::as_bytes(std::span(junk.data(), junk.size()))));
  }
  ASSERT_TRUE(sender.send(std::as_bytes(std::span(bytes.data(), bytes.size()))));
  ASSERT_TRUE(client.wait_for_stdout("frame=7", 20s)) << client.stderr_text();
  EXPECT_TRUE(client.running()) << client.stderr_text();  // --count 2: one prediction so far
  client.signal(SIGTERM);
  ASSERT_EQ(client.wait(10s), 0) << client.stderr_text();
  EXPECT_NE(client.stderr_text().find("1 predictions received, 3 datagrams that did not decode"),
            std::string::npos)
      << client.stderr_text();
  // The one prediction, on one line.
  const std::string printed = client.stdout_text();
  EXPECT_EQ(std::count(printed.begin(), printed.end(), '\n'), 1) << printed;
  EXPECT_NE(printed.find("t=1.50 frame=7 step 1 p(formation)=0.250"), std::string::npos) << printed;
}

TEST(PredictionClient, SaysWhatIsWrongWithItsOptionsAndStopsWhenTold) {
  TempDir dir;
  // Nothing sent: it listens for a second and stops, having received nothing.
  const auto quiet = testing::run_to_end(
      python, {client_script.string(), "--group", new_group(), "--duration", "1"}, dir.path(),
      "quiet", 30s);
  EXPECT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_NE(quiet.err.find("0 predictions received"), std::string::npos) << quiet.err;
  const auto bad_group = testing::run_to_end(
      python, {client_script.string(), "--group", "10.1.2.3:10040", "--duration", "1"}, dir.path(),
      "bad-group", 30s);
  EXPECT_NE(bad_group.exit_code, 0);
  EXPECT_NE(bad_group.err.find("not a multicast group"), std::string::npos) << bad_group.err;
  const auto bad_proto = testing::run_to_end(
      python, {client_script.string(), "--proto", (dir / "nowhere").string(), "--duration", "1"},
      dir.path(), "bad-proto", 30s);
  EXPECT_NE(bad_proto.exit_code, 0);
  EXPECT_NE(bad_proto.err.find("formation_prediction.proto"), std::string::npos) << bad_proto.err;
}

}  // namespace
}  // namespace ssl_formation
