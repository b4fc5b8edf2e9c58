// How the simulated match meets the rules: the stoppages and fouls it provokes, the possession it
// hands to our side, and what it does at each referee command (match_simulation.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "match_rules.hpp"
#include "ssl_formation/simulation/match_simulation.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::simulation {

using namespace detail;

void MatchSimulation::call_stoppage(double now_s) {
  // The ball stops where it left the field.
  ball_.position = Point{std::clamp(ball_.position.x, -field_.length_mm / 2, field_.length_mm / 2),
                         std::clamp(ball_.position.y, -field_.width_mm / 2, field_.width_mm / 2)};
  ball_.velocity = Point{0.0, 0.0};
  ball_.shot = false;
  std::uniform_real_distribution<double> draw(0.0, 1.0);
  const std::optional<GameShape>& shape = game_->config().shape;
  const double kind = draw(random_);
  if (kind < (shape ? shape->shot_goal_share : kGoalShare)) {
    ++goals_;
    game_->stop_for_goal(config_.opponent_color, now_s);
    return;
  }
  if (shape && kind < shape->shot_goal_share + shape->shot_saved_share) {
    // Our keeper saves it and throws the ball to a team mate: play goes on.
    const Point keeper = robot_position(team_size_);
    ball_.position = inside_field(Point{keeper.x - kBallAheadMm, keeper.y});
    start_our_possession(now_s);
    ball_.rolling = true;
    return;
  }
  if (draw(random_) < kCornerShare) {
    // A corner (or another set piece): the play waits, and the ball is placed where its taker
    // starts.
    start_play(now_s, PlayRestart::free_kick);
    holding_play_ = true;
    taker_kicks_ = true;
    const PlayStep& first = config_.playbook.plays[play_].steps.front();
    Point spot = on_field(Point{0.9, ball_.position.y < 0 ? -0.9 : 0.9});
    if (first.ball_robot) {
      // The taker places the ball: it goes to fetch it, then carries it to where it starts.
      Point& taker = play_targets_[static_cast<std::size_t>(receiver_for(first))];
      spot = inside_field(Point{taker.x + kBallAheadMm, taker.y});
      taker = ball_.position;
    }
    game_->stop_for_ball_out(config_.opponent_color, now_s, normalise(spot, attacks_));
    return;
  }
  // A goal kick for us, from the side of our goal area where the ball went out.
  const Point spot{field_.length_mm / 2 - 500.0, ball_.position.y < 0 ? -1000.0 : 1000.0};
  game_->stop_for_ball_out(opposite(config_.opponent_color), now_s, normalise(spot, attacks_));
}

void MatchSimulation::call_foul(double now_s) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const bool opponents_kick = unit(random_) < 0.5;
  const double angle = unit(random_) * 2.0 * kPi;
  const double distance =
      kFoulPlacementMinMm + (kFoulPlacementMaxMm - kFoulPlacementMinMm) * unit(random_);
  const double half_length = field_.length_mm / 2.0 - kPlacementMarginMm;
  const double half_width = field_.width_mm / 2.0 - kPlacementMarginMm;
  const Point spot{
      std::clamp(ball_.position.x + distance * std::cos(angle), -half_length, half_length),
      std::clamp(ball_.position.y + distance * std::sin(angle), -half_width, half_width)};
  // Play stops where it is; nobody kicks until the restart.
  ball_.velocity = Point{0.0, 0.0};
  ball_.holder = -1;
  ball_.receiver = -1;
  ball_.rolling = false;
  ball_.shot = false;
  if (opponents_kick) {
    // A play from where the foul was, waiting (a playbook's free-kick plays are set pieces near
    // the goal, such as corners). The robot nearest to the ball places it and kicks.
    start_play(now_s, PlayRestart::any);
    holding_play_ = true;
    taker_kicks_ = false;
  }
  const TeamColor team = opponents_kick ? config_.opponent_color : opposite(config_.opponent_color);
  game_->stop_for_foul(team, now_s, normalise(spot, attacks_));
}

void MatchSimulation::start_our_possession(double now_s) {
  mode_ = Mode::our_possession;
  holding_play_ = false;
  kick_at_s_ = now_s;
  // Our robot nearest to the ball fetches it; the opponent falls back and presses.
  const int nearest = nearest_of(team_size_ + 1, 2 * team_size_, ball_.position,
                                 [this](int i) { return robot_position(i); });
  ball_.holder = -1;
  ball_.rolling = false;
  ball_.shot = false;
  ball_.receiver = nearest;
  std::uniform_real_distribution<double> lasts(kOurPossessionMinS, kOurPossessionMaxS);
  possession_ends_s_ = now_s + lasts(random_);
  play_ = -1;
  const std::vector<Point> shape = line_up(field_, team_size_);
  for (int id = 1; id < team_size_; ++id) {
    play_targets_[static_cast<std::size_t>(id)] = shape[static_cast<std::size_t>(id)];
  }
}

void MatchSimulation::follow_referee(const Referee& message, double now_s) {
  const bool new_command = message.command_counter() != command_counter_;
  const bool new_stage = static_cast<int>(message.stage()) != stage_;
  if (!new_command && !new_stage) return;
  command_counter_ = message.command_counter();
  stage_ = static_cast<int>(message.stage());
  if (game_->opponent_attacks() != attacks_) {
    // The teams changed ends: the same robots, seen from the other end. Nothing moves on the
    // wire; in normalised positions everything turns about the centre.
    attacks_ = game_->opponent_attacks();
    robots_.mirror();
    for (Point& p : play_targets_) p = Point{-p.x, -p.y};
    ball_ = Ball{};
  }
  if (!new_command) return;
  const auto state = game_state_of_command(message.command());
  if (!state) return;
  const bool team_command = message.command() >= Referee::PREPARE_KICKOFF_YELLOW;
  const bool for_opponent =
      team_command && team_of_command(message.command()) == config_.opponent_color;
  const auto freeze_ball = [&] {
    ball_.velocity = Point{0.0, 0.0};
    ball_.holder = -1;
    ball_.receiver = -1;
    ball_.rolling = false;
    ball_.shot = false;
  };
  const std::optional<GameShape>& game_shape = game_->config().shape;
  switch (*state) {
    case GameState::halt:
    case GameState::timeout:
      freeze_ball();
      mode_ = Mode::halted;
      return;
    case GameState::stop:
      freeze_ball();
      // Before a half's kick-off (after the break), the teams line up for it.
      mode_ = message.stage() == Referee::NORMAL_FIRST_HALF_PRE ||
                      message.stage() == Referee::NORMAL_SECOND_HALF_PRE
                  ? Mode::lining_up
                  : Mode::stopped;
      return;
    case GameState::penalty_preparation:
      freeze_ball();
      mode_ = Mode::stopped;
      return;
    case GameState::kickoff_preparation:
      ball_ = Ball{};
      mode_ = Mode::kickoff_preparation;
      kickoff_by_opponent_ = for_opponent;
      holding_play_ = true;
      taker_kicks_ = true;
      if (for_opponent) {
        start_play(now_s, PlayRestart::kickoff);
        ball_.receiver = -1;  // nobody touches the ball before NORMAL_START
      } else {
        play_ = -1;
        const std::vector<Point> shape = line_up(field_, team_size_);
        for (int id = 1; id < team_size_; ++id) {
          play_targets_[static_cast<std::size_t>(id)] = shape[static_cast<std::size_t>(id)];
        }
      }
      return;
    case GameState::ball_placement: {
      mode_ = Mode::ball_placement;
      freeze_ball();
      placement_ = message.has_designated_position()
                       ? normalise(Point{message.designated_position().x(),
                                         message.designated_position().y()},
                                   attacks_)
                       : ball_.position;
      // The placing team's robot nearest to the ball carries it (keepers stay home); for the
      // opponent's set play, the robot that will take the free kick.
      const int first = for_opponent ? 1 : team_size_ + 1;
      ball_.receiver = nearest_of(first, first + team_size_ - 1, ball_.position,
                                  [this](int i) { return robot_position(i); });
      if (for_opponent && holding_play_ && play_ >= 0 && taker_kicks_) {
        const PlayStep& step = config_.playbook.plays[play_].steps.front();
        if (step.ball_robot) ball_.receiver = receiver_for(step);
      }
      return;
    }
    case GameState::running:
    case GameState::free_kick: {
      // A placement cut short (the game controller waits 30 s at most): the free kick is taken
      // where the ball was to be placed, as a referee would put it there.
      if (mode_ == Mode::ball_placement) ball_.position = placement_;
      const bool ours_to_take = *state == GameState::free_kick
                                    ? !for_opponent
                                    : message.command() == Referee::NORMAL_START &&
                                          mode_ == Mode::kickoff_preparation &&
                                          !kickoff_by_opponent_;
      ball_.receiver = -1;
      // A shaped game's free kick is taken its kick delay after the command.
      const bool kick_after_delay = game_shape && *state == GameState::free_kick;
      const double kick_at_s = kick_after_delay ? now_s + game_shape->kick_delay_s : now_s;
      if (ours_to_take) {
        start_our_possession(now_s);
        kick_at_s_ = kick_at_s;
        return;
      }
      kick_at_s_ = kick_at_s;
      mode_ = Mode::opponent_play;
      if (play_ < 0) {
        start_play(now_s, PlayRestart::any);
      } else if (holding_play_) {
        // The restart's play goes: its first step was held until now. Unless its own taker
        // stands at the ball, the robot nearest to the ball (after a placement, the one that
        // placed it) takes the kick: a pass to the play's first receiver, which starts the play.
        const int kicker =
            nearest_of(1, team_size_, ball_.position, [this](int i) { return robot_position(i); });
        const PlayStep& first = config_.playbook.plays[play_].steps.front();
        if (!taker_kicks_ && first.ball_robot && receiver_for(first) != kicker) {
          ball_.receiver = kicker;
          step_ = -1;
          const double fetch_s =
              length(minus(robot_position(kicker), ball_.position)) / kStopSpeedMmS;
          step_ends_s_ = std::max(kick_at_s_, now_s + fetch_s);
        } else {
          aim_at_step();
          step_ends_s_ = kick_after_delay
                             ? kick_at_s_
                             : now_s + hold_scale_ * config_.playbook.plays[play_]
                                                         .steps[static_cast<std::size_t>(step_)]
                                                         .hold_s;
        }
      }
      holding_play_ = false;
      return;
    }
    case GameState::unknown:
      return;
  }
}

}  // namespace ssl_formation::simulation
