// ssl-evaluate as a process: the paper driver on a tiny run, and determinism of every mode. The
// simulated streams jump between formations every 2 s (the paper's scenario), so holdout and
// grid-sweep run --model paper on them; the default motion model is evaluated on logs of robots
// that move (HoldoutOfTheMotionModel...).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include "child_process.hpp"
#include "moving_robots.hpp"

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
       "--test-seed", "8", "--model", "paper"},
      {"grid-sweep", "--train-formations", "300", "--test-formations", "100", "--seed", "7",
       "--grids", "3x2", "6x4", "--model", "paper"}};
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

// The accuracy table has a line for every method at `horizon` (as printed) and `steps`.
void expect_every_method(const std::string& out, const std::string& horizon,
                         const std::string& steps) {
  for (const std::string method :
       {"model", "persistence", "constant velocity", "damped constant velocity",
        "constant acceleration", "damped constant acceleration"}) {
    EXPECT_TRUE(std::regex_search(
        out, std::regex(horizon + R"(\s+)" + steps + R"(\s+)" + method + R"(\s+[\d.]+%)")))
        << horizon << " " << steps << " " << method << "\n"
        << out;
  }
}

TEST(Evaluate, HoldoutScoresEveryMethodAtEveryHorizonInMillimetresAndCells) {
  TempDir dir;
  const auto run = evaluate(dir,
                            {"holdout", "--train-formations", "800", "--test-formations", "300",
                             "--horizons", "1,2", "--model", "paper"},
                            "holdout");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Each horizon in seconds is a model of its own, then the chains of 1-3 steps of --step (2 s).
  const std::vector<std::pair<std::string, std::string>> rows{
      {"1.00 s", "1"}, {"2.00 s", "1"}, {"2.00 s", "1"}, {"4.00 s", "2"}, {"6.00 s", "3"}};
  for (const auto& [horizon, steps] : rows) {
    expect_every_method(run.out, horizon, steps);
  }
  EXPECT_NE(run.out.find("Brier"), std::string::npos);
  EXPECT_NE(run.out.find("ECE"), std::string::npos);

  // Five horizons, six methods, and without a referee the rows "all" and "running" only.
  const auto accuracy = csv_rows(read(dir / "holdout" / "holdout-accuracy.csv"));
  ASSERT_EQ(accuracy.size(), 1u + 5u * 6u * 2u);
  EXPECT_EQ(accuracy[0], (std::vector<std::string>{"grid",
                                                   "horizon_steps",
                                                   "horizon_s",
                                                   "game_state",
                                                   "method",
                                                   "state_accuracy",
                                                   "cell_accuracy",
                                                   "mean_cell_distance",
                                                   "mean_error_mm",
                                                   "median_error_mm",
                                                   "p90_error_mm",
                                                   "robots",
                                                   "mean_error_mm_ci_low",
                                                   "mean_error_mm_ci_high",
                                                   "best_baseline",
                                                   "ratio_to_best_baseline",
                                                   "ratio_ci_low",
                                                   "ratio_ci_high",
                                                   "model_ratio_to_method",
                                                   "model_ratio_ci_low",
                                                   "model_ratio_ci_high",
                                                   "bootstrap_blocks"}));
  for (std::size_t i = 1; i < accuracy.size(); ++i) {
    ASSERT_EQ(accuracy[i].size(), 22u);
    EXPECT_EQ(accuracy[i][0], "3x2");
    EXPECT_TRUE(accuracy[i][3] == "all" || accuracy[i][3] == "running") << accuracy[i][3];
    // Every mean has its interval (300 formations 2 s apart: 60 blocks of 10 s), and every
    // method its ratio to the best baseline, with an interval too. The 1 s section scores no
    // robot (its formations are 2 s apart): no interval, no blocks.
    if (accuracy[i][11] == "0") {
      EXPECT_TRUE(accuracy[i][12].empty() && accuracy[i][15].empty()) << i;
      EXPECT_EQ(accuracy[i][21], "0");
      continue;
    }
    const double mean = std::stod(accuracy[i][8]);
    EXPECT_LE(std::stod(accuracy[i][12]), mean + 1e-9) << i;
    EXPECT_GE(std::stod(accuracy[i][13]), mean - 1e-9) << i;
    EXPECT_FALSE(accuracy[i][14].empty());
    const double ratio = std::stod(accuracy[i][15]);
    EXPECT_LE(std::stod(accuracy[i][16]), ratio + 1e-9) << i;
    EXPECT_GE(std::stod(accuracy[i][17]), ratio - 1e-9) << i;
    if (accuracy[i][4] == accuracy[i][14]) {
      EXPECT_EQ(accuracy[i][15], "1");
    }
    // The model over this method, with its interval.
    const double model_ratio = std::stod(accuracy[i][18]);
    EXPECT_LE(std::stod(accuracy[i][19]), model_ratio + 1e-9) << i;
    EXPECT_GE(std::stod(accuracy[i][20]), model_ratio - 1e-9) << i;
    if (accuracy[i][4] == "model") {
      EXPECT_EQ(accuracy[i][18], "1");
    }
    EXPECT_GE(std::stoi(accuracy[i][21]), 55) << i;
    const double cell = std::stod(accuracy[i][6]);
    EXPECT_GE(cell, 0.0);
    EXPECT_LE(cell, 1.0);
    EXPECT_GE(std::stod(accuracy[i][10]), std::stod(accuracy[i][9]));  // p90 >= median
  }
  // The paper's simulation moves robots every 2 s: at 2 s and on, every method was scored.
  EXPECT_GT(std::stoull(accuracy[13][11]), 0u);  // the 2 s section's first row
  EXPECT_NE(run.out.find("no referee messages"), std::string::npos) << run.out;

  const auto calibration = csv_rows(read(dir / "holdout" / "holdout-calibration.csv"));
  ASSERT_EQ(calibration.size(), 1u + 5u * 2u * 2u);
  EXPECT_EQ(calibration[0],
            (std::vector<std::string>{"grid", "horizon_steps", "horizon_s", "game_state", "method",
                                      "quantity", "brier", "ece", "predictions", "within_radius_50",
                                      "within_radius_90"}));
  EXPECT_EQ(calibration[3][5], "robot");
  EXPECT_EQ(calibration[4][5], "formation");
  // The paper's model states no radii: nothing is within them, and the report has no radii
  // section.
  for (std::size_t i = 1; i < calibration.size(); ++i) {
    ASSERT_EQ(calibration[i].size(), 11u);
    EXPECT_EQ(calibration[i][4], "model");
    EXPECT_EQ(calibration[i][9], "0");
    EXPECT_EQ(calibration[i][10], "0");
  }
  EXPECT_EQ(run.out.find("radii"), std::string::npos) << run.out;
  const std::string reliability = read(dir / "holdout" / "holdout-reliability.csv");
  EXPECT_EQ(std::count(reliability.begin(), reliability.end(), '\n'), 1 + 5 * 2 * 2 * 10);
}

TEST(Evaluate, HoldoutOnSeveralLogsSplitInTimeAndOnSeparateTestLogs) {
  TempDir dir;
  const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
  for (const auto& [name, seed] :
       {std::pair{"a.log", "1"}, std::pair{"b.log.gz", "2"}, std::pair{"c.log", "3"}}) {
    const auto written = testing::run_to_end(
        producer_program,
        {"--simulation", "paper", "--referee", "off", "--write-log", (dir / name).string(),
         "--count", "300", "--seed", seed, "--cameras", "2"},
        dir.path(), std::string("write-") + name, 30s);
    ASSERT_EQ(written.exit_code, 0) << written.err;
  }
  const auto split =
      evaluate(dir,
               {"holdout", "--train-log", (dir / "a.log").string(), (dir / "b.log.gz").string(),
                "--split", "0.6", "--horizons", "2", "--model", "paper"},
               "split");
  ASSERT_EQ(split.exit_code, 0) << split.err;
  // Two streams of 300 formations, the last 40% of each tested: 2 x 120 formations.
  EXPECT_NE(split.out.find(": 240 test formations"), std::string::npos) << split.out;
  // The tuning split: the first 60% of each split again, 36% trained on and 24% tested, and the
  // last 40%, which reports, never read.
  const auto tune =
      evaluate(dir,
               {"holdout", "--train-log", (dir / "a.log").string(), (dir / "b.log.gz").string(),
                "--split", "0.6", "--tune", "--horizons", "2", "--model", "paper"},
               "tune");
  ASSERT_EQ(tune.exit_code, 0) << tune.err;
  EXPECT_NE(tune.out.find(": 144 test formations"), std::string::npos) << tune.out;
  EXPECT_NE(tune.out.find("transitions from 216 formations"), std::string::npos) << tune.out;
  EXPECT_NE(tune.out.find("the last 0.4, which reports, is not scored"), std::string::npos)
      << tune.out;
  EXPECT_EQ(evaluate(dir, {"holdout", "--tune"}, "tune-without-split").exit_code, 2);
  // The tuning split never reads reported data: other logs to test on are refused.
  EXPECT_EQ(evaluate(dir,
                     {"holdout", "--train-log", (dir / "a.log").string(), "--split", "0.6",
                      "--tune", "--test-log", (dir / "c.log").string(), "--model", "paper"},
                     "tune-with-test-log")
                .exit_code,
            2);
  const auto separate =
      evaluate(dir,
               {"holdout", "--train-log", (dir / "a.log").string(), (dir / "b.log.gz").string(),
                "--test-log", (dir / "c.log").string(), "--horizons", "2", "--model", "paper"},
               "separate");
  ASSERT_EQ(separate.exit_code, 0) << separate.err;
  EXPECT_NE(separate.out.find("transitions from 600 formations"), std::string::npos)
      << separate.out;
  EXPECT_NE(separate.out.find(": 300 test formations"), std::string::npos) << separate.out;

  // A run that fails leaves the CSVs of an earlier run in the same folder as they were: a test
  // log that is missing, and one that is not a log.
  const std::string accuracy = read(dir / "separate" / "holdout-accuracy.csv");
  ASSERT_NE(accuracy.find("mean_error_mm"), std::string::npos);
  { std::ofstream(dir / "notes.log") << "not a log at all, but long enough to be read as one\n"; }
  for (const char* test_log : {"missing.log", "notes.log"}) {
    const auto failed = evaluate(dir,
                                 {"holdout", "--train-log", (dir / "a.log").string(), "--test-log",
                                  (dir / test_log).string(), "--horizons", "2", "--model", "paper"},
                                 "separate");
    EXPECT_NE(failed.exit_code, 0) << test_log << ": " << failed.out;
    EXPECT_EQ(read(dir / "separate" / "holdout-accuracy.csv"), accuracy) << test_log;
  }
  for (const auto& entry : std::filesystem::directory_iterator(dir / "separate")) {
    EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << "left behind: " << entry;
  }
}

// The default model on logs of robots that really move (60 Hz frames): every horizon of its own
// and every chain of --step (0.5 s) scored for every method in mm and cells, its radii checked
// against where the robots went, the same numbers on a second run.
TEST(Evaluate, HoldoutOfTheMotionModelOnLogsOfMovingRobots) {
  TempDir dir;
  const auto train_log = dir / "train.log.gz";
  const auto test_log = dir / "test.log";
  ASSERT_EQ(testing::write_train_and_test_logs(train_log, test_log, 20.0), "");
  const std::vector<std::string> args{"holdout",    "--train-log",     train_log.string(),
                                      "--test-log", test_log.string(), "--horizons",
                                      "0.5,1"};
  const auto run = evaluate(dir, args, "motion");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("frame sampling: 1200 test formations"), std::string::npos) << run.out;
  // --horizons 0.5 and 1 s, each a model of its own, then the chains of 1-3 steps of 0.5 s.
  const std::vector<std::pair<std::string, std::string>> rows{
      {"0.50 s", "1"}, {"1.00 s", "1"}, {"0.50 s", "1"}, {"1.00 s", "2"}, {"1.50 s", "3"}};
  for (const auto& [horizon, steps] : rows) {
    expect_every_method(run.out, horizon, steps);
    // The radii section: how often the robot ended up within r50 and r90.
    EXPECT_TRUE(std::regex_search(
        run.out, std::regex(horizon + R"(\s+)" + steps + R"(\s+[\d.]+%\s+[\d.]+%\s+[1-9]\d*\n)")))
        << horizon << " " << steps << "\n"
        << run.out;
  }
  EXPECT_NE(run.out.find("The model's radii"), std::string::npos) << run.out;

  const auto accuracy = csv_rows(read(dir / "motion" / "holdout-accuracy.csv"));
  ASSERT_EQ(accuracy.size(), 1u + 5u * 7u * 2u);
  std::size_t all_rows = 0;
  for (std::size_t i = 1; i < accuracy.size(); i += 7) {
    // Rows of one horizon and game state: the model, the five baselines, the pooled model.
    ASSERT_EQ(accuracy[i].size(), 22u);
    EXPECT_EQ(accuracy[i][4], "model");
    EXPECT_EQ(accuracy[i + 6][4], "pooled model");
    EXPECT_EQ(accuracy[i + 6][11], accuracy[i][11]);  // scored on the same robots
    if (accuracy[i][3] != "all") continue;
    ++all_rows;
    const double model_mm = std::stod(accuracy[i][8]);
    EXPECT_GT(std::stoull(accuracy[i][11]), 1000u) << i;
    EXPECT_GT(model_mm, 0.0);
    // Robots that move: the model's mean error is below persistence's and constant velocity's.
    for (std::size_t b = 1; b < 6; ++b) {
      EXPECT_EQ(accuracy[i + b][11], accuracy[i][11]);  // the same robots scored
    }
    for (std::size_t b = 1; b < 4; ++b) {
      EXPECT_LT(model_mm, std::stod(accuracy[i + b][8])) << accuracy[i + b][4] << " row " << i;
    }
  }
  EXPECT_EQ(all_rows, 5u);
  const auto calibration = csv_rows(read(dir / "motion" / "holdout-calibration.csv"));
  ASSERT_EQ(calibration.size(), 1u + 5u * 2u * 2u);
  EXPECT_EQ(calibration[0].back(), "within_radius_90");
  for (std::size_t i = 1; i < calibration.size(); ++i) {
    ASSERT_EQ(calibration[i].size(), 11u);
    const double within50 = std::stod(calibration[i][9]);
    const double within90 = std::stod(calibration[i][10]);
    // Calibrated on the table's held-out frames: near 50% and 90% on another match.
    EXPECT_GT(within50, 0.3) << i;
    EXPECT_LT(within50, 0.7) << i;
    EXPECT_GT(within90, 0.75) << i;
    EXPECT_LT(within90, 0.99) << i;
  }

  const auto again = evaluate(dir, args, "again");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  for (const std::string csv :
       {"holdout-accuracy.csv", "holdout-calibration.csv", "holdout-reliability.csv"}) {
    EXPECT_EQ(read(dir / "motion" / csv), read(dir / "again" / csv)) << csv;
  }
}

// Without logs, the default model is evaluated on a simulated match with its referee: every table
// gains its rows by game state, as the daemons follow the referee.
TEST(Evaluate, HoldoutOnASimulatedMatchFollowsItsRefereeByGameState) {
  TempDir dir;
  const auto run = evaluate(dir,
                            {"holdout", "--train-seconds", "120", "--test-seconds", "90",
                             "--horizons", "1", "--chain-steps", "1", "--learn-during", "all"},
                            "match");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto accuracy = csv_rows(read(dir / "match" / "holdout-accuracy.csv"));
  // Two sections (1 s, and one step of 0.5 s), 11 rows of game state, 7 methods (the model,
  // five baselines, the pooled model).
  ASSERT_EQ(accuracy.size(), 1u + 2u * 11u * 7u);
  std::map<std::string, std::uint64_t> robots;
  for (std::size_t i = 1; i < accuracy.size(); ++i) {
    if (accuracy[i][4] == "model" && accuracy[i][1] == "1" && accuracy[i][2] == "1") {
      robots[accuracy[i][3]] = std::stoull(accuracy[i][11]);
    }
  }
  ASSERT_EQ(robots.size(), 11u);
  for (const std::string state :
       {"all", "running", "stop", "halt", "ball_placement_opponent", "ball_placement_us",
        "kickoff_opponent", "kickoff_us", "free_kick_opponent", "free_kick_us", "penalty"}) {
    EXPECT_TRUE(robots.contains(state)) << state;
  }
  // The simulated match kicks off, plays, stops and places the ball.
  EXPECT_GT(robots["running"], 1000u);
  EXPECT_GT(robots["kickoff_opponent"] + robots["kickoff_us"], 0u);
  std::uint64_t by_state = 0;
  for (const auto& [state, n] : robots) by_state += state == "all" ? 0 : n;
  EXPECT_EQ(by_state, robots["all"]);  // every instant in exactly one state
  EXPECT_NE(run.out.find("by phase of the game"), std::string::npos) << run.out;

  // Intervals where a state spans enough 10 s blocks (90 s of test: 9 blocks at most), none
  // where it spans fewer than 5; the printed ratio table names the best baseline.
  for (std::size_t i = 1; i < accuracy.size(); ++i) {
    const int blocks = std::stoi(accuracy[i][21]);
    EXPECT_LE(blocks, 10) << i;
    EXPECT_EQ(accuracy[i][12].empty(), blocks < 5) << accuracy[i][3] << " " << blocks;
    if (accuracy[i][3] == "all") {
      EXPECT_GE(blocks, 8);
    }
  }
  EXPECT_TRUE(std::regex_search(
      run.out, std::regex(R"(1\.00 s\s+1 all\s+\d+ damped constant (velocity|acceleration))"
                          R"(\s+[\d.]+\s+\[[\d.]+, [\d.]+\])")))
      << run.out;

  // --bootstrap 0: the same means, no intervals.
  const auto plain =
      evaluate(dir,
               {"holdout", "--train-seconds", "120", "--test-seconds", "90", "--horizons", "1",
                "--chain-steps", "1", "--learn-during", "all", "--bootstrap", "0"},
               "plain");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto plain_accuracy = csv_rows(read(dir / "plain" / "holdout-accuracy.csv"));
  ASSERT_EQ(plain_accuracy.size(), accuracy.size());
  for (std::size_t i = 1; i < plain_accuracy.size(); ++i) {
    EXPECT_EQ(plain_accuracy[i][8], accuracy[i][8]) << i;
    EXPECT_EQ(plain_accuracy[i][15], accuracy[i][15]) << i;
    EXPECT_TRUE(plain_accuracy[i][12].empty() && plain_accuracy[i][16].empty()) << i;
  }
  EXPECT_EQ(plain.out.find("95% interval"), std::string::npos) << plain.out;
}

TEST(Evaluate, HoldoutWritesEveryScoredRobotAsItsTablesCountedIt) {
  TempDir dir;
  const std::filesystem::path samples = dir / "samples.csv";
  const auto run =
      evaluate(dir,
               {"holdout", "--train-seconds", "60", "--test-seconds", "45", "--horizons", "1",
                "--chain-steps", "1", "--write-samples", samples.string()},
               "samples");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto lines = csv_rows(read(samples));
  ASSERT_GT(lines.size(), 1000u);
  std::map<std::string, std::size_t> column;
  for (std::size_t c = 0; c < lines.front().size(); ++c) column[lines.front()[c]] = c;
  const auto number = [&](const std::vector<std::string>& line, const std::string& name) {
    return std::stod(line.at(column.at(name)));
  };
  const auto text = [&](const std::vector<std::string>& line, const std::string& name) {
    return line.at(column.at(name));
  };
  const auto error = [&](const std::vector<std::string>& line, const std::string& method) {
    return std::hypot(number(line, method + "_x_mm") - number(line, "truth_x_mm"),
                      number(line, method + "_y_mm") - number(line, "truth_y_mm"));
  };
  // Per game state at 1 s (its own model, not the chain's), how many robots, each method's mean
  // error and how many the model's 90% radius held.
  struct Sums {
    std::uint64_t robots = 0;
    std::uint64_t within90 = 0;
    std::map<std::string, double> error;
  };
  std::map<std::string, Sums> by_state;
  std::map<std::tuple<std::string, std::string, long>, std::pair<double, double>> at_second;
  const std::vector<std::string> methods{"model", "persistence", "damped-constant-acceleration"};
  std::uint64_t chained = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string>& line = lines[i];
    ASSERT_EQ(line.size(), column.size()) << i;
    if (text(line, "chain") == "1") {
      ++chained;
      continue;
    }
    if (text(line, "horizon_s") != "1" || text(line, "horizon_steps") != "1") continue;
    at_second[{text(line, "stream"), text(line, "robot_id"),
               std::lround(number(line, "time_s") * 1000)}] = {number(line, "x_mm"),
                                                               number(line, "y_mm")};
    for (const std::string& name : {std::string("all"), text(line, "game_state")}) {
      Sums& sums = by_state[name];
      ++sums.robots;
      if (error(line, "model") <= number(line, "model_radius90_mm")) ++sums.within90;
      for (const std::string& method : methods) sums.error[method] += error(line, method);
    }
  }
  EXPECT_GT(chained, 0u);  // the chain's steps are written too, told apart
  // Where a robot went is where it was a second later, when it was scored then too.
  std::size_t followed = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string>& line = lines[i];
    if (text(line, "chain") != "0" || text(line, "horizon_s") != "1") continue;
    const auto later = at_second.find({text(line, "stream"), text(line, "robot_id"),
                                       std::lround(number(line, "time_s") * 1000) + 1000});
    if (later == at_second.end()) continue;
    EXPECT_NEAR(later->second.first, number(line, "truth_x_mm"), 0.05) << i;
    EXPECT_NEAR(later->second.second, number(line, "truth_y_mm"), 0.05) << i;
    ++followed;
  }
  EXPECT_GT(followed, 1000u);
  // The same robots, errors and radii as the tables (positions written to 0.1 mm).
  const std::map<std::string, std::string> label{
      {"model", "model"},
      {"persistence", "persistence"},
      {"damped-constant-acceleration", "damped constant acceleration"}};
  std::size_t compared = 0;
  for (const auto& row : csv_rows(read(dir / "samples" / "holdout-accuracy.csv"))) {
    if (row[1] != "1" || row[2] != "1" || !by_state.contains(row[3])) continue;
    const Sums& sums = by_state[row[3]];
    for (const std::string& method : methods) {
      if (row[4] != label.at(method)) continue;
      EXPECT_EQ(std::stoull(row[11]), sums.robots) << row[3];
      EXPECT_NEAR(std::stod(row[8]), sums.error.at(method) / static_cast<double>(sums.robots), 0.1)
          << row[3] << ' ' << method;
      ++compared;
    }
  }
  EXPECT_GE(compared, 3u * 4u);  // all, running and at least two stoppages
  std::size_t radii = 0;
  for (const auto& row : csv_rows(read(dir / "samples" / "holdout-calibration.csv"))) {
    if (row[1] != "1" || row[2] != "1" || row[5] != "robot" || !by_state.contains(row[3])) continue;
    const Sums& sums = by_state[row[3]];
    EXPECT_NEAR(std::stod(row[10]),
                static_cast<double>(sums.within90) / static_cast<double>(sums.robots), 0.002)
        << row[3];
    ++radii;
  }
  EXPECT_GE(radii, 4u);
  EXPECT_GT(by_state["all"].robots, by_state["running"].robots);

  // A file it cannot write stops it before any work, saying which; other modes refuse it.
  const auto unwritable =
      evaluate(dir, {"holdout", "--write-samples", (dir / "no-such-dir" / "samples.csv").string()},
               "unwritable");
  EXPECT_NE(unwritable.exit_code, 0);
  EXPECT_NE(unwritable.err.find("no-such-dir"), std::string::npos) << unwritable.err;
  EXPECT_EQ(
      evaluate(dir, {"paper", "--write-samples", (dir / "paper.csv").string()}, "paper").exit_code,
      2);
  EXPECT_FALSE(std::filesystem::exists(dir / "paper.csv"));
}

// The mean error of `method` at `steps` steps in the row "all" of an accuracy CSV: the last such
// row (holdout's chains come after its horizons).
double mean_error_of(const std::vector<std::vector<std::string>>& accuracy,
                     const std::string& method, const std::string& steps) {
  double found = -1.0;
  for (std::size_t i = 1; i < accuracy.size(); ++i) {
    if (accuracy[i][3] == "all" && accuracy[i][4] == method && accuracy[i][1] == steps) {
      found = std::stod(accuracy[i][8]);
    }
  }
  return found;
}

TEST(Evaluate, ScoresThePredictorsOwnCsvAsHoldoutScoresItsChains) {
  TempDir dir;
  const auto train_log = dir / "train.log.gz";
  const auto test_log = dir / "test.log";
  ASSERT_EQ(testing::write_train_and_test_logs(train_log, test_log, 20.0), "");
  // What a team does: train a table from one log, predict another with the daemon's pipeline.
  const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
  const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;
  const auto table = dir / "table.bin";
  const auto csv = dir / "predictions.csv";
  const auto trained = testing::run_to_end(
      trainer_program, {"--from-log", train_log.string(), "--table", table.string()}, dir.path(),
      "trainer", 60s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  const auto predicted = testing::run_to_end(
      predictor_program,
      {"--from-log", test_log.string(), "--table", table.string(), "--output", csv.string()},
      dir.path(), "predictor", 60s);
  ASSERT_EQ(predicted.exit_code, 0) << predicted.err;

  const auto scored =
      evaluate(dir,
               {"score", "--log", test_log.string(), "--predictions", csv.string(), "--train-log",
                train_log.string(), "--bootstrap-block", "2"},  // 20 s: 10 blocks
               "score");
  ASSERT_EQ(scored.exit_code, 0) << scored.err;
  EXPECT_NE(scored.out.find("Scored predictions from"), std::string::npos) << scored.out;
  EXPECT_NE(scored.out.find("The predictions against the best baseline"), std::string::npos)
      << scored.out;
  EXPECT_NE(scored.out.find("The model's radii"), std::string::npos) << scored.out;
  const auto holdout = evaluate(dir,
                                {"holdout", "--train-log", train_log.string(), "--test-log",
                                 test_log.string(), "--horizons", "0.5", "--chain-steps", "2"},
                                "holdout");
  ASSERT_EQ(holdout.exit_code, 0) << holdout.err;

  // The daemon's own predictions, scored, are holdout's chains of 0.5 s steps (the same table,
  // the same pipeline), within a millimetre; so are the baselines beside them.
  const auto score_rows = csv_rows(read(dir / "score" / "score-accuracy.csv"));
  const auto holdout_rows = csv_rows(read(dir / "holdout" / "holdout-accuracy.csv"));
  for (const std::string steps : {"1", "2"}) {
    SCOPED_TRACE(steps);
    const double predictions = mean_error_of(score_rows, "predictions", steps);
    const double chain = mean_error_of(holdout_rows, "model", steps);
    ASSERT_GT(predictions, 0.0) << scored.out;
    ASSERT_GT(chain, 0.0) << holdout.out;
    EXPECT_NEAR(predictions, chain, 1.0);
    EXPECT_NEAR(mean_error_of(score_rows, "damped constant acceleration", steps),
                mean_error_of(holdout_rows, "damped constant acceleration", steps), 1.0);
  }
  // Every row has its interval (over 2 s blocks), and the predictions' ratio to the best
  // baseline.
  for (std::size_t i = 1; i < score_rows.size(); ++i) {
    if (score_rows[i][11] == "0") continue;
    EXPECT_FALSE(score_rows[i][12].empty()) << i;
    EXPECT_FALSE(score_rows[i][15].empty()) << i;
  }

  EXPECT_NE(scored.out.find("1200 of the file's 1200 instants are frames of the log"),
            std::string::npos)
      << scored.out;

  // A team's own file, with the five key columns only and half its instants: scored in mm on what
  // it has, without the cells and states it does not state.
  {
    const std::vector<std::string> lines = [&] {
      std::vector<std::string> out;
      std::istringstream in(read(csv));
      for (std::string line; std::getline(in, line);) out.push_back(line);
      return out;
    }();
    std::ofstream team(dir / "team.csv");
    team << "t_capture,robot_id,horizon_s,predicted_feed_x_mm,predicted_feed_y_mm\n";
    std::set<std::string> instants;
    for (std::size_t i = 1; i < lines.size(); ++i) {
      std::vector<std::string> f;
      std::stringstream fields(lines[i]);
      for (std::string field; std::getline(fields, field, ',');) f.push_back(field);
      instants.insert(f[0]);
      if (instants.size() % 2 == 0) continue;  // every other instant left out
      team << f[0] << ',' << f[2] << ',' << f[4] << ',' << f[18] << ',' << f[19] << '\n';
    }
  }
  const auto team = evaluate(dir,
                             {"score", "--log", test_log.string(), "--predictions",
                              (dir / "team.csv").string(), "--train-log", train_log.string()},
                             "team");
  ASSERT_EQ(team.exit_code, 0) << team.err;
  EXPECT_NE(team.out.find("600 of the file's 600 instants are frames of the log"),
            std::string::npos)
      << team.out;
  EXPECT_EQ(team.out.find("Calibration of"), std::string::npos) << team.out;
  const auto team_rows = csv_rows(read(dir / "team" / "score-accuracy.csv"));
  for (std::size_t i = 1; i < team_rows.size(); ++i) {
    if (team_rows[i][4] != "predictions") continue;
    EXPECT_TRUE(team_rows[i][5].empty() && team_rows[i][6].empty() && team_rows[i][7].empty()) << i;
    EXPECT_GT(std::stod(team_rows[i][8]), 0.0) << i;
  }
  // Half the instants, the same predictions on them: about the whole file's error.
  EXPECT_NEAR(mean_error_of(team_rows, "predictions", "1"),
              mean_error_of(score_rows, "predictions", "1"), 15.0);

  // The file says its grid: another --grid is refused with the one to give, and cells that
  // almost never hold their robot are warned about.
  const auto other_grid = evaluate(
      dir, {"score", "--log", test_log.string(), "--predictions", csv.string(), "--grid", "12x9"},
      "other-grid");
  EXPECT_EQ(other_grid.exit_code, 2);
  EXPECT_NE(other_grid.err.find("give --grid 3x2"), std::string::npos) << other_grid.err;
  {
    std::string text = read(csv);
    ASSERT_NE(text.find(",3x2,"), std::string::npos);
    for (std::size_t at = text.find(",3x2,"); at != std::string::npos;
         at = text.find(",3x2,", at)) {
      text.replace(at, 5, ",12x9,");
    }
    std::ofstream(dir / "relabelled.csv") << text;
  }
  const auto relabelled = evaluate(
      dir,
      {"score", "--log", test_log.string(), "--predictions", (dir / "relabelled.csv").string()},
      "relabelled");
  EXPECT_EQ(relabelled.exit_code, 0) << relabelled.err;
  EXPECT_NE(relabelled.err.find("were the predictions made with --grid 12x9"), std::string::npos)
      << relabelled.err;
  EXPECT_EQ(scored.err.find("were the predictions made with"), std::string::npos) << scored.err;

  // Predictions of another log score nothing, and say so; a file that is not there, likewise.
  const auto other_log = dir / "other.log";
  ASSERT_EQ(testing::write_vision_log(other_log,
                                      testing::moving_robots_packets(
                                          {.seed = 3, .seconds = 20.0, .start_time_s = 5000.0})),
            "");
  const auto mismatched = evaluate(
      dir, {"score", "--log", other_log.string(), "--predictions", csv.string()}, "mismatched");
  EXPECT_EQ(mismatched.exit_code, 1);
  EXPECT_NE(mismatched.err.find("is it that log's CSV?"), std::string::npos) << mismatched.err;
  const auto missing = evaluate(
      dir, {"score", "--log", test_log.string(), "--predictions", (dir / "none.csv").string()},
      "missing");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("none.csv"), std::string::npos) << missing.err;
  EXPECT_EQ(evaluate(dir, {"score", "--log", test_log.string()}, "no-predictions").exit_code, 2);
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
  EXPECT_EQ(evaluate(dir, {"holdout", "--simulation", "dream"}, "simulation").exit_code, 2);
  // A train log without anything to test on is refused, not tested on a simulation.
  const auto no_test =
      evaluate(dir, {"holdout", "--train-log", (dir / "x.log").string()}, "no-test");
  EXPECT_EQ(no_test.exit_code, 2);
  EXPECT_NE(no_test.err.find("--test-log"), std::string::npos) << no_test.err;
  EXPECT_EQ(
      evaluate(dir, {"holdout", "--recalibration-half-life", "-1"}, "recalibration").exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--bootstrap", "-1"}, "bootstrap").exit_code, 2);
  EXPECT_EQ(evaluate(dir, {"holdout", "--bootstrap-block", "0"}, "bootstrap-block").exit_code, 2);
}

}  // namespace
}  // namespace ssl_formation
