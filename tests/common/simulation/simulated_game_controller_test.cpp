#include "ssl_formation/simulation/simulated_game_controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <vector>

#include "ssl_formation/match/referee.hpp"

namespace ssl_formation::simulation {
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

// The plain game of earlier versions, which the paper's opponent plays.
GameControllerConfig plain(GameControllerConfig config) {
  config.shape.reset();
  return config;
}

bool is_team_command(Referee::Command command, Referee::Command yellow) {
  return command == yellow || command == yellow + 1;
}

void expect_two_halves_and_the_next_match(const GameControllerConfig& config) {
  // Two matches: 2 x (8 + 4 + 120 + a stoppage's overrun + 2 + 20) s each, and some.
  const std::vector<Referee> messages = run(config, 2 * 2 * 170.0, 0.25);
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
  // Each half starts with a kick-off: the opponent's in the first, ours in the second. After a
  // break the teams first walk to their places, in a STOP; the first match starts lined up.
  std::map<int, std::vector<Referee::Command>> before_kickoff;  // by the stage's start
  int pre_stage_start = -1;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const Referee& m = messages[i];
    const bool pre =
        m.stage() == Referee::NORMAL_FIRST_HALF_PRE || m.stage() == Referee::NORMAL_SECOND_HALF_PRE;
    if (pre && (i == 0 || messages[i - 1].stage() != m.stage()))
      pre_stage_start = static_cast<int>(i);
    std::vector<Referee::Command>& commands = before_kickoff[pre_stage_start];
    if (pre && (commands.empty() || commands.back() != m.command()))
      commands.push_back(m.command());
  }
  ASSERT_GE(before_kickoff.size(), 4u);
  for (const auto& [start, commands] : before_kickoff) {
    const Referee& first = messages[static_cast<std::size_t>(start)];
    const Referee::Command kickoff = first.stage() == Referee::NORMAL_FIRST_HALF_PRE
                                         ? Referee::PREPARE_KICKOFF_YELLOW
                                         : Referee::PREPARE_KICKOFF_BLUE;
    if (start == 0) {
      EXPECT_EQ(commands, std::vector<Referee::Command>{kickoff});
    } else {
      EXPECT_EQ(commands, (std::vector<Referee::Command>{Referee::STOP, kickoff})) << start;
    }
  }
  for (std::size_t i = 1; i < messages.size(); ++i) {
    const Referee& m = messages[i];
    if (m.stage() == messages[i - 1].stage()) continue;
    if (m.stage() == Referee::NORMAL_FIRST_HALF || m.stage() == Referee::NORMAL_SECOND_HALF) {
      EXPECT_EQ(m.command(), Referee::NORMAL_START);
    }
    if (m.stage() == Referee::NORMAL_HALF_TIME || m.stage() == Referee::POST_GAME) {
      EXPECT_EQ(m.command(), Referee::HALT);
      EXPECT_EQ(messages[i - 1].command(), Referee::STOP) << "play ends with a STOP first";
    }
  }
}

TEST(SimulatedGameController, AMatchRunsTwoHalvesWithTheEndsChangedAndThenTheNextMatch) {
  for (const GameControllerConfig& config : {short_halves(), plain(short_halves())}) {
    SCOPED_TRACE(config.shape ? "shaped game" : "plain game");
    expect_two_halves_and_the_next_match(config);
  }
}

// Six hours of data time, a message every 0.1 s: what may follow what, as the rules have it, and
// how often each kind of command comes.
struct CommandCounts {
  std::map<Referee::Command, int> commands;
  std::uint32_t goals = 0;
  int halts_in_play = 0;  // HALTs outside the breaks
  double running_share = 0.0;
};

CommandCounts expect_rules_kept(const GameControllerConfig& config) {
  SimulatedGameController game(config);
  CommandCounts counts;
  Referee before = game.message_at(0.0);
  int running = 0;
  int messages = 0;
  for (double t = 0.1; t < 6 * 3600.0; t += 0.1) {
    const Referee m = game.message_at(t);
    ++messages;
    if (is_running_play(*game_state_of_command(m.command()))) ++running;
    const std::uint32_t score = m.yellow().score() + m.blue().score();
    const std::uint32_t score_before = before.yellow().score() + before.blue().score();
    if (m.command_counter() == before.command_counter()) {
      EXPECT_EQ(m.command(), before.command()) << "a new command without a new counter";
      EXPECT_EQ(m.command_timestamp(), before.command_timestamp());
      EXPECT_EQ(score, score_before);
      before = m;
      continue;
    }
    EXPECT_EQ(m.command_counter(), before.command_counter() + 1) << "a command missed, t=" << t;
    EXPECT_GE(m.command_timestamp(), before.command_timestamp());
    ++counts.commands[m.command()];
    if (score > score_before) {
      ++counts.goals;
      EXPECT_EQ(score, score_before + 1);
      EXPECT_EQ(m.command(), Referee::STOP) << "a goal stops the play";
    }
    const Referee::Command was = before.command();
    const bool was_running = is_running_play(*game_state_of_command(was));
    const bool pause =
        was == Referee::HALT || was == Referee::TIMEOUT_YELLOW || was == Referee::TIMEOUT_BLUE;
    switch (m.command()) {
      case Referee::BALL_PLACEMENT_YELLOW:
      case Referee::BALL_PLACEMENT_BLUE:
      case Referee::FORCE_START:
      case Referee::TIMEOUT_YELLOW:
      case Referee::TIMEOUT_BLUE:
      case Referee::PREPARE_KICKOFF_YELLOW:
      case Referee::PREPARE_KICKOFF_BLUE:
        EXPECT_EQ(was, Referee::STOP) << Referee::Command_Name(m.command());
        break;
      case Referee::DIRECT_FREE_YELLOW:
      case Referee::DIRECT_FREE_BLUE:
        EXPECT_TRUE(was == Referee::STOP || is_team_command(was, Referee::BALL_PLACEMENT_YELLOW));
        if (is_team_command(was, Referee::BALL_PLACEMENT_YELLOW)) {
          EXPECT_EQ(m.command() - Referee::DIRECT_FREE_YELLOW, was - Referee::BALL_PLACEMENT_YELLOW)
              << "the team that placed the ball takes the free kick";
        }
        break;
      case Referee::NORMAL_START:
        EXPECT_TRUE(is_team_command(was, Referee::PREPARE_KICKOFF_YELLOW));
        break;
      case Referee::STOP:
        // Play stops, or goes on towards a restart after a HALT or a timeout.
        EXPECT_TRUE(was_running || pause) << Referee::Command_Name(was);
        break;
      case Referee::HALT:
        EXPECT_EQ(was, Referee::STOP) << "the referee stops the play before halting it";
        if (m.stage() != Referee::NORMAL_HALF_TIME && m.stage() != Referee::POST_GAME) {
          ++counts.halts_in_play;
        }
        break;
      default:
        ADD_FAILURE() << "unexpected " << Referee::Command_Name(m.command());
        break;
    }
    before = m;
  }
  counts.running_share = static_cast<double>(running) / messages;
  // Every kind of stoppage happens.
  EXPECT_GT(counts.commands[Referee::BALL_PLACEMENT_YELLOW], 5);
  EXPECT_GT(counts.commands[Referee::BALL_PLACEMENT_BLUE], 5);
  EXPECT_GT(counts.commands[Referee::DIRECT_FREE_YELLOW], 10);
  EXPECT_GT(counts.commands[Referee::DIRECT_FREE_BLUE], 10);
  EXPECT_GT(counts.goals, 5u);
  return counts;
}

TEST(SimulatedGameController, StoppagesRestartAsTheRulesSayAndTheCounterCountsEveryCommand) {
  {
    SCOPED_TRACE("plain game");
    const CommandCounts plain_game = expect_rules_kept(plain(short_halves()));
    // Play runs most of the time; no HALT but the breaks, no timeouts.
    EXPECT_GT(plain_game.running_share, 0.5);
    EXPECT_LT(plain_game.running_share, 0.95);
    EXPECT_EQ(plain_game.halts_in_play, 0);
    EXPECT_EQ(plain_game.commands.count(Referee::TIMEOUT_YELLOW), 0u);
    EXPECT_EQ(plain_game.commands.count(Referee::FORCE_START), 0u);
  }
  SCOPED_TRACE("shaped game");
  CommandCounts shaped = expect_rules_kept(short_halves());
  // Without a match to cut play short, play runs about half of the time; the referee halts it
  // at about a quarter of the stoppages, the teams ask for timeouts now and then.
  EXPECT_GT(shaped.running_share, 0.35);
  EXPECT_LT(shaped.running_share, 0.75);
  const int stoppages = shaped.commands[Referee::DIRECT_FREE_YELLOW] +
                        shaped.commands[Referee::DIRECT_FREE_BLUE] +
                        shaped.commands[Referee::FORCE_START] + static_cast<int>(shaped.goals);
  EXPECT_GT(shaped.halts_in_play, stoppages / 6);
  EXPECT_LT(shaped.halts_in_play, stoppages / 2);
  EXPECT_GT(shaped.commands[Referee::TIMEOUT_YELLOW] + shaped.commands[Referee::TIMEOUT_BLUE], 2);
  EXPECT_GT(shaped.commands[Referee::FORCE_START], stoppages / 40);
}

TEST(SimulatedGameController, ShapedStretchesAreMostlyShortWithALongTail) {
  GameControllerConfig config;
  config.half_s = 1e6;  // no breaks: stretch lengths only
  SimulatedGameController game(config);
  std::map<GameState, std::vector<double>> lasted;
  std::uint32_t counter = 0;
  GameState state = GameState::unknown;
  double since = 0.0;
  for (double t = 0.0; t < 4 * 3600.0; t += 0.05) {
    const Referee& m = game.message_at(t);
    if (m.command_counter() == counter) continue;
    if (counter != 0) lasted[state].push_back(t - since);
    counter = m.command_counter();
    state = *game_state_of_command(m.command());
    since = t;
  }
  const auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size()))];
  };
  std::vector<double> running = lasted[GameState::running];
  running.insert(running.end(), lasted[GameState::free_kick].begin(),
                 lasted[GameState::free_kick].end());
  // Real matches (docs/simulation.md): running play a median 1-3 s (90th percentile 10-14 s),
  // placements 4-6 s, halts 5-6 s (and here and there a long one).
  EXPECT_GT(quantile(running, 0.5), 1.0);
  EXPECT_LT(quantile(running, 0.5), 4.0);
  EXPECT_GT(quantile(running, 0.9), 10.0);
  EXPECT_GT(quantile(lasted[GameState::ball_placement], 0.5), 4.0);
  EXPECT_LT(quantile(lasted[GameState::ball_placement], 0.5), 6.0);
  EXPECT_GT(quantile(lasted[GameState::halt], 0.5), 4.5);
  EXPECT_LT(quantile(lasted[GameState::halt], 0.5), 7.0);
  EXPECT_GT(quantile(lasted[GameState::halt], 0.9), 10.0);
  EXPECT_LT(quantile(lasted[GameState::stop], 0.5), 2.0);
}

TEST(SimulatedGameController, ATimeoutCountsDownTheTeamsTimeoutsAndItsTime) {
  GameControllerConfig config;
  config.shape->timeout_share = 0.5;
  SimulatedGameController game(config);
  int timeouts = 0;
  std::uint32_t counter = 0;
  Referee before = game.message_at(0.0);
  for (double t = 0.1; t < 1200.0; t += 0.1) {
    const Referee m = game.message_at(t);
    const bool in_timeout =
        m.command() == Referee::TIMEOUT_YELLOW || m.command() == Referee::TIMEOUT_BLUE;
    const Referee::TeamInfo& team = m.command() == Referee::TIMEOUT_YELLOW ? m.yellow() : m.blue();
    const Referee::TeamInfo& team_before =
        m.command() == Referee::TIMEOUT_YELLOW ? before.yellow() : before.blue();
    if (in_timeout && m.command_counter() != counter) {
      ++timeouts;
      EXPECT_EQ(team.timeouts() + 1, team_before.timeouts()) << "a timeout used, t=" << t;
    } else if (in_timeout) {
      // Its time runs while it lasts.
      EXPECT_NEAR(static_cast<double>(team_before.timeout_time()) - team.timeout_time(), 1e5, 1.0);
    }
    EXPECT_LE(m.yellow().timeouts(), 4u);
    counter = m.command_counter();
    before = m;
  }
  EXPECT_GT(timeouts, 4);
}

TEST(SimulatedGameController, TheMatchCallsTheRefereesOwnStoppagesWithWhereToPlaceTheBall) {
  GameControllerConfig config;
  config.random_stoppages = false;  // a match beside it
  SimulatedGameController game(config);
  int called = 0;
  int placed = 0;
  std::uint32_t counter = 0;
  Referee::Command command = Referee::HALT;
  double placement_started = 0.0;
  for (double t = 0.0; t < 600.0; t += 0.05) {
    const Referee& m = game.message_at(t);
    if (m.command_counter() != counter) {
      counter = m.command_counter();
      command = m.command();
      if (command == Referee::BALL_PLACEMENT_YELLOW || command == Referee::BALL_PLACEMENT_BLUE) {
        // The match's spot, as it gave it.
        ASSERT_TRUE(m.has_designated_position());
        EXPECT_FLOAT_EQ(m.designated_position().x(), 1000.0F);
        EXPECT_FLOAT_EQ(m.designated_position().y(), -500.0F);
        placement_started = t;
      }
    }
    const bool placing =
        command == Referee::BALL_PLACEMENT_YELLOW || command == Referee::BALL_PLACEMENT_BLUE;
    if (placing && t >= placement_started + 1.0) {
      // The match places the ball in a second; the placement lasts its drawn length still.
      game.ball_placed(t);
      ++placed;
    }
    if (game.stoppage_due(t)) {
      EXPECT_TRUE(is_running_play(*game_state_of_command(command)));
      ++called;
      game.stop_for_foul(called % 2 ? TeamColor::yellow : TeamColor::blue, t,
                         Point{1000.0, -500.0});
      EXPECT_FALSE(game.stoppage_due(t)) << "play has stopped";
    }
  }
  // Play stops every few seconds to half a minute; almost every stoppage is placed.
  EXPECT_GT(called, 15);
  EXPECT_GT(placed, 0);
  // Without a match asking, the referee waits for the half's end.
  SimulatedGameController alone(config);
  for (double t = 0.0; t < 100.0; t += 0.05) alone.message_at(t);
  EXPECT_EQ(alone.state(), GameState::running);
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
  refused([](GameControllerConfig& c) { c.shape->halt_share = 1.5; });
  refused([](GameControllerConfig& c) { c.shape->halt_share = c.shape->timeout_share = 0.6; });
  refused([](GameControllerConfig& c) { c.shape->running.bands.clear(); });
  refused([](GameControllerConfig& c) { c.shape->halt.bands = {{1.0, 5.0, 4.0}}; });
  refused([](GameControllerConfig& c) { c.shape->ball_placement.bands = {{0.0, 4.0, 6.0}}; });
  refused([](GameControllerConfig& c) { c.shape->kickoff_preparation_s = 0.0; });
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
}  // namespace ssl_formation::simulation
