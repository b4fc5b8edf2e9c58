// The status lines of the three daemons as a team reads them in a terminal during a match: every
// one under 200 characters, no counter at zero on any, the figures that matter on each, and a
// problem on every line from the one it happened on.

#include "status_lines.hpp"

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <regex>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "feed_groups.hpp"
#include "pipeline_support.hpp"
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

// The status lines in a program's log: periodic ("status: "), at the end ("done: ",
// "stopped: "), what did not fit at the end ("status, more: "), and the predictor's field view.
std::vector<std::string> status_lines(const std::string& log) {
  static const std::regex status(R"(: (status|done|stopped|failed|field view)(, more)?: )");
  std::vector<std::string> out;
  for (const std::string& line : testing::split(log, '\n')) {
    if (std::regex_search(line, status)) out.push_back(line);
  }
  return out;
}

bool has(const std::string& line, const std::string& text) {
  return line.find(text) != std::string::npos;
}

// Under 200 characters, and no counter at zero.
void expect_calm(const std::vector<std::string>& lines, const std::string& program) {
  static const std::regex zero(R"(=0( |$))");
  for (const std::string& line : lines) {
    EXPECT_LT(line.size(), 200u) << program << ": " << line;
    EXPECT_FALSE(std::regex_search(line, zero)) << program << ": " << line;
  }
}

TEST(StatusLines, AreShortLeaveZerosOutShowTheFiguresAndEveryProblem) {
  TempDir dir;
  const testing::FeedGroups groups;  // the three on the same four groups
  const std::vector<std::string> often{"--status-interval", "0.2"};
  ChildProcess trainer(trainer_program, groups.complete(trainer_program, often), dir.path(),
                       "trainer", Readiness::ready_file);
  ChildProcess predictor(predictor_program, groups.complete(predictor_program, often), dir.path(),
                         "predictor", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  // Status lines before the first packet.
  ASSERT_TRUE(trainer.wait_for_stderr("status: no vision packets yet", 10s))
      << trainer.stderr_text();
  ASSERT_TRUE(predictor.wait_for_stderr("status: no vision packets yet", 10s))
      << predictor.stderr_text();

  // A simulated match with its game controller: a second of it before the learned table is
  // saved and taken up, then predicted and scored.
  std::vector<std::string> match{"--duration", "8", "--status-interval", "0.2"};
  ChildProcess producer(producer_program, groups.complete(producer_program, match), dir.path(),
                        "producer");
  ASSERT_TRUE(predictor.wait_for_stderr("live_error=", 30s)) << predictor.stderr_text();
  // A datagram that is no SSL-Vision packet: a problem from then on, on every line.
  ASSERT_TRUE(testing::send_to_group(groups.vision, "not a vision packet"));
  ASSERT_TRUE(trainer.wait_for_stderr("problems: parse_errors=1", 10s)) << trainer.stderr_text();
  ASSERT_TRUE(predictor.wait_for_stderr("problems: parse_errors=1", 10s))
      << predictor.stderr_text();
  EXPECT_EQ(producer.wait(30s), 0) << producer.stderr_text();
  trainer.signal(SIGTERM);
  predictor.signal(SIGTERM);
  EXPECT_EQ(trainer.wait(10s), 0) << trainer.stderr_text();
  EXPECT_EQ(predictor.wait(10s), 0) << predictor.stderr_text();

  const std::vector<std::string> producer_lines = status_lines(producer.stderr_text());
  const std::vector<std::string> trainer_lines = status_lines(trainer.stderr_text());
  const std::vector<std::string> predictor_lines = status_lines(predictor.stderr_text());
  // Lines at every stage: before the first packet, while learning and predicting, at the end.
  ASSERT_GE(producer_lines.size(), 10u) << producer.stderr_text();
  ASSERT_GE(trainer_lines.size(), 10u) << trainer.stderr_text();
  ASSERT_GE(predictor_lines.size(), 10u) << predictor.stderr_text();
  expect_calm(producer_lines, "ssl-producer");
  expect_calm(trainer_lines, "ssl-trainer");
  expect_calm(predictor_lines, "ssl-predictor");

  // The producer: the match's frames, the packets sent, the game its controller runs.
  for (const std::string& line : producer_lines) {
    for (const char* figure : {"frames=", "packets=", "game=", "attacks=", "score="}) {
      EXPECT_TRUE(has(line, figure)) << figure << " missing from " << line;
    }
  }
  ASSERT_TRUE(has(producer_lines.back(), "done: ")) << producer_lines.back();

  // The daemons: the packets (or that none came yet), the game, whom they predict and which way
  // it attacks; the problem on every line from the first that has it.
  for (const auto* lines : {&trainer_lines, &predictor_lines}) {
    bool problem_seen = false;
    for (const std::string& line : *lines) {
      if (has(line, "field view: ") || has(line, ", more: ")) continue;
      EXPECT_TRUE(has(line, "packets=") || has(line, "no vision packets yet")) << line;
      for (const char* figure : {"game=", "opponent=", "attacks="}) {
        EXPECT_TRUE(has(line, figure)) << figure << " missing from " << line;
      }
      problem_seen = problem_seen || has(line, "parse_errors=1");
      if (problem_seen) {
        EXPECT_TRUE(has(line, "| problems: parse_errors=1")) << line;
      }
    }
    EXPECT_TRUE(problem_seen);
  }
  // What was learned and predicted, on the last periodic line of each.
  const auto last_periodic = [](const std::vector<std::string>& lines) {
    std::string last;
    for (const std::string& line : lines) {
      if (has(line, " status: ")) last = line;
    }
    return last;
  };
  const std::string trained = last_periodic(trainer_lines);
  for (const char* figure : {"packets=", "formations=", "motion_instances="}) {
    EXPECT_TRUE(has(trained, figure)) << figure << " missing from " << trained;
  }
  const std::string predicted = last_periodic(predictor_lines);
  for (const char* figure : {"packets=", "predictions=", "live_error="}) {
    EXPECT_TRUE(has(predicted, figure)) << figure << " missing from " << predicted;
  }
  // And every counter at stop, the ones the periodic lines had no room for too.
  const testing::Status trainer_end = testing::last_status(trainer.stderr_text());
  const testing::Status predictor_end = testing::last_status(predictor.stderr_text());
  EXPECT_GT(trainer_end.at("referee_messages"), 0u) << trainer.stderr_text();
  EXPECT_GT(trainer_end.at("saves"), 0u) << trainer.stderr_text();
  EXPECT_GT(predictor_end.at("formations"), 0u) << predictor.stderr_text();
  EXPECT_GT(predictor_end.at("table_reloads"), 0u) << predictor.stderr_text();
  EXPECT_EQ(predictor_end.at("parse_errors"), 1u) << predictor.stderr_text();
}

}  // namespace
}  // namespace ssl_formation
