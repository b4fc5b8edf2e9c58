// The referee feed (common/match/src/referee.cpp): real Referee messages, serialised as the game
// controller sends them, followed from one game controller; bad input is counted, never thrown.

#include "ssl_formation/match/referee.hpp"

#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <optional>
#include <string>

#include "ssl_gc_referee_message.pb.h"

namespace sf = ssl_formation;

namespace {

Referee::TeamInfo team(const std::string& name) {
  Referee::TeamInfo info;
  info.set_name(name);
  info.set_score(0);
  info.set_red_cards(0);
  info.set_yellow_cards(0);
  info.set_timeouts(4);
  info.set_timeout_time(300000000);
  info.set_goalkeeper(0);
  return info;
}

// A complete message, as a game controller sends it.
Referee message(Referee::Command command, std::uint32_t counter, const std::string& source = "gc-a",
                const std::string& yellow = "TIGERs Mannheim",
                const std::string& blue = "ER-Force") {
  Referee m;
  m.set_packet_timestamp(1700000000000000);
  m.set_stage(Referee::NORMAL_FIRST_HALF);
  m.set_command(command);
  m.set_command_counter(counter);
  m.set_command_timestamp(1700000000000000);
  *m.mutable_yellow() = team(yellow);
  *m.mutable_blue() = team(blue);
  m.set_source_identifier(source);
  return m;
}

std::string bytes(const Referee& m) {
  EXPECT_TRUE(m.IsInitialized());
  return m.SerializeAsString();
}

// The message with command number `command`, which the schema may not define (field 4, varint).
std::string with_raw_command(Referee m, unsigned char command) {
  m.clear_command();
  std::string out = m.SerializePartialAsString();
  out += '\x20';  // field 4, wire type 0
  out += static_cast<char>(command);
  return out;
}

TEST(RefereeCommand, EveryCommandNumberLeavesTheDocumentedStateAndOthersNone) {
  using enum sf::GameState;
  // clang-format off
  const std::array<sf::GameState, 18> documented{
      halt,                 // 0 HALT
      stop,                 // 1 STOP
      running,              // 2 NORMAL_START
      running,              // 3 FORCE_START
      kickoff_preparation,  // 4 PREPARE_KICKOFF_YELLOW
      kickoff_preparation,  // 5 PREPARE_KICKOFF_BLUE
      penalty_preparation,  // 6 PREPARE_PENALTY_YELLOW
      penalty_preparation,  // 7 PREPARE_PENALTY_BLUE
      free_kick,            // 8 DIRECT_FREE_YELLOW
      free_kick,            // 9 DIRECT_FREE_BLUE
      free_kick,            // 10 INDIRECT_FREE_YELLOW (deprecated)
      free_kick,            // 11 INDIRECT_FREE_BLUE (deprecated)
      timeout,              // 12 TIMEOUT_YELLOW
      timeout,              // 13 TIMEOUT_BLUE
      stop,                 // 14 GOAL_YELLOW (deprecated)
      stop,                 // 15 GOAL_BLUE (deprecated)
      ball_placement,       // 16 BALL_PLACEMENT_YELLOW
      ball_placement,       // 17 BALL_PLACEMENT_BLUE
  };
  // clang-format on
  for (int command = 0; command < 18; ++command) {
    SCOPED_TRACE(command);
    const sf::GameState expected = documented[static_cast<std::size_t>(command)];
    EXPECT_EQ(sf::game_state_of_command(command), expected);
    sf::RefereeFollower referee;
    referee.add(bytes(message(static_cast<Referee::Command>(command), 1)), 1.0);
    EXPECT_EQ(referee.view().state, expected);
    EXPECT_EQ(referee.view().command, command);
  }
  EXPECT_EQ(sf::game_state_of_command(-1), std::nullopt);
  EXPECT_EQ(sf::game_state_of_command(18), std::nullopt);
  EXPECT_EQ(sf::game_state_of_command(99), std::nullopt);
}

TEST(RefereeCommand, OnlyRunningAndFreeKickAreRunningPlayAndNamesRoundTrip) {
  for (int i = 0; i < sf::game_state_count; ++i) {
    const auto state = static_cast<sf::GameState>(i);
    SCOPED_TRACE(sf::to_string(state));
    EXPECT_EQ(sf::is_running_play(state),
              state == sf::GameState::running || state == sf::GameState::free_kick);
    EXPECT_EQ(sf::parse_game_state(sf::to_string(state)), state);
  }
  EXPECT_EQ(sf::parse_game_state("playing"), std::nullopt);
}

TEST(RefereeFollower, ANewCommandIsReportedOnceAndItsRepeatsAreNot) {
  sf::RefereeFollower referee;
  EXPECT_FALSE(referee.heard());
  const sf::RefereeChange first = referee.add(bytes(message(Referee::HALT, 1)), 10.0);
  EXPECT_TRUE(first.command);
  EXPECT_TRUE(first.teams);  // from nothing to the two names
  EXPECT_TRUE(referee.heard());
  EXPECT_EQ(referee.view().source, "gc-a");
  EXPECT_EQ(referee.view().stage, Referee::NORMAL_FIRST_HALF);
  for (int i = 1; i <= 3; ++i) {
    const sf::RefereeChange repeat = referee.add(bytes(message(Referee::HALT, 1)), 10.0 + 0.1 * i);
    EXPECT_FALSE(repeat.any());
  }
  const sf::RefereeChange start = referee.add(bytes(message(Referee::NORMAL_START, 2)), 11.0);
  EXPECT_TRUE(start.command);
  EXPECT_FALSE(start.teams);
  EXPECT_EQ(referee.view().state, sf::GameState::running);
  EXPECT_EQ(referee.counters().messages, 5u);
  EXPECT_EQ(referee.counters().used, 5u);
  EXPECT_EQ(referee.counters().commands, 2u);
}

TEST(RefereeFollower, ANewCounterWithTheSameCommandIsANewCommand) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::STOP, 7)), 1.0);
  EXPECT_FALSE(referee.add(bytes(message(Referee::STOP, 7)), 1.1).command);
  EXPECT_TRUE(referee.add(bytes(message(Referee::STOP, 8)), 1.2).command);
  EXPECT_EQ(referee.view().command_counter, 8u);
  EXPECT_EQ(referee.counters().commands, 2u);
}

TEST(RefereeFollower, ATeamNameChangeIsReported) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::STOP, 1, "gc-a", "", "")), 1.0);
  const sf::RefereeChange named =
      referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B")), 1.1);
  EXPECT_TRUE(named.teams);
  EXPECT_FALSE(named.command);
  EXPECT_EQ(referee.view().yellow_name, "Y");
  EXPECT_EQ(referee.view().blue_name, "B");
  EXPECT_FALSE(referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B")), 1.2).teams);
  // Other names take over once they have held for a second of messages.
  EXPECT_FALSE(referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B2")), 1.3).teams);
  EXPECT_FALSE(referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B2")), 2.0).teams);
  EXPECT_EQ(referee.view().blue_name, "B");
  EXPECT_TRUE(referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B2")), 2.4).teams);
  EXPECT_EQ(referee.view().blue_name, "B2");
  EXPECT_EQ(referee.counters().refused_name_switches, 0u);
}

TEST(RefereeFollower, SpoofedNamesBetweenTheRealOnesNeverTakeOverAndSwitchesAreRateLimited) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B")), 0.0);
  // 10 s of the real names at 10 Hz, each followed by a spoofed one (a new name every time).
  double t = 0.0;
  for (int i = 0; i < 100; ++i) {
    t += 0.05;
    EXPECT_FALSE(referee.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B")), t).teams);
    t += 0.05;
    EXPECT_FALSE(referee
                     .add(bytes(message(Referee::STOP, 1, "gc-a", "Y",
                                        std::string("spoof").append(std::to_string(i)))),
                          t)
                     .teams);
  }
  EXPECT_EQ(referee.view().blue_name, "B");
  EXPECT_GE(referee.counters().refused_name_switches, 99u);
  // Names that really change, one after the other, every 2 s: three take over within the
  // minute, the fourth waits for the window.
  sf::RefereeFollower changing;
  changing.add(bytes(message(Referee::STOP, 1, "gc-a", "Y", "B0")), 0.0);
  int switches = 0;
  for (int k = 1; k <= 4; ++k) {
    for (double s = 0.0; s < 2.0; s += 0.1) {
      switches += changing
                      .add(bytes(message(Referee::STOP, 1, "gc-a", "Y",
                                         std::string("B").append(std::to_string(k)))),
                           2.0 * k + s)
                      .teams;
    }
  }
  EXPECT_EQ(switches, 3);
  EXPECT_EQ(changing.view().blue_name, "B3");
  EXPECT_GE(changing.counters().refused_name_switches, 1u);
}

TEST(RefereeFollower, SidesChangeOnlyWhenTheFieldIsGivenAndDiffers) {
  sf::RefereeFollower referee;
  Referee m = message(Referee::STOP, 1);
  EXPECT_FALSE(referee.add(bytes(m), 1.0).sides);  // an older game controller says nothing
  EXPECT_EQ(referee.view().blue_on_positive_half, std::nullopt);
  m.set_blue_team_on_positive_half(true);
  EXPECT_TRUE(referee.add(bytes(m), 1.1).sides);
  EXPECT_EQ(referee.view().blue_on_positive_half, true);
  EXPECT_FALSE(referee.add(bytes(m), 1.2).sides);
  m.clear_blue_team_on_positive_half();
  EXPECT_FALSE(referee.add(bytes(m), 1.3).any());  // silence keeps the last word
  EXPECT_EQ(referee.view().blue_on_positive_half, true);
  m.set_blue_team_on_positive_half(false);
  const sf::RefereeChange half_time = referee.add(bytes(m), 1.4);
  EXPECT_TRUE(half_time.sides && half_time.any());
  EXPECT_EQ(referee.view().blue_on_positive_half, false);
}

TEST(RefereeFollower, ASecondSourceWhileTheFirstTalksIsCountedNotUsed) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::HALT, 1, "gc-a")), 10.0);
  const sf::RefereeChange b1 =
      referee.add(bytes(message(Referee::FORCE_START, 40, "gc-b", "X", "Z")), 10.5);
  EXPECT_TRUE(b1.conflict);
  EXPECT_FALSE(b1.any());
  EXPECT_FALSE(referee.add(bytes(message(Referee::FORCE_START, 40, "gc-b")), 10.6).conflict);
  EXPECT_TRUE(referee.add(bytes(message(Referee::STOP, 3, "gc-c")), 10.7).conflict);
  EXPECT_EQ(referee.counters().other_source, 3u);
  EXPECT_EQ(referee.counters().used, 1u);
  EXPECT_EQ(referee.counters().source_switches, 0u);
  const sf::RefereeView& view = referee.view();
  EXPECT_EQ(view.source, "gc-a");
  EXPECT_EQ(view.state, sf::GameState::halt);
  EXPECT_EQ(view.yellow_name, "TIGERs Mannheim");
  // The first still speaks (within the timeout of its last message) and is still followed.
  const sf::RefereeChange a = referee.add(bytes(message(Referee::STOP, 2, "gc-a")), 11.9);
  EXPECT_TRUE(a.command);
  EXPECT_FALSE(a.conflict);
  EXPECT_EQ(referee.view().state, sf::GameState::stop);
}

TEST(RefereeFollower, AfterTheFollowedSourceFallsSilentAnotherTakesOver) {
  sf::RefereeFollower referee(0.5);
  referee.add(bytes(message(Referee::STOP, 5, "gc-a")), 10.0);
  EXPECT_TRUE(referee.add(bytes(message(Referee::STOP, 5, "gc-b")), 10.4).conflict);
  // Same command and counter as gc-a's, but another game controller's: a new command.
  const sf::RefereeChange takeover = referee.add(bytes(message(Referee::STOP, 5, "gc-b")), 10.6);
  EXPECT_TRUE(takeover.source);
  EXPECT_TRUE(takeover.command);
  EXPECT_EQ(referee.view().source, "gc-b");
  EXPECT_EQ(referee.counters().source_switches, 1u);
  EXPECT_EQ(referee.counters().commands, 2u);
  EXPECT_EQ(referee.counters().other_source, 1u);
  // Now gc-a is the second one.
  EXPECT_TRUE(referee.add(bytes(message(Referee::HALT, 6, "gc-a")), 10.7).conflict);
  EXPECT_EQ(referee.view().state, sf::GameState::stop);
}

TEST(RefereeFollower, AnUnknownCommandNumberIsCountedAndChangesNothing) {
  sf::RefereeFollower referee;
  Referee unknown = message(Referee::HALT, 9, "gc-a", "Other", "Names");
  unknown.set_blue_team_on_positive_half(true);
  const std::string payload = with_raw_command(unknown, 99);
  EXPECT_FALSE(referee.add(payload, 1.0).any());  // as the first message
  EXPECT_FALSE(referee.heard());
  referee.add(bytes(message(Referee::HALT, 1)), 2.0);
  const sf::RefereeChange change = referee.add(payload, 2.1);
  EXPECT_FALSE(change.any());
  EXPECT_FALSE(change.conflict);
  EXPECT_EQ(referee.counters().unknown_command, 2u);
  EXPECT_EQ(referee.counters().used, 1u);
  EXPECT_EQ(referee.counters().messages, 3u);
  EXPECT_EQ(referee.view().command, Referee::HALT);
  EXPECT_EQ(referee.view().command_counter, 1u);
  EXPECT_EQ(referee.view().yellow_name, "TIGERs Mannheim");
  EXPECT_EQ(referee.view().blue_on_positive_half, std::nullopt);
}

// An unknown command says nothing usable whoever sends it: no conflict, and no switch counted
// for a message that was not used (the switch comes with the new source's first good one).
TEST(RefereeFollower, AnUnknownCommandFromAnotherSourceIsNeitherConflictNorSwitch) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::HALT, 1, "gc-a")), 0.0);
  EXPECT_FALSE(referee.add(with_raw_command(message(Referee::HALT, 1, "gc-b"), 99), 0.5).conflict);
  EXPECT_EQ(referee.counters().other_source, 0u);
  referee.add(with_raw_command(message(Referee::HALT, 1, "gc-b"), 99), 5.0);
  EXPECT_EQ(referee.view().source, "gc-a");
  EXPECT_EQ(referee.counters().unknown_command, 2u);
  EXPECT_EQ(referee.counters().source_switches, 0u);
  EXPECT_TRUE(referee.add(bytes(message(Referee::STOP, 2, "gc-b")), 5.1).source);
  EXPECT_EQ(referee.counters().source_switches, 1u);
}

TEST(RefereeFollower, GarbageIsCountedUndecodableAndNeverThrows) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::FORCE_START, 3)), 1.0);
  const std::string whole = bytes(message(Referee::STOP, 4));
  const std::array<std::string, 5> garbage{
      std::string("\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff", 11),  // an endless varint
      std::string("\x08", 1),                                           // a tag, no value
      std::string("\x00\x01", 2),                                       // field number 0
      std::string("\x0f\x01", 2),                                       // wire type 7
      whole.substr(0, whole.size() - 3),                                // cut in a name
  };
  for (std::size_t i = 0; i < garbage.size(); ++i) {
    SCOPED_TRACE(i);
    sf::RefereeChange change;
    EXPECT_NO_THROW(change = referee.add(garbage[i], 1.1 + 0.01 * static_cast<double>(i)));
    EXPECT_FALSE(change.any());
    EXPECT_FALSE(change.conflict);
  }
  EXPECT_EQ(referee.counters().undecodable, garbage.size());
  EXPECT_EQ(referee.counters().messages, garbage.size() + 1);
  EXPECT_EQ(referee.counters().used, 1u);
  EXPECT_EQ(referee.view().state, sf::GameState::running);
}

TEST(RefereeFollower, MessagesNamingNeitherTeamAreCountedButUsed) {
  sf::RefereeFollower referee;
  const sf::RefereeChange change =
      referee.add(bytes(message(Referee::NORMAL_START, 1, "", "", "")), 1.0);
  EXPECT_TRUE(change.command);
  EXPECT_FALSE(change.teams);  // nothing named, as before
  EXPECT_EQ(referee.view().state, sf::GameState::running);
  EXPECT_EQ(referee.view().source, "");
  referee.add(bytes(message(Referee::NORMAL_START, 1, "", "Y", "")), 1.1);  // one named: not
  EXPECT_EQ(referee.counters().unnamed_teams, 1u);
  EXPECT_EQ(referee.counters().used, 2u);
}

TEST(RefereeFollower, ResetForgetsTheViewButKeepsTheCounters) {
  sf::RefereeFollower referee;
  Referee m = message(Referee::DIRECT_FREE_BLUE, 12, "gc-a");
  m.set_blue_team_on_positive_half(false);
  referee.add(bytes(m), 1.0);
  referee.add(bytes(message(Referee::STOP, 1, "gc-b")), 1.1);
  referee.reset();
  EXPECT_FALSE(referee.heard());
  const sf::RefereeView& view = referee.view();
  EXPECT_EQ(view.state, sf::GameState::unknown);
  EXPECT_EQ(view.command, -1);
  EXPECT_EQ(view.stage, -1);
  EXPECT_EQ(view.yellow_name + view.blue_name + view.source, "");
  EXPECT_EQ(view.blue_on_positive_half, std::nullopt);
  EXPECT_EQ(referee.counters().messages, 2u);
  // Any game controller is followed afresh, at once, without counting a switch.
  const sf::RefereeChange next = referee.add(bytes(message(Referee::STOP, 1, "gc-b")), 1.2);
  EXPECT_TRUE(next.command);
  EXPECT_FALSE(next.source);
  EXPECT_FALSE(next.conflict);
  EXPECT_EQ(referee.view().source, "gc-b");
  EXPECT_EQ(referee.counters().source_switches, 0u);
  EXPECT_EQ(referee.counters().commands, 2u);
}

TEST(RefereeFollower, DescribeNamesTheStateTheStageTheTeamsAndTheSides) {
  sf::RefereeFollower referee;
  EXPECT_EQ(sf::describe(referee), "no referee heard");
  Referee m = message(Referee::BALL_PLACEMENT_BLUE, 1);
  m.set_stage(Referee::NORMAL_SECOND_HALF);
  m.set_blue_team_on_positive_half(true);
  referee.add(bytes(m), 1.0);
  const std::string text = sf::describe(referee);
  EXPECT_NE(text.find("ball_placement"), std::string::npos) << text;
  EXPECT_NE(text.find("NORMAL_SECOND_HALF"), std::string::npos) << text;
  EXPECT_NE(text.find("'TIGERs Mannheim'"), std::string::npos) << text;
  EXPECT_NE(text.find("'ER-Force'"), std::string::npos) << text;
  EXPECT_NE(text.find("+x"), std::string::npos) << text;
  m.set_blue_team_on_positive_half(false);
  referee.add(bytes(m), 1.1);
  EXPECT_NE(sf::describe(referee).find("-x"), std::string::npos) << sf::describe(referee);
}

TEST(RefereeFollower, TheDesignatedPositionIsTheLastUsedMessages) {
  sf::RefereeFollower referee;
  EXPECT_EQ(referee.view().designated_position, std::nullopt);
  Referee placement = message(Referee::BALL_PLACEMENT_YELLOW, 4);
  placement.mutable_designated_position()->set_x(-1250.5F);
  placement.mutable_designated_position()->set_y(875.0F);
  referee.add(bytes(placement), 1.0);
  ASSERT_TRUE(referee.view().designated_position.has_value());
  EXPECT_EQ(referee.view().designated_position->x, -1250.5);
  EXPECT_EQ(referee.view().designated_position->y, 875.0);
  // Repeats of the command carry it on, and a moved target moves it (no new command).
  placement.mutable_designated_position()->set_x(-1000.0F);
  EXPECT_FALSE(referee.add(bytes(placement), 1.1).any());
  EXPECT_EQ(referee.view().designated_position->x, -1000.0);
  // A message from a second game controller changes nothing.
  Referee other = message(Referee::BALL_PLACEMENT_BLUE, 9, "gc-b");
  other.mutable_designated_position()->set_x(3000.0F);
  other.mutable_designated_position()->set_y(3000.0F);
  referee.add(bytes(other), 1.2);
  EXPECT_EQ(referee.view().designated_position->x, -1000.0);
  // The next message without one has none.
  referee.add(bytes(message(Referee::STOP, 5)), 1.3);
  EXPECT_EQ(referee.view().designated_position, std::nullopt);
  // Nor has one with a target that is not finite, or lacks a coordinate.
  placement.set_command_counter(6);
  placement.mutable_designated_position()->set_x(std::numeric_limits<float>::infinity());
  referee.add(bytes(placement), 1.4);
  EXPECT_EQ(referee.view().state, sf::GameState::ball_placement);
  EXPECT_EQ(referee.view().designated_position, std::nullopt);
  placement.mutable_designated_position()->clear_x();
  referee.add(placement.SerializePartialAsString(), 1.5);
  EXPECT_EQ(referee.view().state, sf::GameState::ball_placement);
  EXPECT_EQ(referee.view().designated_position, std::nullopt);
  // reset() forgets it.
  placement.mutable_designated_position()->set_x(10.0F);
  referee.add(bytes(placement), 1.6);
  EXPECT_TRUE(referee.view().designated_position.has_value());
  referee.reset();
  EXPECT_EQ(referee.view().designated_position, std::nullopt);
}

}  // namespace

namespace {

// The message as the followed game controller sends it `seconds` after the first, at stage
// `stage`.
Referee at(Referee m, double seconds, Referee::Stage stage = Referee::NORMAL_FIRST_HALF) {
  m.set_packet_timestamp(1700000000000000 + static_cast<std::uint64_t>(seconds * 1e6));
  m.set_stage(stage);
  return m;
}

TEST(RefereeFollower, AReplayedOrStaleMessageOfTheFollowedSourceChangesNothing) {
  sf::RefereeFollower referee;
  const Referee kickoff = at(message(Referee::PREPARE_KICKOFF_YELLOW, 3), 0.0);
  referee.add(bytes(kickoff), 100.0);
  referee.add(bytes(at(message(Referee::NORMAL_START, 4), 5.0)), 105.0);
  referee.add(bytes(at(message(Referee::STOP, 9), 60.0)), 160.0);
  ASSERT_EQ(referee.view().state, sf::GameState::stop);
  // The kick-off's message sent again a minute later, as it was (counter 3, its old timestamp),
  // and with a fresh timestamp (the counter still goes back).
  const sf::RefereeChange replay = referee.add(bytes(kickoff), 160.1);
  EXPECT_TRUE(replay.stale);
  EXPECT_FALSE(replay.any());
  EXPECT_TRUE(referee.add(bytes(at(kickoff, 60.1)), 160.2).stale);
  // A counter that is current but a timestamp 2 s back: stale too.
  EXPECT_TRUE(referee.add(bytes(at(message(Referee::HALT, 9), 58.0)), 160.3).stale);
  // A timestamp far ahead of the game controller's clock: forged, and it would lock the real
  // one out if it were taken.
  EXPECT_TRUE(referee.add(bytes(at(message(Referee::HALT, 10), 3600.0)), 160.4).stale);
  EXPECT_EQ(referee.view().state, sf::GameState::stop);
  EXPECT_EQ(referee.view().command_counter, 9u);
  // A message of the stage before, replayed with its own timestamp less than a second old:
  // its counter goes back, and it is no restart, since its timestamp goes back too.
  EXPECT_TRUE(referee
                  .add(bytes(at(message(Referee::PREPARE_KICKOFF_YELLOW, 2), 59.5,
                                Referee::NORMAL_FIRST_HALF_PRE)),
                       160.5)
                  .stale);
  EXPECT_EQ(referee.counters().stale, 5u);
  // The game controller goes on: used.
  const sf::RefereeChange next =
      referee.add(bytes(at(message(Referee::NORMAL_START, 10), 61.0)), 161.0);
  EXPECT_TRUE(next.command);
  EXPECT_FALSE(next.stale);
  EXPECT_EQ(referee.view().state, sf::GameState::running);
  EXPECT_EQ(referee.counters().used, 4u);
}

TEST(RefereeFollower, ARestartedGameControllerIsFollowedAfterASilenceOrInANewStage) {
  sf::RefereeFollower referee;
  referee.add(bytes(at(message(Referee::STOP, 40), 0.0)), 10.0);
  // Restarted 3 s later (longer than the source timeout): its counter starts again.
  const sf::RefereeChange restarted = referee.add(bytes(at(message(Referee::HALT, 0), 3.0)), 13.0);
  EXPECT_FALSE(restarted.stale);
  EXPECT_EQ(referee.view().state, sf::GameState::halt);
  EXPECT_EQ(referee.view().command_counter, 0u);
  // Restarted at once, in the next stage: followed too.
  referee.add(bytes(at(message(Referee::STOP, 12), 4.0)), 14.0);
  const sf::RefereeChange next_stage =
      referee.add(bytes(at(message(Referee::HALT, 1), 4.5, Referee::NORMAL_HALF_TIME)), 14.5);
  EXPECT_FALSE(next_stage.stale);
  EXPECT_EQ(referee.view().state, sf::GameState::halt);
  EXPECT_EQ(referee.counters().stale, 0u);
}

TEST(RefereeFollower, NamesFromTheWireAreShortAndPrintable) {
  sf::RefereeFollower referee;
  referee.add(bytes(message(Referee::HALT, 1, "gc\n-a", std::string(59814, 'Y'), "Blue\x1b[2J")),
              1.0);
  std::string cut(64, 'Y');
  cut += "…(59814 bytes)";
  EXPECT_EQ(referee.view().yellow_name, cut);
  EXPECT_EQ(referee.view().blue_name, "Blue\\u{001B}[2J");
  EXPECT_EQ(referee.view().source, "gc\\u{000A}-a");
  EXPECT_LT(sf::describe(referee).size(), 250u) << sf::describe(referee);
  // The same source still: the next message is used, not a second game controller.
  EXPECT_TRUE(referee.add(bytes(message(Referee::STOP, 2, "gc\n-a")), 1.1).command);
}

}  // namespace

namespace {

TEST(RefereeFollower, AForgedMessageRunningAheadLocksTheGameControllerOutForASecondAtMost) {
  sf::RefereeFollower referee;
  // The real game controller at 10 Hz in running play (counter 5); every 1.9 s a forged HALT in
  // its name with a higher counter and a current timestamp.
  int real_used = 0;
  int real_sent = 0;
  for (int i = 0; i < 300; ++i) {
    const double t = 0.1 * i;
    const sf::RefereeChange real =
        referee.add(bytes(at(message(Referee::NORMAL_START, 5), t)), 100.0 + t);
    ++real_sent;
    real_used += real.stale ? 0 : 1;
    if (i % 19 == 0 && i > 0) {
      referee.add(bytes(at(message(Referee::HALT, 6 + static_cast<std::uint32_t>(i)), t + 0.05)),
                  100.0 + t + 0.05);
    }
  }
  // Each forgery holds for three real messages.
  EXPECT_GE(real_used, real_sent * 8 / 10);
  EXPECT_GE(referee.counters().resyncs, 15u);
  EXPECT_EQ(referee.view().state, sf::GameState::running);
}

TEST(RefereeFollower, AReplayHeardFirstOrALogStartingOverGivesWayToTheNewestClock) {
  // An hour-old replay heard first, then the real game controller beside it, both at 10 Hz.
  sf::RefereeFollower referee;
  int real_used_late = 0;
  for (int i = 0; i < 100; ++i) {
    const double t = 0.1 * i;
    referee.add(bytes(at(message(Referee::HALT, 3), 3600.0 + t)), 10.0 + t);
    const sf::RefereeChange real =
        referee.add(bytes(at(message(Referee::NORMAL_START, 40), 7200.0 + t)), 10.0 + t + 0.01);
    if (i >= 20) real_used_late += real.stale ? 0 : 1;
  }
  EXPECT_EQ(real_used_late, 80);  // followed within 2 s, for good
  EXPECT_EQ(referee.view().state, sf::GameState::running);
  EXPECT_EQ(referee.counters().resyncs, 1u);
  // A log that loops: its clock goes back by ten minutes, and nothing else is heard.
  sf::RefereeFollower looping;
  for (int i = 0; i < 50; ++i)
    looping.add(bytes(at(message(Referee::STOP, 100), 600.0 + 0.1 * i)), 0.1 * i);
  int used_after_loop = 0;
  for (int i = 0; i < 30; ++i) {
    used_after_loop +=
        looping.add(bytes(at(message(Referee::HALT, 1), 0.1 * i)), 5.0 + 0.1 * i).stale ? 0 : 1;
  }
  EXPECT_GE(used_after_loop, 10);  // once nothing was used for 2 s
  EXPECT_EQ(looping.view().state, sf::GameState::halt);
}

}  // namespace
