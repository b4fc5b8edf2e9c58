#pragma once
// The phase of the game as the team being predicted lives it: the referee's state, whose restart
// it is (the opponent's or ours), and the first seconds of a restart after the kick is allowed,
// when a set play unfolds. What the evaluation breaks its tables into, on the data clock.
//
//   running                   play goes on (and every instant of a feed without a referee)
//   stop                      STOP (and the deprecated GOAL_*)
//   halt                      HALT and timeouts: no robot may move
//   ball_placement_*          a ball placement, by the team placing
//   kickoff_*                 a kick-off: its preparation and the first restart_window_s after
//                             NORMAL_START, by the kicking team
//   free_kick_*               a free kick: the first restart_window_s after its command (the kick
//                             is allowed at once), by the kicking team
//   penalty                   a penalty: its preparation and the first restart_window_s after
//                             NORMAL_START, either team
// "opponent" is the team being predicted, "us" the other.

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/match/referee.hpp"

namespace ssl_formation {
inline namespace match {

enum class GamePhase : std::uint8_t {
  running,
  stop,
  halt,
  ball_placement_opponent,
  ball_placement_us,
  kickoff_opponent,
  kickoff_us,
  free_kick_opponent,
  free_kick_us,
  penalty,
};
inline constexpr std::array<GamePhase, 10> all_game_phases{GamePhase::running,
                                                           GamePhase::stop,
                                                           GamePhase::halt,
                                                           GamePhase::ball_placement_opponent,
                                                           GamePhase::ball_placement_us,
                                                           GamePhase::kickoff_opponent,
                                                           GamePhase::kickoff_us,
                                                           GamePhase::free_kick_opponent,
                                                           GamePhase::free_kick_us,
                                                           GamePhase::penalty};
std::string_view to_string(GamePhase phase);  // "ball_placement_opponent", ...

// The team a command is for (a kick-off, a free kick, a placement, a timeout: yellow's have even
// numbers, blue's odd ones); none for HALT, STOP, NORMAL_START, FORCE_START.
std::optional<TeamColor> team_of_command(int command);

class GamePhaseTracker {
 public:
  // How long after the kick is allowed a restart still counts as one.
  static constexpr double restart_window_s = 3.0;

  // The referee's new command (Referee::Command's number), in effect from the sample at `time_s`
  // on the data clock. Every command counts, also two that came between the same two samples (a
  // kick-off prepared and started at once).
  void on_command(int command, double time_s);
  void on_command(const RefereeView& view, double time_s) { on_command(view.command, time_s); }
  // Forgets the commands (a new stream).
  void reset() { *this = GamePhaseTracker{}; }

  // The phase at `time_s` (not before the last command's), for the team of `opponent`'s colour.
  GamePhase phase(double time_s, TeamColor opponent) const;
  // Seconds since the current command took effect (infinity before any).
  double since_command_s(double time_s) const {
    return command_ < 0 ? std::numeric_limits<double>::infinity() : time_s - command_start_s_;
  }

 private:
  int command_ = -1;  // Referee::Command's number; -1: none yet
  double command_start_s_ = 0.0;
  // The restart the current running play comes from (a kick-off or penalty prepared, then
  // NORMAL_START), while it is recent: the prepare command, or -1.
  int restart_ = -1;
};

}  // namespace match
}  // namespace ssl_formation
