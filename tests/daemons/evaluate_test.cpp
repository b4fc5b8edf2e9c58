// ssl-evaluate as a process: the paper driver on a tiny run, and determinism of every mode.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>

#include "child_process.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

const std::filesystem::path evaluate_program = SSLF_EVALUATE_PATH;

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

testing::RunResult evaluate(const TempDir& dir, std::vector<std::string> args,
                            const std::string& out) {
  args.push_back("--output-dir");
  args.push_back((dir / out).string());
  return testing::run_to_end(evaluate_program, args, dir.path(), out, 120s);
}

TEST(Evaluate, PaperDriverOnATinyRun) {
  TempDir dir;
  const auto run = evaluate(dir, {"paper", "--train-formations", "600", "--tests", "25"}, "paper");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("trained on 600 formations"), std::string::npos) << run.out;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(
      run.out, match,
      std::regex(R"(count similarity measure\s+([\d.]+)\s+16\.6826\s+([\d.]+)\s+5\.5608)")))
      << run.out;
  const double per_play = std::stod(match[1]);
  EXPECT_NEAR(std::stod(match[2]), per_play / 3.0, 1e-4);
  EXPECT_GE(per_play, 0.0);
  EXPECT_LE(per_play, 18.0);  // 6 robots x 3 formations at most
  EXPECT_NE(run.out.find("distance similarity measure"), std::string::npos);
  EXPECT_NE(run.out.find("average confidence: 1st predicted formation"), std::string::npos);
  const std::string csv = read(dir / "paper" / "paper-running-averages.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 26);  // header + one line per test
}

TEST(Evaluate, SameSeedSameNumbersInEveryMode) {
  TempDir dir;
  const std::vector<std::vector<std::string>> modes{
      {"paper", "--train-formations", "500", "--tests", "50", "--seed", "7", "--test-seed", "8"},
      {"holdout", "--train-formations", "500", "--test-formations", "200", "--seed", "7",
       "--test-seed", "8"},
      {"grid-sweep", "--train-formations", "300", "--test-formations", "100", "--seed", "7",
       "--grids", "3x2", "6x4"}};
  const std::vector<std::string> csvs{"paper-running-averages.csv", "holdout-accuracy.csv",
                                      "grid-sweep-accuracy.csv"};
  for (std::size_t m = 0; m < modes.size(); ++m) {
    const auto first = evaluate(dir, modes[m], "first" + std::to_string(m));
    const auto second = evaluate(dir, modes[m], "second" + std::to_string(m));
    ASSERT_EQ(first.exit_code, 0) << first.err;
    ASSERT_EQ(second.exit_code, 0) << second.err;
    const std::string a = read(dir / ("first" + std::to_string(m)) / csvs[m]);
    EXPECT_FALSE(a.empty());
    EXPECT_EQ(a, read(dir / ("second" + std::to_string(m)) / csvs[m])) << csvs[m];
  }
  // A different seed gives different numbers: the seed is really used.
  auto other = modes[1];
  other[6] = "9";
  ASSERT_EQ(evaluate(dir, other, "other").exit_code, 0);
  EXPECT_NE(read(dir / "other" / "holdout-accuracy.csv"),
            read(dir / "first1" / "holdout-accuracy.csv"));
}

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> fields;
    std::istringstream in(line);
    for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

TEST(Evaluate, HoldoutScoresEveryMethodAtEveryHorizonInMillimetresAndCells) {
  TempDir dir;
  const auto run = evaluate(dir,
                            {"holdout", "--train-formations", "800", "--test-formations", "300",
                             "--horizons", "1,2"},
                            "holdout");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Each horizon in seconds is a model of its own, then the chains of 1-3 steps of --step (2 s).
  const std::vector<std::pair<std::string, std::string>> rows{
      {"1.00 s", "1"}, {"2.00 s", "1"}, {"2.00 s", "1"}, {"4.00 s", "2"}, {"6.00 s", "3"}};
  for (const auto& [horizon, steps] : rows) {
    for (const std::string method :
         {"model", "persistence", "constant velocity", "damped constant velocity"}) {
      EXPECT_TRUE(std::regex_search(
          run.out, std::regex(horizon + R"(\s+)" + steps + R"(\s+)" + method + R"(\s+[\d.]+%)")))
          << horizon << " " << steps << " " << method << "\n"
          << run.out;
    }
  }
  EXPECT_NE(run.out.find("Brier"), std::string::npos);
  EXPECT_NE(run.out.find("ECE"), std::string::npos);

  const auto accuracy = csv_rows(read(dir / "holdout" / "holdout-accuracy.csv"));
  ASSERT_EQ(accuracy.size(), 1u + 5u * 4u);
  EXPECT_EQ(accuracy[0],
            (std::vector<std::string>{"grid", "horizon_steps", "horizon_s", "method",
                                      "state_accuracy", "cell_accuracy", "mean_cell_distance",
                                      "mean_error_mm", "median_error_mm", "p90_error_mm",
                                      "robots"}));
  for (std::size_t i = 1; i < accuracy.size(); ++i) {
    ASSERT_EQ(accuracy[i].size(), 11u);
    EXPECT_EQ(accuracy[i][0], "3x2");
    const double cell = std::stod(accuracy[i][5]);
    EXPECT_GE(cell, 0.0);
    EXPECT_LE(cell, 1.0);
    EXPECT_GE(std::stod(accuracy[i][9]), std::stod(accuracy[i][8]));  // p90 >= median
  }
  // The paper's simulation moves robots every 2 s: at 2 s and on, every method was scored.
  EXPECT_GT(std::stoull(accuracy[5][10]), 0u);

  const auto calibration = csv_rows(read(dir / "holdout" / "holdout-calibration.csv"));
  ASSERT_EQ(calibration.size(), 1u + 5u * 2u);
  EXPECT_EQ(calibration[0], (std::vector<std::string>{"grid", "horizon_steps", "horizon_s",
                                                      "method", "quantity", "brier", "ece",
                                                      "predictions"}));
  EXPECT_EQ(calibration[3][4], "robot");
  EXPECT_EQ(calibration[4][4], "formation");
  const std::string reliability = read(dir / "holdout" / "holdout-reliability.csv");
  EXPECT_EQ(std::count(reliability.begin(), reliability.end(), '\n'), 1 + 5 * 2 * 10);
}

TEST(Evaluate, HoldoutOnSeveralLogsSplitInTimeAndOnSeparateTestLogs) {
  TempDir dir;
  const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
  for (const auto& [name, seed] : {std::pair{"a.log", "1"}, std::pair{"b.log.gz", "2"},
                                   std::pair{"c.log", "3"}}) {
    const auto written = testing::run_to_end(
        producer_program,
        {"--write-log", (dir / name).string(), "--count", "300", "--seed", seed, "--cameras", "2"},
        dir.path(), std::string("write-") + name, 30s);
    ASSERT_EQ(written.exit_code, 0) << written.err;
  }
  const auto split = evaluate(dir,
                              {"holdout", "--train-log", (dir / "a.log").string(),
                               (dir / "b.log.gz").string(), "--split", "0.6", "--horizons", "2"},
                              "split");
  ASSERT_EQ(split.exit_code, 0) << split.err;
  // Two streams of 300 formations, the last 40% of each tested: 2 x 120 formations.
  EXPECT_NE(split.out.find(": 240 test formations"), std::string::npos) << split.out;
  const auto separate = evaluate(dir,
                                 {"holdout", "--train-log", (dir / "a.log").string(),
                                  (dir / "b.log.gz").string(), "--test-log",
                                  (dir / "c.log").string(), "--horizons", "2"},
                                 "separate");
  ASSERT_EQ(separate.exit_code, 0) << separate.err;
  EXPECT_NE(separate.out.find("transitions from 600 formations"), std::string::npos)
      << separate.out;
  EXPECT_NE(separate.out.find(": 300 test formations"), std::string::npos) << separate.out;
}

TEST(Evaluate, BadModeAndOptionsExitWithTwo) {
  TempDir dir;
  EXPECT_EQ(evaluate(dir, {"guess"}, "bad").exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--split", "0.5"}, "split").exit_code,
            2);  // needs --train-log
  EXPECT_EQ(testing::run_to_end(evaluate_program, {}, dir.path(), "none", 10s).exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--horizons", "0.5,-1"}, "horizons").exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--horizons", "0.5,,1"}, "empty-horizon").exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--sampling", "sometimes"}, "sampling").exit_code, 2);
}

}  // namespace
}  // namespace ssl_formation
