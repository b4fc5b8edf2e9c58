// What the real ssl-predictor pushes to a field view: the status (the age of the last packet on
// the predictor's own clock, never negative, and the loaded table's formations) and the
// predictions (the model and each step's horizon in seconds), read off a raw WebSocket.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "raw_client.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "web_test_support.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::Readiness;
using testing::TempDir;
using web_testing::RawClient;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

// The JSON texts of `type` in the raw bytes of a WebSocket (the server's frames are unmasked, so
// each text is there whole): from {"type":"<type>" to its closing brace.
std::vector<std::string> json_messages(const std::string& bytes, const std::string& type) {
  std::vector<std::string> out;
  const std::string start = R"({"type":")" + type + '"';
  for (std::size_t at = bytes.find(start); at != std::string::npos;
       at = bytes.find(start, at + 1)) {
    int depth = 0;
    bool in_string = false;
    for (std::size_t i = at; i < bytes.size(); ++i) {
      const char c = bytes[i];
      if (in_string) {
        if (c == '\\') {
          ++i;
        } else if (c == '"') {
          in_string = false;
        }
      } else if (c == '"') {
        in_string = true;
      } else if (c == '{' || c == '[') {
        ++depth;
      } else if (c == '}' || c == ']') {
        if (--depth == 0) {
          out.push_back(bytes.substr(at, i + 1 - at));
          break;
        }
      }
    }
  }
  return out;
}

// A number (or null: empty) of `key` in a flat part of a message.
std::optional<double> number_of(const std::string& json, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex('"' + key + R"(":(-?[0-9.eE+-]+|null))")))
    return std::nullopt;
  if (match[1] == "null") return std::nullopt;
  return std::stod(match[1]);
}

std::int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

TEST(FieldViewStatus, TheRealPredictorSendsAPositiveAgeTheTablesFormationsAndHorizons) {
  TempDir dir;
  const auto table_path = dir / "table.bin";
  const web_testing::ReferenceTable reference = web_testing::reference_stored_table(3, 300);
  ASSERT_GT(reference.metadata.samples, 0u);
  ASSERT_TRUE(save_table(table_path, reference.table, reference.metadata));
  const std::string vision = testing::new_group();
  const std::string predictions = testing::new_group();
  const std::uint16_t port = web_testing::free_tcp_port();
  ChildProcess predictor(
      predictor_program,
      {"--vision-address", vision, "--prediction-address", predictions, "--table",
       table_path.string(), "--model", "paper", "--http-port", std::to_string(port), "--quiet"},
      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  ASSERT_EQ(predictor.ready_fact("table_loaded"), "1") << predictor.stderr_text();

  RawClient view(port);
  ASSERT_TRUE(view.upgrade());
  // The simulated feed: 2 s of data clock every 0.05 s of wall time, so an age taken from the
  // data's t_capture would be far off (and one from before a clock reset negative).
  ChildProcess producer(
      producer_program,
      {"--simulation", "paper", "--referee", "off", "--vision-address", vision, "--seed", "5",
       "--count", "60", "--period", "0.05", "--status-interval", "100"},
      dir.path(), "producer");
  std::string bytes;
  std::vector<std::string> live_statuses;
  for (const auto deadline = std::chrono::steady_clock::now() + 15s;
       std::chrono::steady_clock::now() < deadline;) {
    bytes += view.read_until("\x01", 100ms);  // never found: what comes in 100 ms
    live_statuses.clear();
    for (const std::string& status : json_messages(bytes, "status")) {
      if (number_of(status, "since_packet_s")) live_statuses.push_back(status);
    }
    if (live_statuses.size() >= 2 && !json_messages(bytes, "prediction").empty()) break;
  }
  ASSERT_GE(live_statuses.size(), 2u) << bytes.size() << " bytes\n" << predictor.stderr_text();

  for (const std::string& status : live_statuses) {
    SCOPED_TRACE(status);
    const double since = *number_of(status, "since_packet_s");
    EXPECT_GE(since, 0.0);
    EXPECT_LT(since, 2.0);  // packets every 0.05 s of wall time
    // The server's wall clock dates the packet and the status: the one before the other, now.
    const auto last = number_of(status, "last_packet_unix_ms");
    const auto server = number_of(status, "server_unix_ms");
    ASSERT_TRUE(last && server);
    EXPECT_LE(*last, *server);
    EXPECT_NEAR(*server - *last, since * 1000.0, 2.0);
    EXPECT_NEAR(*server, static_cast<double>(unix_ms_now()), 60'000.0);
    // The loaded table: its transitions and the formations it was trained on.
    EXPECT_NE(
        status.find(R"("table":{"loaded":true,"transitions":)" +
                    std::to_string(reference.table.transitions()) + R"(,"formations":)" +
                    std::to_string(reference.metadata.samples) + R"(,"motion_instances":null,)"),
        std::string::npos);
  }

  const std::vector<std::string> predictions_seen = json_messages(bytes, "prediction");
  ASSERT_FALSE(predictions_seen.empty());
  const std::string& prediction = predictions_seen.back();
  EXPECT_NE(prediction.find(R"("model":"paper")"), std::string::npos) << prediction;
  // Two steps ahead (the default) of 2 s each.
  EXPECT_NE(prediction.find(R"({"step":1,"horizon_s":2,)"), std::string::npos) << prediction;
  EXPECT_NE(prediction.find(R"({"step":2,"horizon_s":4,)"), std::string::npos) << prediction;
  // The paper's model states no positions or radii.
  EXPECT_EQ(prediction.find(R"("radius_90_mm")"), std::string::npos) << prediction;

  // The feed ends: the age grows on the server's clock and stays positive. The statuses are
  // read as they come until one is a second old (or the deadline passes).
  ASSERT_TRUE(producer.wait(20s).has_value());
  std::optional<double> since_later;
  std::string last_status;
  for (const auto deadline = std::chrono::steady_clock::now() + 10s;
       std::chrono::steady_clock::now() < deadline && !(since_later && *since_later >= 1.0);) {
    const std::vector<std::string> later = json_messages(view.read_until("\x01", 200ms), "status");
    if (later.empty()) continue;
    last_status = later.back();
    since_later = number_of(last_status, "since_packet_s");
  }
  ASSERT_TRUE(since_later) << last_status << predictor.stderr_text();
  EXPECT_GE(*since_later, 1.0) << last_status;
  EXPECT_LT(*since_later, 30.0) << last_status;

  predictor.signal(SIGTERM);
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();
}

// A version-3 table (the paper's counts and the motion model's) from the simulated feed, sampled
// at every frame as the motion model needs.
StoredTable motion_reference_table(std::uint64_t seed, int count) {
  simulation::SimulationConfig config;
  config.seed = seed;
  simulation::SimulatedVision vision(config);
  SamplerConfig sampler;
  sampler.sampling = Sampling::frame;
  MotionConfig motion;
  motion.step_s = sampler.step_s;
  Training training(sampler, TransitionTable(Grid(3, 2)), 0, MotionTable(motion));
  for (int i = 0; i < count; ++i) {
    for (const auto& packet : vision.next().packets) training.add(packet);
  }
  TableMetadata metadata;
  metadata.field = training.sampler().field();
  metadata.step_s = sampler.step_s;
  metadata.samples = training.samples();
  return training.stored_table(metadata);
}

TEST(FieldViewStatus, AMotionTableShowsItsInstancesAndEveryRobotItsPositionAndRadii) {
  TempDir dir;
  const auto table_path = dir / "motion.bin";
  const StoredTable table = motion_reference_table(3, 300);
  ASSERT_TRUE(table.motion != nullptr);
  ASSERT_TRUE(save_table(table_path, table));
  const std::string vision = testing::new_group();
  const std::string predictions = testing::new_group();
  const std::uint16_t port = web_testing::free_tcp_port();
  ChildProcess predictor(predictor_program,
                         {"--vision-address", vision, "--prediction-address", predictions,
                          "--table", table_path.string(), "--model", "motion", "--step", "2",
                          "--http-port", std::to_string(port), "--quiet"},
                         dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  ASSERT_EQ(predictor.ready_fact("table_loaded"), "1") << predictor.stderr_text();

  RawClient view(port);
  ASSERT_TRUE(view.upgrade());
  ChildProcess producer(
      producer_program,
      {"--simulation", "paper", "--referee", "off", "--vision-address", vision, "--seed", "5",
       "--count", "40", "--period", "0.05", "--status-interval", "100"},
      dir.path(), "producer");
  std::string bytes;
  for (const auto deadline = std::chrono::steady_clock::now() + 15s;
       std::chrono::steady_clock::now() < deadline;) {
    bytes += view.read_until("\x01", 100ms);
    if (!json_messages(bytes, "status").empty() && json_messages(bytes, "prediction").size() >= 2)
      break;
  }
  const std::vector<std::string> statuses = json_messages(bytes, "status");
  ASSERT_FALSE(statuses.empty()) << predictor.stderr_text();
  EXPECT_NE(statuses.back().find(R"(,"formations":)" + std::to_string(table.metadata.samples) +
                                 R"(,"motion_instances":)" +
                                 std::to_string(table.motion->instances()) + ","),
            std::string::npos)
      << statuses.back();

  const std::vector<std::string> seen = json_messages(bytes, "prediction");
  ASSERT_FALSE(seen.empty()) << predictor.stderr_text();
  const std::string& prediction = seen.back();
  EXPECT_NE(prediction.find(R"("model":"motion")"), std::string::npos) << prediction;
  EXPECT_NE(prediction.find(R"({"step":1,"horizon_s":2,)"), std::string::npos) << prediction;
  // Every predicted robot states its position and radii, 0 < r50 < r90.
  const std::regex robot(
      R"re("p":[^,]+,"unseen":(true|false),"position":\[(-?[0-9.e+-]+),(-?[0-9.e+-]+)\],)re"
      R"re("radius_50_mm":([0-9.e+-]+),"radius_90_mm":([0-9.e+-]+)\})re");
  std::size_t robots = 0;
  for (auto it = std::sregex_iterator(prediction.begin(), prediction.end(), robot);
       it != std::sregex_iterator(); ++it) {
    ++robots;
    const double r50 = std::stod((*it)[4]);
    const double r90 = std::stod((*it)[5]);
    EXPECT_GT(r50, 0.0) << it->str();
    EXPECT_GT(r90, r50) << it->str();
  }
  std::size_t stated = 0;
  for (std::size_t at = prediction.find(R"("unseen":)"); at != std::string::npos;
       at = prediction.find(R"("unseen":)", at + 1)) {
    ++stated;
  }
  EXPECT_GT(robots, 0u) << prediction;
  EXPECT_EQ(robots, stated) << prediction;

  ASSERT_TRUE(producer.wait(20s).has_value());
  predictor.signal(SIGTERM);
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();
}

}  // namespace
}  // namespace ssl_formation

namespace ssl_formation {
namespace {

// The first status a page gets counts the page itself, also when the periodic ones are far apart.
TEST(FieldViewStatus, APageIsCountedAmongTheViewersInTheFirstStatusItGets) {
  TempDir dir;
  const std::uint16_t port = web_testing::free_tcp_port();
  ChildProcess predictor(
      predictor_program,
      {"--vision-address", testing::new_group(), "--referee-address", testing::new_group(),
       "--prediction-address", testing::new_group(), "--table", (dir / "none.bin").string(),
       "--http-port", std::to_string(port), "--http-status-interval", "60", "--quiet"},
      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  const auto first_status = [](RawClient& client) {
    std::string bytes;
    for (const auto deadline = std::chrono::steady_clock::now() + 5s;
         std::chrono::steady_clock::now() < deadline;) {
      bytes += client.read_until("\x01", 100ms);
      const std::vector<std::string> statuses = json_messages(bytes, "status");
      if (!statuses.empty()) return statuses.front();
    }
    return std::string();
  };
  RawClient first(port);
  ASSERT_TRUE(first.upgrade());
  const std::string seen_by_first = first_status(first);
  EXPECT_EQ(number_of(seen_by_first, "clients"), 1.0) << seen_by_first;
  RawClient second(port);
  ASSERT_TRUE(second.upgrade());
  const std::string seen_by_second = first_status(second);
  EXPECT_EQ(number_of(seen_by_second, "clients"), 2.0) << seen_by_second;
  // The first page hears of the second at once too.
  const std::string later = first_status(first);
  EXPECT_EQ(number_of(later, "clients"), 2.0) << later;
  predictor.signal(SIGTERM);
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();
}

}  // namespace
}  // namespace ssl_formation
