// The phase of the game (match/src/game_phase.cpp): whose command, and restarts' first seconds.

#include "ssl_formation/match/game_phase.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation {
namespace {

// The view the referee leaves after `command` (only the command number matters here).
RefereeView view(int command) {
  RefereeView v;
  v.command = command;
  v.state = game_state_of_command(command).value_or(GameState::unknown);
  return v;
}

constexpr double window = GamePhaseTracker::restart_window_s;

TEST(TeamOfCommand, YellowsAreEvenBluesOddAndTheNeutralOnesNone) {
  EXPECT_EQ(team_of_command(Referee::HALT), std::nullopt);
  EXPECT_EQ(team_of_command(Referee::STOP), std::nullopt);
  EXPECT_EQ(team_of_command(Referee::NORMAL_START), std::nullopt);
  EXPECT_EQ(team_of_command(Referee::FORCE_START), std::nullopt);
  for (int command = 4; command <= 17; ++command) {
    SCOPED_TRACE(command);
    ASSERT_TRUE(Referee::Command_IsValid(command));
    const std::string name = Referee::Command_Name(static_cast<Referee::Command>(command));
    const bool yellow = name.ends_with("_YELLOW");
    ASSERT_TRUE(yellow || name.ends_with("_BLUE")) << name;
    EXPECT_EQ(team_of_command(command), yellow ? TeamColor::yellow : TeamColor::blue) << name;
    EXPECT_EQ(yellow, command % 2 == 0);
  }
  // Numbers the wire format does not define are nobody's.
  EXPECT_EQ(team_of_command(-1), std::nullopt);
  EXPECT_EQ(team_of_command(18), std::nullopt);
}

TEST(GamePhase, BeforeAnyCommandPlayRuns) {
  const GamePhaseTracker tracker;
  EXPECT_EQ(tracker.phase(0.0, TeamColor::yellow), GamePhase::running);
  EXPECT_EQ(tracker.phase(1e6, TeamColor::blue), GamePhase::running);
  EXPECT_TRUE(std::isinf(tracker.since_command_s(10.0)));
}

TEST(GamePhase, HaltAndTimeoutsHaltStopAndGoalsStop) {
  for (const int command : {Referee::HALT, Referee::TIMEOUT_YELLOW, Referee::TIMEOUT_BLUE}) {
    GamePhaseTracker tracker;
    tracker.on_command(view(command), 10.0);
    EXPECT_EQ(tracker.phase(10.0, TeamColor::yellow), GamePhase::halt) << command;
    EXPECT_EQ(tracker.phase(100.0, TeamColor::blue), GamePhase::halt) << command;
  }
  for (const int command : {Referee::STOP, Referee::GOAL_YELLOW, Referee::GOAL_BLUE}) {
    GamePhaseTracker tracker;
    tracker.on_command(view(command), 10.0);
    EXPECT_EQ(tracker.phase(10.0, TeamColor::yellow), GamePhase::stop) << command;
    EXPECT_EQ(tracker.phase(100.0, TeamColor::blue), GamePhase::stop) << command;
  }
}

TEST(GamePhase, BallPlacementIsByTheTeamPlacingRelativeToTheOpponent) {
  GamePhaseTracker tracker;
  tracker.on_command(view(Referee::BALL_PLACEMENT_YELLOW), 5.0);
  EXPECT_EQ(tracker.phase(5.0, TeamColor::yellow), GamePhase::ball_placement_opponent);
  EXPECT_EQ(tracker.phase(5.0, TeamColor::blue), GamePhase::ball_placement_us);
  // A placement lasts as long as its command, restart window or not.
  EXPECT_EQ(tracker.phase(5.0 + 2 * window, TeamColor::blue), GamePhase::ball_placement_us);
  tracker.on_command(view(Referee::BALL_PLACEMENT_BLUE), 20.0);
  EXPECT_EQ(tracker.phase(21.0, TeamColor::blue), GamePhase::ball_placement_opponent);
  EXPECT_EQ(tracker.phase(21.0, TeamColor::yellow), GamePhase::ball_placement_us);
}

TEST(GamePhase, AKickoffHoldsFromItsPreparationUntilThreeSecondsAfterNormalStart) {
  GamePhaseTracker tracker;
  tracker.on_command(view(Referee::STOP), 0.0);
  tracker.on_command(view(Referee::PREPARE_KICKOFF_BLUE), 10.0);
  EXPECT_EQ(tracker.phase(10.0, TeamColor::blue), GamePhase::kickoff_opponent);
  EXPECT_EQ(tracker.phase(10.0, TeamColor::yellow), GamePhase::kickoff_us);
  // The preparation may last any time.
  EXPECT_EQ(tracker.phase(30.0, TeamColor::blue), GamePhase::kickoff_opponent);
  tracker.on_command(view(Referee::NORMAL_START), 40.0);
  EXPECT_EQ(tracker.phase(40.0, TeamColor::blue), GamePhase::kickoff_opponent);
  EXPECT_EQ(tracker.phase(42.9, TeamColor::blue), GamePhase::kickoff_opponent);
  EXPECT_EQ(tracker.phase(42.9, TeamColor::yellow), GamePhase::kickoff_us);
  EXPECT_EQ(tracker.phase(40.0 + window, TeamColor::blue), GamePhase::running);
  EXPECT_EQ(tracker.phase(50.0, TeamColor::yellow), GamePhase::running);
  EXPECT_DOUBLE_EQ(tracker.since_command_s(42.5), 2.5);
}

TEST(GamePhase, ForceStartAfterAKickoffPreparationIsTheKickoffToo) {
  GamePhaseTracker tracker;
  tracker.on_command(view(Referee::PREPARE_KICKOFF_YELLOW), 1.0);
  tracker.on_command(view(Referee::FORCE_START), 2.0);
  EXPECT_EQ(tracker.phase(4.5, TeamColor::yellow), GamePhase::kickoff_opponent);
  EXPECT_EQ(tracker.phase(5.5, TeamColor::yellow), GamePhase::running);
}

TEST(GamePhase, AFreeKickIsOneForThreeSecondsThenPlayRuns) {
  GamePhaseTracker tracker;
  tracker.on_command(view(Referee::STOP), 0.0);
  tracker.on_command(view(Referee::DIRECT_FREE_YELLOW), 7.0);
  EXPECT_EQ(tracker.phase(7.0, TeamColor::yellow), GamePhase::free_kick_opponent);
  EXPECT_EQ(tracker.phase(9.9, TeamColor::blue), GamePhase::free_kick_us);
  EXPECT_EQ(tracker.phase(7.0 + window, TeamColor::yellow), GamePhase::running);
  EXPECT_EQ(tracker.phase(20.0, TeamColor::blue), GamePhase::running);
  // The deprecated indirect free kick alike.
  tracker.on_command(view(Referee::INDIRECT_FREE_BLUE), 30.0);
  EXPECT_EQ(tracker.phase(31.0, TeamColor::yellow), GamePhase::free_kick_us);
  EXPECT_EQ(tracker.phase(31.0, TeamColor::blue), GamePhase::free_kick_opponent);
  EXPECT_EQ(tracker.phase(34.0, TeamColor::blue), GamePhase::running);
}

TEST(GamePhase, APenaltyHoldsFromItsPreparationUntilThreeSecondsAfterNormalStart) {
  for (const int prepare : {Referee::PREPARE_PENALTY_YELLOW, Referee::PREPARE_PENALTY_BLUE}) {
    SCOPED_TRACE(prepare);
    GamePhaseTracker tracker;
    tracker.on_command(view(prepare), 100.0);
    EXPECT_EQ(tracker.phase(100.0, TeamColor::yellow), GamePhase::penalty);
    EXPECT_EQ(tracker.phase(110.0, TeamColor::blue), GamePhase::penalty);
    tracker.on_command(view(Referee::NORMAL_START), 120.0);
    EXPECT_EQ(tracker.phase(120.0, TeamColor::yellow), GamePhase::penalty);
    EXPECT_EQ(tracker.phase(122.5, TeamColor::blue), GamePhase::penalty);
    EXPECT_EQ(tracker.phase(123.0, TeamColor::blue), GamePhase::running);
  }
}

TEST(GamePhase, NormalStartAfterStopRunsAtOnce) {
  GamePhaseTracker tracker;
  tracker.on_command(view(Referee::STOP), 0.0);
  tracker.on_command(view(Referee::NORMAL_START), 5.0);
  EXPECT_EQ(tracker.phase(5.0, TeamColor::yellow), GamePhase::running);
  EXPECT_EQ(tracker.phase(5.1, TeamColor::blue), GamePhase::running);
  // A second NORMAL_START after a kick-off's does not make a kick-off of it again.
  tracker.on_command(view(Referee::PREPARE_KICKOFF_YELLOW), 10.0);
  tracker.on_command(view(Referee::NORMAL_START), 11.0);
  tracker.on_command(view(Referee::NORMAL_START), 12.0);
  EXPECT_EQ(tracker.phase(12.0, TeamColor::yellow), GamePhase::running);
}

TEST(GamePhase, SinceCommandCountsFromTheLastCommandAndResetForgetsIt) {
  GamePhaseTracker tracker;
  tracker.on_command(view(Referee::HALT), 3.0);
  EXPECT_DOUBLE_EQ(tracker.since_command_s(3.0), 0.0);
  EXPECT_DOUBLE_EQ(tracker.since_command_s(4.25), 1.25);
  tracker.on_command(view(Referee::STOP), 10.0);
  EXPECT_DOUBLE_EQ(tracker.since_command_s(10.5), 0.5);
  tracker.on_command(view(Referee::PREPARE_KICKOFF_YELLOW), 11.0);
  tracker.reset();
  EXPECT_TRUE(std::isinf(tracker.since_command_s(12.0)));
  EXPECT_EQ(tracker.phase(12.0, TeamColor::yellow), GamePhase::running);
  // After a reset a NORMAL_START follows no preparation.
  tracker.on_command(view(Referee::NORMAL_START), 13.0);
  EXPECT_EQ(tracker.phase(13.0, TeamColor::yellow), GamePhase::running);
}

TEST(GamePhase, EveryPhaseHasItsName) {
  EXPECT_EQ(to_string(GamePhase::running), "running");
  EXPECT_EQ(to_string(GamePhase::ball_placement_opponent), "ball_placement_opponent");
  EXPECT_EQ(to_string(GamePhase::kickoff_us), "kickoff_us");
  EXPECT_EQ(to_string(GamePhase::free_kick_opponent), "free_kick_opponent");
  EXPECT_EQ(to_string(GamePhase::penalty), "penalty");
  for (const GamePhase phase : all_game_phases) EXPECT_NE(to_string(phase), "?");
}

}  // namespace
}  // namespace ssl_formation
