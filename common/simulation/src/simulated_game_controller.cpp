#include "ssl_formation/simulation/simulated_game_controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "ssl_formation/match/match.hpp"

namespace ssl_formation::sim {

namespace {

// How long the game controller's fixed phases last, in data seconds. A real STOP before a free
// kick or a kick-off lasts a few seconds; the exact figures do not matter to anything learned.
constexpr double kKickoffPreparationS = 4.0;
constexpr double kStopS = 4.0;
constexpr double kGoalStopS = 6.0;
constexpr double kBallPlacementS = 4.0;
constexpr double kEndOfHalfStopS = 2.0;
// Play after a restart lasts at least this long, even when the half is nearly over: a half ends
// with play, never with a restart nobody got to take.
constexpr double kShortestPlayS = 5.0;
// The timeouts a team has left and their time, as the game controller starts a match with.
constexpr std::uint32_t kTimeouts = 4;
constexpr std::uint32_t kTimeoutTimeUs = 300'000'000;


std::uint64_t microseconds(double t_s) {
  return t_s <= 0.0 ? 0 : static_cast<std::uint64_t>(std::llround(t_s * 1e6));
}

// A running phase lasts until the game controller plans the next stoppage (negative duration).
constexpr double kUntilStoppage = -1.0;
// A ball placement the match carries out lasts until it says the ball is placed, or at most
// this long.
constexpr double kUntilPlaced = -2.0;
constexpr double kLongestPlacementS = 30.0;

}  // namespace

SimulatedGameController::SimulatedGameController(GameControllerConfig config)
    : config_(std::move(config)),
      // A stream of its own, apart from the vision's: a seed's formations do not depend on
      // whether a game controller runs beside them.
      random_(config_.seed ^ 0x9e3779b97f4a7c15ULL),
      opponent_attacks_(config_.opponent_attacks) {
  if (!(config_.half_s > 0.0) || !std::isfinite(config_.half_s)) {
    throw std::invalid_argument("the half must last a positive number of seconds");
  }
  if (!(config_.half_time_s >= 0.0) || !std::isfinite(config_.half_time_s)) {
    throw std::invalid_argument("the half-time break must last zero or more seconds");
  }
  if (!(config_.play_min_s > 0.0) || !(config_.play_max_s >= config_.play_min_s) ||
      !std::isfinite(config_.play_max_s)) {
    throw std::invalid_argument("play between stoppages needs 0 < shortest <= longest");
  }
  if (same_team_name(config_.opponent_name, config_.our_name)) {
    throw std::invalid_argument("the two teams need different names, or the referee could not " +
                                std::string("tell them apart: '") + config_.opponent_name + "'");
  }
  const TeamColor ours = our_color();
  Referee::TeamInfo& opponent = config_.opponent_color == TeamColor::yellow
                                    ? *message_.mutable_yellow()
                                    : *message_.mutable_blue();
  Referee::TeamInfo& us =
      ours == TeamColor::yellow ? *message_.mutable_yellow() : *message_.mutable_blue();
  opponent.set_name(config_.opponent_name);
  us.set_name(config_.our_name);
  for (Referee::TeamInfo* team : {&opponent, &us}) {
    team->set_score(0);
    team->set_red_cards(0);
    team->set_yellow_cards(0);
    team->set_timeouts(kTimeouts);
    team->set_timeout_time(kTimeoutTimeUs);
    team->set_goalkeeper(0);  // robot 0 keeps goal in the simulation, on both teams
  }
  message_.set_source_identifier(config_.source_identifier);
  message_.set_command_counter(0);
  start_match(config_.start_time_s);
}

TeamColor SimulatedGameController::our_color() const { return opposite(config_.opponent_color); }

GameState SimulatedGameController::state() const {
  return game_state_of_command(phase_.command).value_or(GameState::unknown);
}

Referee::Command SimulatedGameController::for_team(Referee::Command yellow_command,
                                                   TeamColor team) const {
  // Every team command has its yellow value followed by its blue one.
  return static_cast<Referee::Command>(yellow_command + (team == TeamColor::blue ? 1 : 0));
}

void SimulatedGameController::set_sides() {
  // blue_team_on_positive_half: blue defends the goal on +x. The opponent attacking +x defends
  // -x, so blue is on the positive half exactly when blue is not the opponent there.
  const bool opponent_defends_positive = opponent_attacks_ == AttackDirection::negative_x;
  const bool blue_is_opponent = config_.opponent_color == TeamColor::blue;
  message_.set_blue_team_on_positive_half(blue_is_opponent == opponent_defends_positive);
}

void SimulatedGameController::issue(Referee::Command command, double at_s) {
  // Where to place the ball goes with the placement command only.
  const bool placing =
      command == Referee::BALL_PLACEMENT_YELLOW || command == Referee::BALL_PLACEMENT_BLUE;
  if (placing && placement_) {
    message_.mutable_designated_position()->set_x(static_cast<float>(placement_->x));
    message_.mutable_designated_position()->set_y(static_cast<float>(placement_->y));
  } else {
    message_.clear_designated_position();
  }
  phase_.command = command;
  message_.set_command(command);
  message_.set_command_counter(message_.command_counter() + 1);
  message_.set_command_timestamp(microseconds(at_s));
}

void SimulatedGameController::start_match(double at_s) {
  ++matches_;
  second_half_ = false;
  opponent_attacks_ = config_.opponent_attacks;
  yellow_score_ = blue_score_ = 0;
  set_sides();
  queued_.clear();
  // The opponent kicks off the first half, we the second.
  phase_.stage = Referee::NORMAL_FIRST_HALF_PRE;
  issue(for_team(Referee::PREPARE_KICKOFF_YELLOW, config_.opponent_color), at_s);
  phase_.until_s = at_s + kKickoffPreparationS;
  half_ends_s_ = phase_.until_s + config_.half_s;
  queued_.push_back({Referee::NORMAL_START, kUntilStoppage});
}

void SimulatedGameController::start_stoppage(double at_s) {
  std::uniform_real_distribution<double> draw(0.0, 1.0);
  const double kind = draw(random_);
  const TeamColor team = draw(random_) < 0.5 ? TeamColor::yellow : TeamColor::blue;
  if (kind < 0.5) {
    stop_for_ball_out(team, at_s, std::nullopt);
  } else if (kind < 0.8) {
    stop_for_foul(team, at_s);
  } else {
    stop_for_goal(team, at_s);
  }
}

void SimulatedGameController::stop_for_ball_out(TeamColor restart_team, double at_s,
                                                std::optional<Point> placement) {
  // The team to restart places the ball, then takes a free kick.
  queued_.clear();
  issue(Referee::STOP, at_s);
  phase_.until_s = at_s + kStopS;
  placement_ = placement;
  queued_.push_back({for_team(Referee::BALL_PLACEMENT_YELLOW, restart_team),
                     config_.random_stoppages ? kBallPlacementS : kUntilPlaced});
  queued_.push_back({for_team(Referee::DIRECT_FREE_YELLOW, restart_team), kUntilStoppage});
}

void SimulatedGameController::ball_placed(double at_s) {
  const bool placing = phase_.command == Referee::BALL_PLACEMENT_YELLOW ||
                       phase_.command == Referee::BALL_PLACEMENT_BLUE;
  if (placing && at_s < phase_.until_s) phase_.until_s = at_s;
}

void SimulatedGameController::stop_for_foul(TeamColor restart_team, double at_s) {
  // A free kick where it happened.
  queued_.clear();
  issue(Referee::STOP, at_s);
  phase_.until_s = at_s + kStopS;
  queued_.push_back({for_team(Referee::DIRECT_FREE_YELLOW, restart_team), kUntilStoppage});
}

void SimulatedGameController::stop_for_goal(TeamColor scorer, double at_s) {
  // The other team kicks off.
  queued_.clear();
  Referee::TeamInfo& team =
      scorer == TeamColor::yellow ? *message_.mutable_yellow() : *message_.mutable_blue();
  team.set_score(++(scorer == TeamColor::yellow ? yellow_score_ : blue_score_));
  issue(Referee::STOP, at_s);
  phase_.until_s = at_s + kGoalStopS;
  queued_.push_back(
      {for_team(Referee::PREPARE_KICKOFF_YELLOW, opposite(scorer)), kKickoffPreparationS});
  queued_.push_back({Referee::NORMAL_START, kUntilStoppage});
}

void SimulatedGameController::advance(double from_s) {
  if (!queued_.empty()) {
    const QueuedPhase next = queued_.front();
    queued_.erase(queued_.begin());
    issue(next.command, from_s);
    if (phase_.stage == Referee::NORMAL_FIRST_HALF_PRE) phase_.stage = Referee::NORMAL_FIRST_HALF;
    if (phase_.stage == Referee::NORMAL_SECOND_HALF_PRE &&
        (next.command == Referee::NORMAL_START)) {
      phase_.stage = Referee::NORMAL_SECOND_HALF;
    }
    if (next.duration_s == kUntilStoppage) {
      // Play goes on until the next stoppage: drawn at random, or (stoppages called by the
      // match) until the half ends.
      double drawn = half_ends_s_ - from_s;
      if (config_.random_stoppages) {
        std::uniform_real_distribution<double> play(config_.play_min_s, config_.play_max_s);
        drawn = play(random_);
      }
      phase_.until_s = from_s + std::max(kShortestPlayS, std::min(drawn, half_ends_s_ - from_s));
    } else if (next.duration_s == kUntilPlaced) {
      // The rules give a placement 30 s; then the game controller goes on regardless.
      phase_.until_s = from_s + kLongestPlacementS;
    } else {
      phase_.until_s = from_s + next.duration_s;
    }
    return;
  }
  // Nothing queued: either play stops (a stoppage, or the half's end) or a break ends.
  switch (phase_.stage) {
    case Referee::NORMAL_FIRST_HALF:
    case Referee::NORMAL_SECOND_HALF:
      if (phase_.command == Referee::STOP) {
        // The half's closing STOP is over: half time, or the end of the match.
        phase_.stage = second_half_ ? Referee::POST_GAME : Referee::NORMAL_HALF_TIME;
        issue(Referee::HALT, from_s);
        phase_.until_s = from_s + config_.half_time_s;
      } else if (from_s >= half_ends_s_ - 1e-9) {
        issue(Referee::STOP, from_s);
        phase_.until_s = from_s + kEndOfHalfStopS;
      } else {
        start_stoppage(from_s);
      }
      return;
    case Referee::NORMAL_HALF_TIME:
      // The teams change ends; we kick off the second half.
      second_half_ = true;
      opponent_attacks_ = opposite(opponent_attacks_);
      set_sides();
      phase_.stage = Referee::NORMAL_SECOND_HALF_PRE;
      issue(for_team(Referee::PREPARE_KICKOFF_YELLOW, our_color()), from_s);
      phase_.until_s = from_s + kKickoffPreparationS;
      half_ends_s_ = phase_.until_s + config_.half_s;
      queued_.push_back({Referee::NORMAL_START, kUntilStoppage});
      return;
    default:  // POST_GAME: the next match starts, on the first half's ends again
      start_match(from_s);
      return;
  }
}

const Referee& SimulatedGameController::message_at(double t_s) {
  if (t_s < last_t_s_) {
    throw std::invalid_argument("the game controller's time went backwards");
  }
  last_t_s_ = t_s;
  while (t_s >= phase_.until_s) advance(phase_.until_s);
  message_.set_packet_timestamp(microseconds(t_s));
  message_.set_stage(phase_.stage);
  const bool in_half =
      phase_.stage == Referee::NORMAL_FIRST_HALF || phase_.stage == Referee::NORMAL_SECOND_HALF;
  if (in_half) {
    message_.set_stage_time_left(
        static_cast<std::int64_t>(std::llround(std::max(0.0, half_ends_s_ - t_s) * 1e6)));
  } else {
    message_.clear_stage_time_left();
  }
  return message_;
}

std::string describe(const SimulatedGameController& game_controller) {
  const Referee& message = game_controller.message();
  std::string text = "match " + std::to_string(game_controller.matches_started()) + ", " +
                     Referee::Stage_Name(message.stage()) + ", game " +
                     std::string(to_string(game_controller.state())) + ", opponent attacks " +
                     std::string(to_string(game_controller.opponent_attacks())) + ", score " +
                     std::to_string(message.yellow().score()) + ":" +
                     std::to_string(message.blue().score()) + " (yellow:blue)";
  return text;
}

RefereedSimulation::RefereedSimulation(SimulationConfig vision,
                                       std::optional<GameControllerConfig> game)
    : vision_(vision) {
  if (game) {
    game->opponent_color = vision.opponent_color;
    game->opponent_attacks = vision.opponent_attacks;
    game->start_time_s = vision.start_time_s;
    game_.emplace(std::move(*game));
  }
}

RefereedFormation RefereedSimulation::next() {
  RefereedFormation step;
  if (game_) {
    step.referee = game_->message_at(vision_.next_t_capture());
    vision_.set_opponent_attacks(game_->opponent_attacks());
  }
  step.formation = vision_.next();
  return step;
}

}  // namespace ssl_formation::sim
