// ssl-evaluate as a process: the paper driver on a tiny run, and determinism of every mode.

#include <gtest/gtest.h>

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

TEST(Evaluate, HoldoutPrintsModelAndBothBaselinesForEveryHorizon) {
  TempDir dir;
  const auto run = evaluate(
      dir, {"holdout", "--train-formations", "800", "--test-formations", "300"}, "holdout");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const std::string horizon : {"1", "2", "3"}) {
    for (const std::string method : {"model", "persistence", "constant velocity"}) {
      EXPECT_TRUE(
          std::regex_search(run.out, std::regex(horizon + R"(\s+)" + method + R"(\s+[\d.]+%)")))
          << horizon << " " << method << "\n"
          << run.out;
    }
  }
  EXPECT_NE(run.out.find("Brier"), std::string::npos);
  const std::string reliability = read(dir / "holdout" / "holdout-reliability.csv");
  EXPECT_EQ(std::count(reliability.begin(), reliability.end(), '\n'), 1 + 3 * 10);
}

TEST(Evaluate, BadModeAndOptionsExitWithTwo) {
  TempDir dir;
  EXPECT_EQ(evaluate(dir, {"guess"}, "bad").exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--split", "0.5"}, "split").exit_code,
            2);  // needs --train-log
  EXPECT_EQ(testing::run_to_end(evaluate_program, {}, dir.path(), "none", 10s).exit_code, 2);
}

}  // namespace
}  // namespace ssl_formation
