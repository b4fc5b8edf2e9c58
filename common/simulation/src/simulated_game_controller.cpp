#include "ssl_formation/simulation/simulated_game_controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "ssl_formation/match/match.hpp"

namespace ssl_formation::simulation {

namespace {

// How long the plain game's fixed phases last, in data seconds (a GameShape draws its own). A
// real STOP before a free kick or a kick-off lasts a few seconds; the exact figures do not matter
// to anything learned.
constexpr double kKickoffPreparationS = 4.0;
constexpr double kStopS = 4.0;
constexpr double kGoalStopS = 6.0;
constexpr double kBallPlacementS = 4.0;
constexpr double kLineUpS = 8.0;
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
// The rules give a placement 30 s; then the game controller goes on regardless.
constexpr double kLongestPlacementS = 30.0;

bool is_share(double x) { return x >= 0.0 && x <= 1.0; }

bool starts_running_play(Referee::Command command) {
  return is_running_play(game_state_of_command(command).value_or(GameState::unknown));
}

bool is_timeout(Referee::Command command) {
  return command == Referee::TIMEOUT_YELLOW || command == Referee::TIMEOUT_BLUE;
}

}  // namespace

void DurationBands::check(const std::string& what) const {
  double total = 0.0;
  for (const Band& band : bands) {
    if (!(band.weight >= 0.0) || !std::isfinite(band.weight) || !(band.min_s > 0.0) ||
        !(band.max_s >= band.min_s) || !std::isfinite(band.max_s)) {
      throw std::invalid_argument(what + ": every band needs a weight >= 0 and 0 < min <= max");
    }
    total += band.weight;
  }
  if (!(total > 0.0)) throw std::invalid_argument(what + ": needs a band with a weight above 0");
}

double DurationBands::draw(std::mt19937_64& random) const {
  std::vector<double> weights;
  for (const Band& band : bands) weights.push_back(band.weight);
  std::discrete_distribution<std::size_t> pick(weights.begin(), weights.end());
  const Band& band = bands[pick(random)];
  std::uniform_real_distribution<double> length(band.min_s, band.max_s);
  return length(random);
}

void GameShape::check() const {
  running.check("the shape's running play");
  stop.check("the shape's STOP");
  goal_stop.check("the shape's STOP after a goal");
  halt.check("the shape's HALT");
  timeout.check("the shape's timeout");
  ball_placement.check("the shape's ball placement");
  if (!is_share(halt_share) || !is_share(timeout_share) || !(halt_share + timeout_share <= 1.0) ||
      !is_share(force_start_share) || !is_share(placement_share) || !is_share(goal_share) ||
      !is_share(shot_goal_share) || !is_share(shot_saved_share) ||
      !(shot_goal_share + shot_saved_share <= 1.0)) {
    throw std::invalid_argument(
        "the shape's shares must be from 0 to 1 (HALT and timeout together, goals and saves "
        "together)");
  }
  if (!(kickoff_preparation_s > 0.0) || !std::isfinite(kickoff_preparation_s) ||
      !(line_up_s > 0.0) || !std::isfinite(line_up_s) || !(kick_delay_s >= 0.0) ||
      !std::isfinite(kick_delay_s)) {
    throw std::invalid_argument(
        "the shape's kick-off preparation and line-up must last a positive time, the kick delay "
        "zero or more");
  }
}

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
  if (config_.shape) config_.shape->check();
  team_info(config_.opponent_color).set_name(config_.opponent_name);
  team_info(our_color()).set_name(config_.our_name);
  for (const TeamColor color : {TeamColor::yellow, TeamColor::blue}) {
    Referee::TeamInfo& team = team_info(color);
    team.set_score(0);
    team.set_red_cards(0);
    team.set_yellow_cards(0);
    team.set_goalkeeper(0);  // robot 0 keeps goal in the simulation, on both teams
  }
  message_.set_source_identifier(config_.source_identifier);
  message_.set_command_counter(0);
  start_match(config_.start_time_s);
}

TeamColor SimulatedGameController::our_color() const { return opposite(config_.opponent_color); }

Referee::TeamInfo& SimulatedGameController::team_info(TeamColor team) {
  return team == TeamColor::yellow ? *message_.mutable_yellow() : *message_.mutable_blue();
}

double SimulatedGameController::draw_unit() {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  return unit(random_);
}

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
  if (is_timeout(command)) {
    // The team's timeouts count down, and its timeout time while the timeout lasts.
    Referee::TeamInfo& team =
        team_info(command == Referee::TIMEOUT_YELLOW ? TeamColor::yellow : TeamColor::blue);
    team.set_timeouts(team.timeouts() > 0 ? team.timeouts() - 1 : 0);
    timeout_time_at_start_us_ = team.timeout_time();
    timeout_started_s_ = at_s;
  }
  phase_.command = command;
  message_.set_command(command);
  message_.set_command_counter(message_.command_counter() + 1);
  message_.set_command_timestamp(microseconds(at_s));
}

void SimulatedGameController::start_match(double at_s) {
  const bool first = matches_ == 0;
  ++matches_;
  second_half_ = false;
  opponent_attacks_ = config_.opponent_attacks;
  yellow_score_ = blue_score_ = 0;
  for (const TeamColor color : {TeamColor::yellow, TeamColor::blue}) {
    Referee::TeamInfo& team = team_info(color);
    team.set_score(0);
    team.set_timeouts(kTimeouts);
    team.set_timeout_time(kTimeoutTimeUs);
  }
  set_sides();
  queued_.clear();
  // The opponent kicks off the first half, we the second. The robots start the first match
  // lined up; after a match they walk to their kick-off places first, in a STOP.
  phase_.stage = Referee::NORMAL_FIRST_HALF_PRE;
  const Referee::Command kickoff =
      for_team(Referee::PREPARE_KICKOFF_YELLOW, config_.opponent_color);
  const double preparation_s =
      config_.shape ? config_.shape->kickoff_preparation_s : kKickoffPreparationS;
  if (first) {
    issue(kickoff, at_s);
    phase_.until_s = at_s + preparation_s;
  } else {
    issue(Referee::STOP, at_s);
    phase_.until_s = at_s + (config_.shape ? config_.shape->line_up_s : kLineUpS);
    queued_.push_back({kickoff, preparation_s});
  }
  half_ends_s_ = phase_.until_s + (first ? 0.0 : preparation_s) + config_.half_s;
  queued_.push_back({Referee::NORMAL_START, kUntilStoppage});
}

void SimulatedGameController::start_stoppage(double at_s) {
  const double kind = draw_unit();
  const TeamColor team = draw_unit() < 0.5 ? TeamColor::yellow : TeamColor::blue;
  // The plain game: half of its stoppages the ball out, 30% fouls, 20% goals. A shaped game
  // scores far less often than it stops.
  const double goals = config_.shape ? config_.shape->goal_share : 0.2;
  if (kind < goals) {
    stop_for_goal(team, at_s);
  } else if (kind < goals + (1.0 - goals) * 0.625) {
    stop_for_ball_out(team, at_s, std::nullopt);
  } else {
    stop_for_foul(team, at_s);
  }
}

void SimulatedGameController::begin_stoppage(double at_s, double stop_s) {
  queued_.clear();
  issue(Referee::STOP, at_s);
  phase_.until_s = at_s + stop_s;
  if (!config_.shape) return;
  const GameShape& shape = *config_.shape;
  const double u = draw_unit();
  if (u < shape.timeout_share) {
    // A team asks for a timeout: the one drawn, or the other if it has none left.
    TeamColor team = draw_unit() < 0.5 ? TeamColor::yellow : TeamColor::blue;
    if (team_info(team).timeouts() == 0 || team_info(team).timeout_time() == 0) {
      team = opposite(team);
    }
    if (team_info(team).timeouts() > 0 && team_info(team).timeout_time() > 0) {
      const double left_s = team_info(team).timeout_time() / 1e6;
      queued_.push_back(
          {for_team(Referee::TIMEOUT_YELLOW, team), std::min(shape.timeout.draw(random_), left_s)});
      queued_.push_back({Referee::STOP, shape.stop.draw(random_)});
      return;
    }
  }
  if (u < shape.timeout_share + shape.halt_share) {
    queued_.push_back({Referee::HALT, shape.halt.draw(random_)});
    queued_.push_back({Referee::STOP, shape.stop.draw(random_)});
  }
}

void SimulatedGameController::queue_free_kick(TeamColor team, bool place,
                                              std::optional<Point> placement) {
  placement_ = placement;
  if (place) {
    if (!config_.shape) {
      queued_.push_back({for_team(Referee::BALL_PLACEMENT_YELLOW, team), kBallPlacementS,
                         !config_.random_stoppages});
    } else {
      queued_.push_back({for_team(Referee::BALL_PLACEMENT_YELLOW, team),
                         config_.shape->ball_placement.draw(random_), !config_.random_stoppages});
    }
  }
  queued_.push_back({for_team(Referee::DIRECT_FREE_YELLOW, team), kUntilStoppage});
}

void SimulatedGameController::stop_for_ball_out(TeamColor restart_team, double at_s,
                                                std::optional<Point> placement) {
  // The team to restart places the ball, then takes a free kick.
  begin_stoppage(at_s, config_.shape ? config_.shape->stop.draw(random_) : kStopS);
  queue_free_kick(restart_team, true, placement);
}

void SimulatedGameController::ball_placed(double at_s) {
  const bool placing = phase_.command == Referee::BALL_PLACEMENT_YELLOW ||
                       phase_.command == Referee::BALL_PLACEMENT_BLUE;
  const double ends_s = std::max(at_s, placement_at_least_until_s_);
  if (placing && ends_s < phase_.until_s) phase_.until_s = ends_s;
}

void SimulatedGameController::stop_for_foul(TeamColor restart_team, double at_s,
                                            std::optional<Point> placement) {
  // A free kick where it happened, or where the referee has the ball placed; with a shape, now
  // and then the referee restarts at once.
  if (!config_.shape) {
    begin_stoppage(at_s, kStopS);
    queue_free_kick(restart_team, placement.has_value(), placement);
    return;
  }
  const GameShape& shape = *config_.shape;
  begin_stoppage(at_s, shape.stop.draw(random_));
  if (draw_unit() < shape.force_start_share) {
    placement_.reset();
    queued_.push_back({Referee::FORCE_START, kUntilStoppage});
    return;
  }
  // Without a match nobody knows where the ball is, but it is placed all the same.
  const bool can_place = placement.has_value() || config_.random_stoppages;
  queue_free_kick(restart_team, can_place && draw_unit() < shape.placement_share, placement);
}

void SimulatedGameController::stop_for_goal(TeamColor scorer, double at_s) {
  // The other team kicks off.
  Referee::TeamInfo& team = team_info(scorer);
  team.set_score(++(scorer == TeamColor::yellow ? yellow_score_ : blue_score_));
  begin_stoppage(at_s, config_.shape ? config_.shape->goal_stop.draw(random_) : kGoalStopS);
  queued_.push_back({for_team(Referee::PREPARE_KICKOFF_YELLOW, opposite(scorer)),
                     config_.shape ? config_.shape->kickoff_preparation_s : kKickoffPreparationS});
  queued_.push_back({Referee::NORMAL_START, kUntilStoppage});
}

bool SimulatedGameController::stoppage_due(double t_s) const {
  const bool in_half =
      phase_.stage == Referee::NORMAL_FIRST_HALF || phase_.stage == Referee::NORMAL_SECOND_HALF;
  return config_.shape && !config_.random_stoppages && in_half &&
         starts_running_play(phase_.command) && t_s >= play_stops_s_ && t_s < phase_.until_s;
}

void SimulatedGameController::advance(double from_s) {
  if (!queued_.empty()) {
    const QueuedPhase next = queued_.front();
    queued_.erase(queued_.begin());
    issue(next.command, from_s);
    // A half starts with the kick-off's NORMAL_START.
    if (next.command == Referee::NORMAL_START) {
      if (phase_.stage == Referee::NORMAL_FIRST_HALF_PRE) phase_.stage = Referee::NORMAL_FIRST_HALF;
      if (phase_.stage == Referee::NORMAL_SECOND_HALF_PRE) {
        phase_.stage = Referee::NORMAL_SECOND_HALF;
      }
    }
    if (next.duration_s == kUntilStoppage) {
      const double left_s = half_ends_s_ - from_s;
      if (!config_.shape) {
        // Play goes on until the next stoppage: drawn at random, or (stoppages called by the
        // match) until the half ends.
        double drawn = left_s;
        if (config_.random_stoppages) {
          std::uniform_real_distribution<double> play(config_.play_min_s, config_.play_max_s);
          drawn = play(random_);
        }
        phase_.until_s = from_s + std::max(kShortestPlayS, std::min(drawn, left_s));
      } else if (config_.random_stoppages) {
        phase_.until_s = from_s + std::min(config_.shape->running.draw(random_),
                                           std::max(kShortestPlayS, left_s));
      } else {
        // The match plays until the half ends; the referee stops it earlier, when the match
        // asks stoppage_due().
        phase_.until_s = from_s + std::max(kShortestPlayS, left_s);
        play_stops_s_ = from_s + config_.shape->running.draw(random_);
      }
    } else if (next.until_placed) {
      phase_.until_s = from_s + kLongestPlacementS;
      placement_at_least_until_s_ = from_s + (config_.shape ? next.duration_s : 0.0);
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
    case Referee::NORMAL_HALF_TIME: {
      // The teams change ends and walk to their kick-off places; we kick off the second half.
      second_half_ = true;
      opponent_attacks_ = opposite(opponent_attacks_);
      set_sides();
      phase_.stage = Referee::NORMAL_SECOND_HALF_PRE;
      issue(Referee::STOP, from_s);
      phase_.until_s = from_s + (config_.shape ? config_.shape->line_up_s : kLineUpS);
      const double preparation_s =
          config_.shape ? config_.shape->kickoff_preparation_s : kKickoffPreparationS;
      queued_.push_back({for_team(Referee::PREPARE_KICKOFF_YELLOW, our_color()), preparation_s});
      queued_.push_back({Referee::NORMAL_START, kUntilStoppage});
      half_ends_s_ = phase_.until_s + preparation_s + config_.half_s;
      return;
    }
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
  if (is_timeout(phase_.command)) {
    const double used_us = (t_s - timeout_started_s_) * 1e6;
    const double left_us = std::max(0.0, timeout_time_at_start_us_ - used_us);
    team_info(phase_.command == Referee::TIMEOUT_YELLOW ? TeamColor::yellow : TeamColor::blue)
        .set_timeout_time(static_cast<std::uint32_t>(std::llround(left_us)));
  }
  return message_;
}

RefereedSimulation::RefereedSimulation(SimulationConfig vision,
                                       std::optional<GameControllerConfig> game)
    : vision_(vision) {
  if (game) {
    game->opponent_color = vision.opponent_color;
    game->opponent_attacks = vision.opponent_attacks;
    game->start_time_s = vision.start_time_s;
    // The paper's opponent moves on whatever the referee says: a HALT it would not keep.
    game->shape.reset();
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

}  // namespace ssl_formation::simulation
