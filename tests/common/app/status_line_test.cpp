#include "ssl_formation/app/status_line.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "captured_log.hpp"
#include "ssl_formation/app/daemon.hpp"

namespace ssl_formation::app {
namespace {

bool has(const std::string& text, const std::string& item) {
  return (" " + text + " ").find(" " + item + " ") != std::string::npos;
}

TEST(StatusLine, CountersAtZeroAreLeftOut) {
  StatusLine line;
  line.figure("packets", 12)
      .figure("formations", 0)
      .figure("game", "halt")
      .detail("saves", 0)
      .detail("referee_messages", 3)
      .problem("kernel_drops", 0)
      .problem("parse_errors", 2);
  EXPECT_EQ(line.text(199), "packets=12 game=halt referee_messages=3 | problems: parse_errors=2");
}

TEST(StatusLine, AllWellHasNoProblemsPart) {
  StatusLine line;
  line.note("no vision packets yet").figure("game", "unknown").problem("kernel_drops", 0);
  EXPECT_EQ(line.text(199), "no vision packets yet game=unknown");
  EXPECT_EQ(StatusLine().problem("late", 1).text(199), "problems: late=1");
}

TEST(StatusLine, DetailsGiveWayInTheirOrderAndFiguresStay) {
  StatusLine line;
  line.figure("packets", 123456789)
      .detail("first", 1)
      .detail("second_longer", 22)
      .detail("third", 3)
      .figure("game", "running");
  EXPECT_EQ(line.text(200), "packets=123456789 game=running first=1 second_longer=22 third=3");
  // Room for the first detail only: the shorter third does not jump the queue.
  const std::size_t room = std::string("packets=123456789 game=running first=1 third=3").size();
  EXPECT_EQ(line.text(room), "packets=123456789 game=running first=1");
  EXPECT_EQ(line.left_out(room), (std::vector<std::string>{"second_longer=22", "third=3"}));
  // A figure that does not fit gives way to the next that does, and no detail comes instead.
  EXPECT_EQ(line.text(16), "game=running");
  EXPECT_EQ(line.left_out(16), (std::vector<std::string>{"packets=123456789", "first=1",
                                                         "second_longer=22", "third=3"}));
}

TEST(StatusLine, ANonZeroProblemIsNeverLeftOut) {
  StatusLine line;
  line.figure("packets", 123456).figure("formations", 30000).figure("game", "running");
  for (int i = 0; i < 20; ++i) line.detail("detail_" + std::to_string(i), 1000 + i);
  line.problem("kernel_drops", 12).problem("parse_errors", 3);
  const std::string text = line.text(100);
  EXPECT_LE(text.size(), 100u) << text;
  EXPECT_TRUE(has(text, "kernel_drops=12")) << text;
  EXPECT_TRUE(has(text, "parse_errors=3")) << text;
  // Even when the problems alone are longer than the room: then the line is longer.
  const std::string squeezed = line.text(20);
  EXPECT_TRUE(has(squeezed, "kernel_drops=12")) << squeezed;
  EXPECT_TRUE(has(squeezed, "parse_errors=3")) << squeezed;
  EXPECT_EQ(squeezed, "problems: kernel_drops=12 parse_errors=3");
}

TEST(StatusLine, ProblemsOfAGroupAreSummedWhenTheyCrowdTheFiguresOut) {
  StatusLine line;
  line.figure("packets", 5000).figure("formations", 1200).detail("saves", 3);
  line.problem("parse_errors", 2)
      .problem("non_finite", 30, "input_refused")
      .problem("late", 0, "input_refused")
      .problem("bad_camera", 11, "input_refused");
  // Room for everything: each problem on its own.
  EXPECT_EQ(line.text(199),
            "packets=5000 formations=1200 saves=3 | problems: parse_errors=2 non_finite=30 "
            "bad_camera=11");
  // Room for the figures only once the group is summed.
  const std::string grouped =
      "packets=5000 formations=1200 | problems: parse_errors=2 input_refused=41";
  EXPECT_EQ(line.text(grouped.size() + 5), grouped);
  EXPECT_EQ(line.left_out(grouped.size() + 5),
            (std::vector<std::string>{"saves=3", "non_finite=30", "bad_camera=11"}));
}

// Lines of random counters, random names and random room: every non-zero problem is on the line,
// no zero is, and the line fits whenever its problems do.
TEST(StatusLine, EveryNonZeroProblemShowsWhateverTheRest) {
  std::mt19937 random(7);
  const auto count = [&random] {
    // Zero half the time, else up to ten digits.
    if (random() % 2 == 0) return std::uint64_t{0};
    std::uint64_t value = 1 + random() % 9;
    for (int digits = static_cast<int>(random() % 10); digits > 0; --digits) {
      value = value * 10 + random() % 10;
    }
    return value;
  };
  for (int run = 0; run < 2000; ++run) {
    StatusLine line;
    struct Shown {
      std::string problem;
      std::string group;
    };
    std::vector<Shown> problems;
    const int items = static_cast<int>(random() % 40);
    for (int i = 0; i < items; ++i) {
      std::string name = "n";
      name += std::to_string(i);
      name.append(random() % 12, 'x');
      const std::uint64_t value = count();
      switch (random() % 4) {
        case 0:
          line.figure(name, value);
          break;
        case 1:
          line.figure(name, std::string(random() % 30, 'v'));
          break;
        case 2:
          line.detail(name, value);
          break;
        default:
          // In one of two groups, or on its own.
          const std::string group =
              random() % 2 == 0 ? "" : "group_" + std::to_string(random() % 2);
          line.problem(name, value, group);
          if (value != 0) problems.push_back({name + "=" + std::to_string(value), group});
      }
    }
    const std::size_t room = 20 + random() % 200;
    const std::string text = line.text(room);
    const std::vector<std::string> left_out = line.left_out(room);
    for (const Shown& shown : problems) {
      // On the line, or summed in its group's figure there and given in full at stop.
      const bool in_sum =
          !shown.group.empty() && text.find(" " + shown.group + "=") != std::string::npos &&
          std::find(left_out.begin(), left_out.end(), shown.problem) != left_out.end();
      EXPECT_TRUE(has(text, shown.problem) || in_sum) << shown.problem << " missing from " << text;
    }
    EXPECT_EQ((" " + text + " ").find("=0 "), std::string::npos) << text;
    // Longer than the room only when the problems, summed by group, are.
    StatusLine problems_only;
    for (const Shown& shown : problems) {
      const std::size_t equals = shown.problem.find('=');
      problems_only.problem(shown.problem.substr(0, equals),
                            std::stoull(shown.problem.substr(equals + 1)), shown.group);
    }
    problems_only.figure("x", "y");  // a figure that never fits: the groups summed
    if (problems_only.text(1).size() <= room) {
      EXPECT_LE(text.size(), room) << text;
    }
  }
}

TEST(StatusLine, TheRoomIsWhatTheLogLinePrefixLeavesOfTheLimit) {
  // The time, "ssl-predictor", "info" and "status: " take their part of the limit.
  EXPECT_GT(info_prefix_chars("ssl-predictor"), std::string("ssl-predictor info").size());
  EXPECT_EQ(status_text_chars("ssl-predictor", "status") + info_prefix_chars("ssl-predictor") +
                std::string("status: ").size(),
            max_status_line_chars);
  EXPECT_EQ(
      status_text_chars("ssl-trainer", "status") - status_text_chars("ssl-predictor", "status"),
      2u);
}

using testing::CapturedLog;

TEST(StatusLine, AtStopWhatDidNotFitFollowsOnLinesOfItsOwn) {
  StatusLine line;
  line.figure("packets", 5000).figure("game", "running");
  std::vector<std::string> details;
  for (int i = 0; i < 30; ++i) {
    details.push_back("detail_number_" + std::to_string(i) + "=" + std::to_string(100000 + i));
    line.detail("detail_number_" + std::to_string(i), 100000 + i);
  }
  const std::size_t prefix = info_prefix_chars("ssl-trainer");
  {
    CapturedLog log("ssl-trainer");
    line.log("status", StatusMoment::periodic);
    const std::vector<std::string> lines = log.lines();
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_TRUE(lines[0].starts_with("status: packets=5000 game=running detail_number_0=100000"))
        << lines[0];
    EXPECT_LE(prefix + lines[0].size(), max_status_line_chars) << lines[0];
  }
  CapturedLog log("ssl-trainer");
  line.log("stopped", StatusMoment::at_stop);
  const std::vector<std::string> lines = log.lines();
  ASSERT_GE(lines.size(), 3u);
  std::string all;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    EXPECT_LE(prefix + lines[i].size(), max_status_line_chars) << lines[i];
    EXPECT_TRUE(lines[i].starts_with(i == 0 ? "stopped: " : "stopped, more: ")) << lines[i];
    all += " " + lines[i].substr(lines[i].find(": ") + 2);
  }
  for (const std::string& detail : details) EXPECT_TRUE(has(all, detail)) << detail;
}

}  // namespace
}  // namespace ssl_formation::app
