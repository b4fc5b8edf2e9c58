// A simulated match shaped like a real one (issue 29; docs/simulation.md has the real figures):
// over 20 simulated minutes of the default game, the share of data time in each referee state and
// the typical lengths are near what recorded Division A matches show, nobody moves in HALT and
// timeouts, and in STOP and ball placement the opponent keeps to the rules' 1.5 m/s and 0.5 m from
// the ball.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/simulation/match_simulation.hpp"

namespace ssl_formation::simulation {
namespace {

constexpr double kFrameRateHz = 60.0;

double length(Point p) { return std::hypot(p.x, p.y); }
Point minus(Point a, Point b) { return Point{a.x - b.x, a.y - b.y}; }

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<std::size_t>(q * values.size()))];
}

// What a state's share is measured by: the referee's command, a free kick counting as a free
// kick until the kick (the ball leaves its spot) and as running play after it, as the real
// matches' shares count it.
enum class Shaped { running, free_kick, halt, timeout, stop, ball_placement, kickoff, other };
const char* name(Shaped s) {
  switch (s) {
    case Shaped::running:
      return "running";
    case Shaped::free_kick:
      return "free kick";
    case Shaped::halt:
      return "halt";
    case Shaped::timeout:
      return "timeout";
    case Shaped::stop:
      return "stop";
    case Shaped::ball_placement:
      return "ball placement";
    case Shaped::kickoff:
      return "kick-off";
    case Shaped::other:
      return "other";
  }
  return "?";
}

struct Frame {
  double t = 0.0;
  int command = -1;
  double since_command_s = 0.0;
  // How long robots could move away from the ball since play stopped (STOP and placement time).
  double stopped_moving_s = 0.0;
  int placer = -1;  // in a ball placement: the robot placing the ball (index into robots)
  Shaped state = Shaped::other;
  std::vector<Point> robots;  // feed coordinates: the opponent's ids 0-10, then ours
  Point ball;                 // feed coordinates
};

struct Measured {
  std::vector<Frame> frames;
  std::map<Shaped, double> share;
  std::map<GamePhase, double> phase_share;
  std::vector<double> running_stretches_s;  // from a restart to the next command
  std::vector<double> placements_s;
  std::vector<double> halts_s;  // outside the breaks
  std::vector<double> kick_delays_s;
  int timeouts = 0;
};

Point feed(Point normalised, AttackDirection attacks) { return normalise(normalised, attacks); }

Measured measure(std::uint64_t seed, double minutes, GameControllerConfig game) {
  MatchSimulationConfig config;
  config.seed = seed;
  config.frame_rate_hz = kFrameRateHz;
  config.playbook = *parse_playbook(*builtin_playbook_text("wings"), "wings");
  game.seed = seed;
  config.game = game;
  MatchSimulation match(config);
  Measured out;
  const int frames = static_cast<int>(minutes * 60.0 * kFrameRateHz);
  GamePhaseTracker phases;
  std::uint32_t counter = 0;
  int command = -1;
  double command_s = 0.0;
  double stopped_moving_s = 0.0;
  std::size_t command_first_frame = 0;
  int stage = -1;
  bool kicked = true;
  Point ball_at_command;
  for (int f = 0; f < frames; ++f) {
    const MatchFrame m = match.next();
    const Referee& referee = *m.referee;
    const Point ball = feed(m.ball, m.opponent_attacks);
    if (referee.command_counter() != counter) {
      const double lasted = m.t_capture - command_s;
      const auto before = game_state_of_command(command);
      if (before && is_running_play(*before)) out.running_stretches_s.push_back(lasted);
      if (before == GameState::ball_placement) out.placements_s.push_back(lasted);
      const bool break_halt = referee.stage() == Referee::NORMAL_HALF_TIME ||
                              referee.stage() == Referee::POST_GAME ||
                              referee.stage() == Referee::NORMAL_SECOND_HALF_PRE ||
                              referee.stage() == Referee::NORMAL_FIRST_HALF_PRE;
      if (before == GameState::halt && !break_halt) out.halts_s.push_back(lasted);
      const auto now = game_state_of_command(referee.command());
      if (before == GameState::ball_placement && !out.frames.empty()) {
        // The placing robot: of the placing team, the one at the ball when it is placed.
        const std::size_t first = team_of_command(command) == config.opponent_color ? 0 : 11;
        const Frame& last = out.frames.back();
        std::size_t placer = first;
        for (std::size_t r = first; r < first + 11; ++r) {
          if (length(minus(last.robots[r], last.ball)) <
              length(minus(last.robots[placer], last.ball))) {
            placer = r;
          }
        }
        for (std::size_t i = command_first_frame; i < out.frames.size(); ++i) {
          out.frames[i].placer = static_cast<int>(placer);
        }
      }
      if (now == GameState::timeout) ++out.timeouts;
      counter = referee.command_counter();
      command = referee.command();
      command_s = m.t_capture;
      command_first_frame = out.frames.size();
      phases.on_command(command, m.t_capture);
      kicked = now != GameState::free_kick;
      ball_at_command = ball;
    }
    if (!kicked && length(minus(ball, ball_at_command)) > 100.0) {
      kicked = true;
      out.kick_delays_s.push_back(m.t_capture - command_s);
    }
    Frame frame;
    frame.t = m.t_capture;
    frame.command = command;
    frame.since_command_s = m.t_capture - command_s;
    const auto state = game_state_of_command(command);
    // At half time the ball is put on the centre mark (by hand): a new moment to make way.
    if ((state && is_running_play(*state)) || referee.stage() != stage) stopped_moving_s = 0.0;
    stage = referee.stage();
    if (state == GameState::stop || state == GameState::ball_placement) {
      stopped_moving_s += 1.0 / kFrameRateHz;
    }
    frame.stopped_moving_s = stopped_moving_s;
    frame.ball = ball;
    for (const auto* team : {&m.opponent, &m.ours}) {
      for (const Point p : *team) frame.robots.push_back(feed(p, m.opponent_attacks));
    }
    switch (game_state_of_command(command).value_or(GameState::unknown)) {
      case GameState::running:
        frame.state = Shaped::running;
        break;
      case GameState::free_kick:
        frame.state = kicked ? Shaped::running : Shaped::free_kick;
        break;
      case GameState::halt:
        frame.state = Shaped::halt;
        break;
      case GameState::timeout:
        frame.state = Shaped::timeout;
        break;
      case GameState::stop:
        frame.state = Shaped::stop;
        break;
      case GameState::ball_placement:
        frame.state = Shaped::ball_placement;
        break;
      case GameState::kickoff_preparation:
        frame.state = Shaped::kickoff;
        break;
      default:
        frame.state = Shaped::other;
        break;
    }
    out.share[frame.state] += 1.0 / frames;
    out.phase_share[phases.phase(m.t_capture, config.opponent_color)] += 1.0 / frames;
    out.frames.push_back(std::move(frame));
  }
  return out;
}

// One 20-minute match of the default game (shaped like a real one) for every test of the file
// (it takes about a second).
const Measured& measured() {
  static const Measured match = measure(1, 20.0, GameControllerConfig{});
  return match;
}

// Timeouts are rare (a real match has a few): five minutes in which a team asks for one at a
// third of the stoppages.
const Measured& with_timeouts() {
  static const Measured match = [] {
    GameControllerConfig game;
    game.shape->timeout_share = 0.3;
    return measure(2, 5.0, game);
  }();
  return match;
}

TEST(MatchShape, TwentyMinutesSpendTheirTimeAsRealMatchesDo) {
  const Measured& m = measured();
  std::printf("Share of data time by referee state, 20 simulated minutes (seed 1):\n");
  for (const auto& [state, share] : m.share)
    std::printf("  %-15s %5.1f%%\n", name(state), 100 * share);
  std::printf("As the evaluation's game phases (a restart counts for 3 s after its command):\n");
  for (const auto& [phase, share] : m.phase_share) {
    std::printf("  %-24s %5.1f%%\n", std::string(to_string(phase)).c_str(), 100 * share);
  }
  const auto share = [&](Shaped s) { return m.share.contains(s) ? m.share.at(s) : 0.0; };
  // Real matches: running play 32-43%, halt 13-20%, timeout 0-4%, ball placement 26-29%, stop
  // 11-14%, free kicks 2-3%, kick-offs under 1%. Broad bands: 20 minutes are a handful of long
  // stretches.
  EXPECT_GT(share(Shaped::running), 0.28);
  EXPECT_LT(share(Shaped::running), 0.50);
  EXPECT_GT(share(Shaped::halt), 0.09);
  EXPECT_LT(share(Shaped::halt), 0.25);
  EXPECT_LT(share(Shaped::timeout), 0.06);
  EXPECT_GT(share(Shaped::ball_placement), 0.18);
  EXPECT_LT(share(Shaped::ball_placement), 0.36);
  EXPECT_GT(share(Shaped::stop), 0.07);
  EXPECT_LT(share(Shaped::stop), 0.18);
  EXPECT_GT(share(Shaped::free_kick), 0.01);
  EXPECT_LT(share(Shaped::free_kick), 0.08);
  EXPECT_GT(share(Shaped::kickoff), 0.0);
  EXPECT_LT(share(Shaped::kickoff), 0.03);
  EXPECT_EQ(share(Shaped::other), 0.0);
}

TEST(MatchShape, StretchesLastAsLongAsInRealMatches) {
  const Measured& m = measured();
  const auto show = [](const char* what, const std::vector<double>& v) {
    std::printf("  %-26s n=%3zu median %5.2f s, 90th percentile %5.2f s\n", what, v.size(),
                quantile(v, 0.5), quantile(v, 0.9));
  };
  show("running play", m.running_stretches_s);
  show("ball placement", m.placements_s);
  show("halt (outside the breaks)", m.halts_s);
  show("free kick taken after", m.kick_delays_s);
  // Real matches: running play a median 1-3 s before the next command (90th percentile 10-14 s),
  // a ball placement 4-6 s, a halt 5-6 s, a free kick taken about 0.7 s after its command.
  ASSERT_GT(m.running_stretches_s.size(), 40u);
  EXPECT_GT(quantile(m.running_stretches_s, 0.5), 1.0);
  EXPECT_LT(quantile(m.running_stretches_s, 0.5), 6.0);
  EXPECT_GT(quantile(m.running_stretches_s, 0.9), 9.0) << "a long tail";
  ASSERT_GT(m.placements_s.size(), 20u);
  EXPECT_GT(quantile(m.placements_s, 0.5), 4.0);
  EXPECT_LT(quantile(m.placements_s, 0.5), 7.0);
  ASSERT_GT(m.halts_s.size(), 5u);
  EXPECT_GT(quantile(m.halts_s, 0.5), 4.5);
  EXPECT_LT(quantile(m.halts_s, 0.5), 8.0);
  ASSERT_GT(m.kick_delays_s.size(), 20u);
  EXPECT_GT(quantile(m.kick_delays_s, 0.5), 0.5);
  EXPECT_LT(quantile(m.kick_delays_s, 0.5), 1.1);
}

// In HALT and timeouts, once robots have braked, nobody moves.
void expect_still_in_halt_and_timeouts(const Measured& m) {
  // Robots brake as hard as they may (3 m/s^2): stopped within 1 s from any speed. From then
  // on, every robot of both teams stands exactly where it is, to the bit.
  int still_frames = 0;
  double first_second_most_mm = 0.0;
  for (std::size_t f = 1; f < m.frames.size(); ++f) {
    const Frame& now = m.frames[f];
    const Frame& before = m.frames[f - 1];
    if (now.state != Shaped::halt && now.state != Shaped::timeout) continue;
    if (before.command != now.command || before.since_command_s > now.since_command_s) continue;
    for (std::size_t r = 0; r < now.robots.size(); ++r) {
      const double moved = length(minus(now.robots[r], before.robots[r]));
      if (now.since_command_s <= 1.0) {
        first_second_most_mm = std::max(first_second_most_mm, moved);
        continue;
      }
      ASSERT_EQ(now.robots[r].x, before.robots[r].x) << "robot " << r << " t=" << now.t;
      ASSERT_EQ(now.robots[r].y, before.robots[r].y) << "robot " << r << " t=" << now.t;
    }
    if (now.since_command_s > 1.0) ++still_frames;
  }
  // Minutes of it, timeouts included.
  EXPECT_GT(still_frames, static_cast<int>(0.08 * m.frames.size()));
  // Braking at most 3 m/s^2 from at most 3 m/s: under 50 mm a frame.
  EXPECT_LT(first_second_most_mm, 50.0);
}

// In STOP and placement the opponent drives at 1.5 m/s at most and keeps 0.5 m from the ball.
void expect_rules_kept_while_stopped(const Measured& m) {
  const double dt = 1.0 / kFrameRateHz;
  int checked = 0;
  double fastest = 0.0;
  double closest = 1e9;
  int near_ball_frames = 0;
  for (std::size_t f = 1; f < m.frames.size(); ++f) {
    const Frame& now = m.frames[f];
    const Frame& before = m.frames[f - 1];
    const bool stop = now.state == Shaped::stop;
    const bool placement = now.state == Shaped::ball_placement;
    if (!stop && !placement) continue;
    for (std::size_t r = 0; r < 11; ++r) {  // the opponent
      // The robot placing the ball may come to it and drive fast.
      if (placement && static_cast<int>(r) == now.placer) continue;
      // Robots at full speed when play stops brake to 1.5 m/s within 0.5 s.
      if (now.since_command_s > 1.0 || !stop) {
        const double speed = length(minus(now.robots[r], before.robots[r])) / dt;
        fastest = std::max(fastest, speed);
      }
      // The rules leave robots a moment to get away from the ball.
      if (now.stopped_moving_s > 2.0) {
        const double distance = length(minus(now.robots[r], now.ball));
        closest = std::min(closest, distance);
        near_ball_frames += distance < 500.0 ? 1 : 0;
        ++checked;
      }
    }
  }
  ASSERT_GT(checked, 20000);
  EXPECT_LE(fastest, 1500.0 * 1.0001);
  EXPECT_GE(closest, 490.0);
  EXPECT_LT(near_ball_frames, checked / 1000) << "closest " << closest << " mm";
}

TEST(MatchShape, InHaltAndTimeoutsNoRobotMovesOnceItHasStopped) {
  for (const Measured* match : {&measured(), &with_timeouts()}) {
    expect_still_in_halt_and_timeouts(*match);
  }
  EXPECT_GT(with_timeouts().timeouts, 3);
  EXPECT_GT(with_timeouts().share.at(Shaped::timeout), 0.05);
}

TEST(MatchShape, InStopAndPlacementTheOpponentKeepsToTheRulesSpeedAndDistance) {
  for (const Measured* match : {&measured(), &with_timeouts()}) {
    expect_rules_kept_while_stopped(*match);
  }
}

}  // namespace
}  // namespace ssl_formation::simulation
