#include "ssl_formation/match/game_phase.hpp"

#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation {
inline namespace match {

std::string_view to_string(GamePhase phase) {
  switch (phase) {
    case GamePhase::running:
      return "running";
    case GamePhase::stop:
      return "stop";
    case GamePhase::halt:
      return "halt";
    case GamePhase::ball_placement_opponent:
      return "ball_placement_opponent";
    case GamePhase::ball_placement_us:
      return "ball_placement_us";
    case GamePhase::kickoff_opponent:
      return "kickoff_opponent";
    case GamePhase::kickoff_us:
      return "kickoff_us";
    case GamePhase::free_kick_opponent:
      return "free_kick_opponent";
    case GamePhase::free_kick_us:
      return "free_kick_us";
    case GamePhase::penalty:
      return "penalty";
  }
  return "?";
}

std::optional<TeamColor> team_of_command(int command) {
  if (command < Referee::PREPARE_KICKOFF_YELLOW || command > Referee::BALL_PLACEMENT_BLUE) {
    return std::nullopt;
  }
  return command % 2 == 0 ? TeamColor::yellow : TeamColor::blue;
}

void GamePhaseTracker::on_command(int command, double time_s) {
  const bool kick_allowed = command == Referee::NORMAL_START || command == Referee::FORCE_START;
  const bool prepared =
      command_ == Referee::PREPARE_KICKOFF_YELLOW || command_ == Referee::PREPARE_KICKOFF_BLUE ||
      command_ == Referee::PREPARE_PENALTY_YELLOW || command_ == Referee::PREPARE_PENALTY_BLUE;
  restart_ = kick_allowed && prepared ? command_ : -1;
  command_ = command;
  command_start_s_ = time_s;
}

GamePhase GamePhaseTracker::phase(double time_s, TeamColor opponent) const {
  const auto by_team = [&](int command, GamePhase theirs, GamePhase ours) {
    return team_of_command(command) == opponent ? theirs : ours;
  };
  const bool recent = time_s - command_start_s_ < restart_window_s;
  switch (command_) {
    case Referee::HALT:
    case Referee::TIMEOUT_YELLOW:
    case Referee::TIMEOUT_BLUE:
      return GamePhase::halt;
    case Referee::STOP:
    case Referee::GOAL_YELLOW:
    case Referee::GOAL_BLUE:
      return GamePhase::stop;
    case Referee::BALL_PLACEMENT_YELLOW:
    case Referee::BALL_PLACEMENT_BLUE:
      return by_team(command_, GamePhase::ball_placement_opponent, GamePhase::ball_placement_us);
    case Referee::PREPARE_KICKOFF_YELLOW:
    case Referee::PREPARE_KICKOFF_BLUE:
      return by_team(command_, GamePhase::kickoff_opponent, GamePhase::kickoff_us);
    case Referee::PREPARE_PENALTY_YELLOW:
    case Referee::PREPARE_PENALTY_BLUE:
      return GamePhase::penalty;
    case Referee::DIRECT_FREE_YELLOW:
    case Referee::DIRECT_FREE_BLUE:
    case Referee::INDIRECT_FREE_YELLOW:
    case Referee::INDIRECT_FREE_BLUE:
      return recent ? by_team(command_, GamePhase::free_kick_opponent, GamePhase::free_kick_us)
                    : GamePhase::running;
    case Referee::NORMAL_START:
    case Referee::FORCE_START:
      if (!recent || restart_ < 0) return GamePhase::running;
      if (restart_ == Referee::PREPARE_PENALTY_YELLOW ||
          restart_ == Referee::PREPARE_PENALTY_BLUE) {
        return GamePhase::penalty;
      }
      return by_team(restart_, GamePhase::kickoff_opponent, GamePhase::kickoff_us);
    default:
      // No referee heard (or a command this build does not know): play as far as we can tell.
      return GamePhase::running;
  }
}

}  // namespace match
}  // namespace ssl_formation
