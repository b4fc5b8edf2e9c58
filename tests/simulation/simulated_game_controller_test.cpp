#include "ssl_formation/simulation/simulated_game_controller.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <vector>

#include "ssl_formation/match/referee.hpp"

namespace ssl_formation::sim {
namespace {

// Every message of `seconds` of data time, one every `step_s`, as the producer asks for them.
std::vector<Referee> run(GameControllerConfig config, double seconds, double step_s = 2.0) {
  SimulatedGameController game(std::move(config));
  std::vector<Referee> messages;
  for (double t = 0.0; t < seconds; t += step_s) messages.push_back(game.message_at(t));
  return messages;
}

GameControllerConfig short_halves() {
  GameControllerConfig config;
  config.half_s = 120.0;
  config.play_min_s = 10.0;
  config.play_max_s = 30.0;
  return config;
}

bool is_team_command(Referee::Command command, Referee::Command yellow) {
  return command == yellow || command == yellow + 1;
}

TEST(SimulatedGameController, AMatchRunsTwoHalvesWithTheEndsChangedAndThenTheNextMatch) {
  const GameControllerConfig config = short_halves();
  // Two matches: 2 x (4 + 120 + a stoppage's overrun + 2 + 20) s each, and some.
  const std::vector<Referee> messages = run(config, 2 * 2 * 160.0);
  std::vector<Referee::Stage> stages;
  for (const Referee& m : messages) {
    if (stages.empty() || stages.back() != m.stage()) stages.push_back(m.stage());
  }
  const std::vector<Referee::Stage> match{
      Referee::NORMAL_FIRST_HALF_PRE,  Referee::NORMAL_FIRST_HALF,  Referee::NORMAL_HALF_TIME,
      Referee::NORMAL_SECOND_HALF_PRE, Referee::NORMAL_SECOND_HALF, Referee::POST_GAME};
  ASSERT_GE(stages.size(), 2 * match.size());
  for (std::size_t i = 0; i < 2 * match.size(); ++i) {
    EXPECT_EQ(stages[i], match[i % match.size()]) << "stage change " << i;
  }

  // Yellow (the opponent by default) attacks +x in the first half: its goal is on -x, blue's
  // on +x. The teams change ends for the second half and are back for the next match.
  for (const Referee& m : messages) {
    ASSERT_TRUE(m.IsInitialized()) << m.InitializationErrorString();
    ASSERT_TRUE(m.has_blue_team_on_positive_half());
    const bool second_half = m.stage() == Referee::NORMAL_SECOND_HALF_PRE ||
                             m.stage() == Referee::NORMAL_SECOND_HALF ||
                             m.stage() == Referee::POST_GAME;
    EXPECT_EQ(m.blue_team_on_positive_half(), !second_half) << Referee::Stage_Name(m.stage());
    EXPECT_EQ(m.yellow().name(), "Simulated Opponent");
    EXPECT_EQ(m.blue().name(), "ssl-formation");
    EXPECT_EQ(m.source_identifier(), "ssl-producer");
  }
  // Each half starts with a kick-off: the opponent's in the first, ours in the second.
  for (std::size_t i = 1; i < messages.size(); ++i) {
    const Referee& m = messages[i];
    if (m.stage() == messages[i - 1].stage()) continue;
    if (m.stage() == Referee::NORMAL_FIRST_HALF_PRE) {
      EXPECT_EQ(m.command(), Referee::PREPARE_KICKOFF_YELLOW);
    }
    if (m.stage() == Referee::NORMAL_SECOND_HALF_PRE) {
      EXPECT_EQ(m.command(), Referee::PREPARE_KICKOFF_BLUE);
    }
    if (m.stage() == Referee::NORMAL_FIRST_HALF || m.stage() == Referee::NORMAL_SECOND_HALF) {
      EXPECT_EQ(m.command(), Referee::NORMAL_START);
    }
    if (m.stage() == Referee::NORMAL_HALF_TIME || m.stage() == Referee::POST_GAME) {
      EXPECT_EQ(m.command(), Referee::HALT);
      EXPECT_EQ(messages[i - 1].command(), Referee::STOP) << "play ends with a STOP first";
    }
  }
}

TEST(SimulatedGameController, StoppagesRestartAsTheRulesSayAndTheCounterCountsEveryCommand) {
  const std::vector<Referee> messages = run(short_halves(), 6 * 3600.0);
  std::map<Referee::Command, int> commands;
  std::uint32_t goals_seen = 0;
  int running = 0;
  for (std::size_t i = 1; i < messages.size(); ++i) {
    const Referee& before = messages[i - 1];
    const Referee& m = messages[i];
    if (is_running_play(*game_state_of_command(m.command()))) ++running;
    const std::uint32_t score = m.yellow().score() + m.blue().score();
    const std::uint32_t score_before = before.yellow().score() + before.blue().score();
    if (m.command_counter() == before.command_counter()) {
      EXPECT_EQ(m.command(), before.command()) << "a new command without a new counter";
      EXPECT_EQ(m.command_timestamp(), before.command_timestamp());
      EXPECT_EQ(score, score_before);
      continue;
    }
    ASSERT_GT(m.command_counter(), before.command_counter());
    ASSERT_GE(m.command_timestamp(), before.command_timestamp());
    ++commands[m.command()];
    if (score > score_before) {
      ++goals_seen;
      EXPECT_EQ(score, score_before + 1);
      EXPECT_EQ(m.command(), Referee::STOP) << "a goal stops the play";
    }
    // What may follow what, as the rules have it.
    switch (m.command()) {
      case Referee::BALL_PLACEMENT_YELLOW:
      case Referee::BALL_PLACEMENT_BLUE:
        EXPECT_EQ(before.command(), Referee::STOP);
        break;
      case Referee::DIRECT_FREE_YELLOW:
      case Referee::DIRECT_FREE_BLUE:
        EXPECT_TRUE(before.command() == Referee::STOP ||
                    is_team_command(before.command(), Referee::BALL_PLACEMENT_YELLOW));
        if (is_team_command(before.command(), Referee::BALL_PLACEMENT_YELLOW)) {
          EXPECT_EQ(m.command() - Referee::DIRECT_FREE_YELLOW,
                    before.command() - Referee::BALL_PLACEMENT_YELLOW)
              << "the team that placed the ball takes the free kick";
        }
        break;
      case Referee::NORMAL_START:
        EXPECT_TRUE(is_team_command(before.command(), Referee::PREPARE_KICKOFF_YELLOW));
        break;
      case Referee::STOP:
        EXPECT_TRUE(is_running_play(*game_state_of_command(before.command())))
            << Referee::Command_Name(before.command());
        break;
      default:
        break;
    }
  }
  // Six hours of data time: every kind of stoppage happens, and play runs most of the time.
  EXPECT_GT(commands[Referee::BALL_PLACEMENT_YELLOW], 5);
  EXPECT_GT(commands[Referee::BALL_PLACEMENT_BLUE], 5);
  EXPECT_GT(commands[Referee::DIRECT_FREE_YELLOW], 10);
  EXPECT_GT(commands[Referee::DIRECT_FREE_BLUE], 10);
  EXPECT_GT(goals_seen, 5u);
  const double running_share = static_cast<double>(running) / (messages.size() - 1);
  EXPECT_GT(running_share, 0.6);
  EXPECT_LT(running_share, 0.95);
}

TEST(SimulatedGameController, TheRefereeFollowerReadsEveryMessageAndFindsTheOpponentsSides) {
  GameControllerConfig config = short_halves();
  config.opponent_color = TeamColor::blue;
  config.opponent_attacks = AttackDirection::negative_x;
  config.opponent_name = "Rival";
  config.our_name = "Home";
  SimulatedGameController game(config);
  RefereeFollower follower;
  std::set<bool> blue_sides;
  for (double t = 0.0; t < 600.0; t += 0.5) {
    const Referee& message = game.message_at(t);
    follower.add(message.SerializeAsString(), t);
    ASSERT_EQ(follower.view().blue_name, "Rival");
    ASSERT_EQ(follower.view().yellow_name, "Home");
    // Blue attacks -x: its goal is on +x, until the ends change.
    ASSERT_EQ(*follower.view().blue_on_positive_half,
              game.opponent_attacks() == AttackDirection::negative_x);
    ASSERT_EQ(follower.view().state, game.state());
    blue_sides.insert(*follower.view().blue_on_positive_half);
  }
  EXPECT_EQ(blue_sides.size(), 2u) << "the ends change at half time";
  EXPECT_EQ(follower.counters().undecodable, 0u);
  EXPECT_EQ(follower.counters().unknown_command, 0u);
  EXPECT_EQ(follower.counters().other_source, 0u);
  EXPECT_GT(follower.counters().commands, 20u);
}

TEST(SimulatedGameController, TheSameSeedGivesTheSameMessagesAndAnotherSeedOthers) {
  GameControllerConfig config = short_halves();
  config.seed = 5;
  const auto bytes = [](const std::vector<Referee>& messages) {
    std::string all;
    for (const Referee& m : messages) all += m.SerializeAsString();
    return all;
  };
  const std::string first = bytes(run(config, 1000.0));
  EXPECT_EQ(first, bytes(run(config, 1000.0)));
  config.seed = 6;
  EXPECT_NE(first, bytes(run(config, 1000.0)));
}

TEST(SimulatedGameController, ConfigsThatMakeNoMatchAreRefusedAndTimeMayNotGoBack) {
  const auto refused = [](auto change) {
    GameControllerConfig config;
    change(config);
    EXPECT_THROW(SimulatedGameController{config}, std::invalid_argument);
  };
  refused([](GameControllerConfig& c) { c.half_s = 0.0; });
  refused([](GameControllerConfig& c) { c.half_time_s = -1.0; });
  refused([](GameControllerConfig& c) { c.play_min_s = 0.0; });
  refused([](GameControllerConfig& c) { c.play_max_s = c.play_min_s / 2; });
  refused([](GameControllerConfig& c) { c.our_name = " simulated OPPONENT "; });
  SimulatedGameController game{GameControllerConfig{}};
  game.message_at(10.0);
  EXPECT_THROW(game.message_at(9.0), std::invalid_argument);
}

TEST(RefereedSimulation, TheVisionIsTheSeedsOwnAndTheOpponentChangesEndsWithTheReferee) {
  SimulationConfig vision;
  vision.seed = 17;
  GameControllerConfig game = short_halves();
  RefereedSimulation refereed(vision, game);
  SimulatedVision plain(vision);
  int mirrored = 0;
  for (int i = 0; i < 200; ++i) {
    const RefereedFormation step = refereed.next();
    const SimulatedFormation expected = plain.next();
    ASSERT_TRUE(step.referee.has_value());
    EXPECT_EQ(step.referee->packet_timestamp(),
              static_cast<std::uint64_t>(std::llround(expected.t_capture * 1e6)));
    // The same formations, drawn from the vision's own random stream.
    ASSERT_EQ(step.formation.play, expected.play);
    ASSERT_EQ(step.formation.opponent, expected.opponent);
    ASSERT_EQ(step.formation.packets.size(), expected.packets.size());
    // On the wire: the same robots where the opponent attacks +x, mirrored where it attacks -x.
    const bool blue_goal_on_plus_x = step.referee->blue_team_on_positive_half();
    const SSL_DetectionFrame& got = step.formation.packets.back().detection();
    const SSL_DetectionFrame& plain_frame = expected.packets.back().detection();
    ASSERT_EQ(got.robots_yellow_size(), plain_frame.robots_yellow_size());
    for (int r = 0; r < got.robots_yellow_size(); ++r) {
      const SSL_DetectionRobot& p = got.robots_yellow(r);
      const SSL_DetectionRobot& q = plain_frame.robots_yellow(r);
      ASSERT_EQ(p.robot_id(), q.robot_id());
      const float sign = blue_goal_on_plus_x ? 1.0F : -1.0F;
      EXPECT_FLOAT_EQ(p.x(), sign * q.x());
      EXPECT_FLOAT_EQ(p.y(), sign * q.y());
    }
    if (!blue_goal_on_plus_x) ++mirrored;
  }
  // 200 formations of 2 s: the second half is part of them.
  EXPECT_GT(mirrored, 40);
  EXPECT_LT(mirrored, 160);

  RefereedSimulation without(vision, std::nullopt);
  EXPECT_FALSE(without.next().referee.has_value());
  EXPECT_EQ(without.game_controller(), nullptr);
}

}  // namespace
}  // namespace ssl_formation::sim
