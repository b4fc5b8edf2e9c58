// ssl-evaluate --report in a real browser: the page written for a held-out evaluation of logs of
// moving robots is opened offline in Debian's headless Chromium (report_check.mjs, through
// playwright-core), which checks that every figure is drawn and that the table's numbers are the
// CSV's. Skipped, with the reason, where Chromium, node or playwright-core is missing, like the
// field view's browser test.

#include <gtest/gtest.h>

#include <filesystem>

#include "child_process.hpp"
#include "moving_robots.hpp"
#include "web_test_support.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

const std::filesystem::path evaluate_program = SSLF_EVALUATE_PATH;
const std::filesystem::path web_test_dir = SSLF_WEB_TEST_DIR;
const std::filesystem::path screenshot_dir = SSLF_WEB_SCREENSHOT_DIR;

TEST(ReportBrowser, DrawsEveryFigureWithTheCsvsNumbersOffline) {
  std::filesystem::path chromium;
  std::filesystem::path node;
  if (const auto reason = web_testing::missing_browser_tools(chromium, node, web_test_dir)) {
    GTEST_SKIP() << *reason;
  }
  TempDir dir;
  const auto train_log = dir / "train.log";
  const auto test_log = dir / "test.log";
  ASSERT_EQ(testing::write_train_and_test_logs(train_log, test_log, 60.0), "");
  const auto report = dir / "report.html";
  const auto evaluated = testing::run_to_end(
      evaluate_program,
      {"holdout", "--train-log", train_log.string(), "--test-log", test_log.string(), "--horizons",
       "2", "--report", report.string(), "--output-dir", dir.path().string()},
      dir.path(), "evaluate", 120s);
  ASSERT_EQ(evaluated.exit_code, 0) << evaluated.err;
  ASSERT_TRUE(std::filesystem::exists(report));

  std::filesystem::create_directories(screenshot_dir);
  const auto checked = testing::run_to_end(
      node,
      {(web_test_dir / "report_check.mjs").string(), "--report", report.string(), "--csv",
       (dir / "holdout-accuracy.csv").string(), "--user-data-dir",
       (dir / "chromium-profile").string(), "--chromium", chromium.string(), "--screenshot",
       (screenshot_dir / "report.png").string()},
      dir.path(), "browser", 240s);
  if (checked.out.find("PHASE launched ok") == std::string::npos &&
      checked.out.find("FAIL") == std::string::npos) {
    GTEST_SKIP() << "Chromium did not start: " << checked.out << checked.err;
  }
  ASSERT_EQ(checked.exit_code, 0) << checked.out << checked.err;
  EXPECT_NE(checked.out.find("PHASE table ok"), std::string::npos) << checked.out;
  EXPECT_NE(checked.out.find("PHASE figures ok"), std::string::npos) << checked.out;
}

TEST(Report, ABadPathStopsTheRunBeforeAnyWorkAndOtherModesRefuseIt) {
  TempDir dir;
  const auto refused = testing::run_to_end(
      evaluate_program, {"holdout", "--report", (dir / "no-such-dir" / "r.html").string()},
      dir.path(), "bad-path", 60s);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("cannot write the report"), std::string::npos) << refused.err;
  EXPECT_EQ(
      testing::run_to_end(evaluate_program,
                          {"grid-sweep", "--model", "paper", "--report", (dir / "r.html").string()},
                          dir.path(), "sweep", 60s)
          .exit_code,
      2);
  EXPECT_FALSE(std::filesystem::exists(dir / "r.html"));
}

}  // namespace
}  // namespace ssl_formation
