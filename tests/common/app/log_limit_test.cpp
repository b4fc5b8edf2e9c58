#include "ssl_formation/app/log_limit.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <sstream>
#include <string>

#include "ssl_vision_wrapper_tracked.pb.h"

namespace ssl_formation::app {
namespace {

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(RepeatKind, NumbersAndQuotedTextDoNotMakeAnotherKind) {
  EXPECT_EQ(repeat_kind("referee: 3 datagrams that are not referee messages (12 in all)"),
            repeat_kind("referee: 1 datagrams that are not referee messages (4767 in all)"));
  EXPECT_EQ(repeat_kind("opponent: 'YYYYYYYY' yellow"), repeat_kind("opponent: 'Them' blue"));
  EXPECT_NE(repeat_kind("referee: a second game controller"),
            repeat_kind("referee: the game controller followed fell silent"));
  EXPECT_LE(repeat_kind(std::string(5000, 'x')).size(), 120U);
}

TEST(CapLine, CutsLongLinesAtACharacterAndSaysByHowMuch) {
  EXPECT_EQ(cap_line("short", 1000), "short");
  const std::string cut = cap_line(std::string(59814, 'Y'), 1000);
  EXPECT_LE(cut.size(), 1000U);
  EXPECT_NE(cut.find("more characters)"), std::string::npos) << cut;
  // Never in the middle of a UTF-8 character (each "é" is two bytes).
  std::string accents;
  for (int i = 0; i < 600; ++i) accents += "é";
  const std::string cut_accents = cap_line(accents, 101);
  const std::string kept = cut_accents.substr(0, cut_accents.find("…"));
  EXPECT_EQ(kept.size() % 2, 0U);
}

TEST(RepeatLimiter, WritesABurstPerPeriodThenSummarisesWhatItLeftOut) {
  RepeatLimiter limiter(LogLimitSettings{5, 60.0, 1000, 512});
  int written = 0;
  for (int i = 0; i < 4767; ++i) written += limiter.admit("referee: # datagrams", i * 0.004);
  EXPECT_EQ(written, 5);
  EXPECT_TRUE(limiter.due(30.0).empty());  // the period is not over
  const auto summaries = limiter.due(61.0);
  ASSERT_EQ(summaries.size(), 1U);
  EXPECT_EQ(summaries[0].kind, "referee: # datagrams");
  EXPECT_EQ(summaries[0].left_out, 4762U);
  // The next period writes its burst again.
  EXPECT_TRUE(limiter.admit("referee: # datagrams", 61.5));
  EXPECT_TRUE(limiter.due(62.0).empty());
  // Another kind has its own burst.
  EXPECT_TRUE(limiter.admit("tracker: #", 62.0));
}

TEST(RepeatLimiter, ManyKindsShareOneWindowBeyondTheLimit) {
  RepeatLimiter limiter(LogLimitSettings{2, 60.0, 1000, 4});
  int written = 0;
  for (int i = 0; i < 1000; ++i)
    written += limiter.admit("kind " + std::to_string(i * 7) + "x" + std::string(i % 50, 'a'), 1.0);
  // Four kinds of their own (2 lines each at most) and the rest sharing one (2 lines).
  EXPECT_LE(written, 4 * 2 + 2);
}

TEST(LimitedSink, AFloodOfOneWarningBecomesABurstAndASummaryAndLibprotobufGoesThroughIt) {
  std::ostringstream out;
  auto target = std::make_shared<spdlog::sinks::ostream_sink_mt>(out);
  // A period long enough for a slow (sanitised, busy) machine to write the flood within it.
  auto clock = std::make_shared<ManualClock>();
  auto sink = std::make_shared<LimitedSink>(target, LogLimitSettings{5, 1.0, 1000, 512}, clock);
  auto logger = std::make_shared<spdlog::logger>("test", sink);
  logger->set_pattern("%n %l: %v");
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(logger);
  route_protobuf_log();
  for (int i = 0; i < 1000; ++i) {
    spdlog::warn("referee: 1 datagrams that are not referee messages ({} in all)", i + 1);
  }
  // A tracker packet without its required uuid: libprotobuf logs an error of its own.
  TrackerWrapperPacket packet;
  for (int i = 0; i < 200; ++i) EXPECT_FALSE(packet.ParseFromString(std::string()));
  spdlog::info("opponent: '{}'", std::string(59814, 'Y'));
  clock->advance(1.1);
  spdlog::info("status: after the period");
  spdlog::set_default_logger(previous);
  google::protobuf::SetLogHandler(nullptr);

  const std::string text = out.str();
  EXPECT_EQ(count_of(text, "datagrams that are not referee messages"), 5U + 1U) << text;
  EXPECT_NE(text.find("995 more lines like 'referee: # datagrams that are not referee messages"),
            std::string::npos)
      << text;
  EXPECT_EQ(count_of(text, "test warning: protobuf: Can't parse message of type"), 5U) << text;
  EXPECT_NE(text.find("195 more lines like 'protobuf: Can"), std::string::npos) << text;
  // No line over 1,000 characters.
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    EXPECT_LE(line.size(), 1000U) << line.substr(0, 80);
  EXPECT_NE(text.find("status: after the period"), std::string::npos);
}

TEST(LimitedSink, WhatIsLeftOutInTheLastPeriodIsSaidAtExitAndErrorsAreNeverLeftOut) {
  std::ostringstream out;
  {
    auto target = std::make_shared<spdlog::sinks::ostream_sink_mt>(out);
    auto sink = std::make_shared<LimitedSink>(target, LogLimitSettings{2, 3600.0, 1000, 512});
    spdlog::logger logger("test", sink);
    logger.set_pattern("%l: %v");
    for (int i = 0; i < 10; ++i) logger.warn("tracker: {} packets of another tracker", i);
    for (int i = 0; i < 12; ++i) logger.error("cannot open logs/2024-07-0{}_match.log.gz", i % 10);
  }  // the sink goes with the program
  const std::string text = out.str();
  EXPECT_EQ(count_of(text, "packets of another tracker"), 2U + 1U) << text;
  EXPECT_NE(text.find("8 more lines like 'tracker: # packets of another tracker"),
            std::string::npos)
      << text;
  EXPECT_EQ(count_of(text, "error: cannot open logs/"), 12U) << text;
}

}  // namespace
}  // namespace ssl_formation::app
