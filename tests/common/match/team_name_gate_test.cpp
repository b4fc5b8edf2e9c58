// When a game controller's new team names take over (match/team_name_gate.hpp): at once the
// first time, after a second of every message saying them later, and at most three times a
// minute.

#include "ssl_formation/match/team_name_gate.hpp"

#include <gtest/gtest.h>

#include <string>

namespace ssl_formation {
namespace {

// The gate and the names it let through, as RefereeFollower keeps them.
struct Followed {
  TeamNameGate gate;
  std::string yellow;
  std::string blue;
  bool say(const std::string& y, const std::string& b, double receive_s) {
    if (!gate.take_over(yellow, blue, y, b, receive_s)) return false;
    yellow = y;
    blue = b;
    return true;
  }
};

TEST(TeamNameGate, TheFirstNamesTakeOverAtOnceAndLaterOnesAfterHoldingASecond) {
  Followed f;
  EXPECT_TRUE(f.say("A", "B", 10.0));
  EXPECT_FALSE(f.say("A", "B", 10.1));  // the names followed
  EXPECT_FALSE(f.say("A", "C", 10.2));
  EXPECT_FALSE(f.say("A", "C", 11.1));  // 0.9 s
  EXPECT_TRUE(f.say("A", "C", 11.2));
  EXPECT_EQ(f.blue, "C");
  EXPECT_EQ(f.gate.refused(), 0u);
}

TEST(TeamNameGate, NamesThatDoNotHoldAreRefusedAndCounted) {
  Followed f;
  ASSERT_TRUE(f.say("A", "B", 0.0));
  EXPECT_FALSE(f.say("X", "Y", 1.0));
  EXPECT_FALSE(f.say("A", "B", 1.5));  // back to the names followed: X/Y did not hold
  EXPECT_FALSE(f.say("X", "Y", 2.0));
  EXPECT_FALSE(f.say("X", "Z", 2.5));  // another pair in between
  EXPECT_FALSE(f.say("X", "Z", 3.4));
  EXPECT_EQ(f.gate.refused(), 2u);
  EXPECT_TRUE(f.say("X", "Z", 3.5));
}

TEST(TeamNameGate, AtMostThreeSwitchesAMinuteAndTheFourthMustHoldAnewAfterTheWindow) {
  Followed f;
  ASSERT_TRUE(f.say("A", "B", 0.0));
  double t = 0.0;
  for (const char* blue : {"C", "D", "E"}) {
    EXPECT_FALSE(f.say("A", blue, t += 1.0));
    EXPECT_TRUE(f.say("A", blue, t += 1.0)) << blue;
  }
  EXPECT_FALSE(f.say("A", "F", t += 1.0));
  EXPECT_FALSE(f.say("A", "F", t += 1.0));  // held, but the fourth switch within 60 s
  EXPECT_EQ(f.gate.refused(), 1u);
  // Still three switches within the minute at 61 s: refused again, and the hold starts anew.
  // The first switch (at 2 s) leaves the window at 62 s, when the names have held a second.
  EXPECT_FALSE(f.say("A", "F", 61.0));
  EXPECT_EQ(f.gate.refused(), 2u);
  EXPECT_TRUE(f.say("A", "F", 62.0));
}

TEST(TeamNameGate, AClockThatGoesBackStartsTheHoldAndTheWindowAnew) {
  Followed f;
  ASSERT_TRUE(f.say("A", "B", 100.0));
  EXPECT_FALSE(f.say("A", "C", 100.5));
  EXPECT_FALSE(f.say("A", "C", 1.0));  // another log: the hold starts here
  EXPECT_FALSE(f.say("A", "C", 1.9));
  EXPECT_TRUE(f.say("A", "C", 2.0));
  f.gate.reset();
  EXPECT_TRUE(f.say("P", "Q", 3.0));  // the first names since reset()
}

}  // namespace
}  // namespace ssl_formation
