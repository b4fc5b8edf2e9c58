#pragma once
// The game controller of a simulation: the referee messages (DESIGN.md §6) that go with the
// paper's simulated opponent or a simulated match, so the daemons, the demo and the tests run
// with a referee as they do at a tournament. It names the teams, runs two halves with the ends
// changed at half time, and stops the play as a real match does: a ball out of the field (STOP,
// ball placement, a free kick), a foul (STOP, a free kick) and a goal (STOP, a kick-off). For
// the paper's opponent, which has no ball, it stops the play at random; a match calls the
// stoppages its ball makes.
//
// Time is the simulation's data time (t_capture). The game controller decides at each formation
// what holds from that formation on, so every command starts at a formation and no formation
// straddles two. Deterministic for a seed, from a random stream of its own: the vision of a seed
// is the same with and without a referee.
//
//   RefereedSimulation simulation(vision_config, game_config);
//   const RefereedFormation step = simulation.next();
//   // send step.referee, then step.formation.packets

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation::sim {

struct GameControllerConfig {
  std::uint64_t seed = 1;
  std::string opponent_name = "Simulated Opponent";
  std::string our_name = "ssl-formation";
  TeamColor opponent_color = TeamColor::yellow;
  AttackDirection opponent_attacks = AttackDirection::positive_x;  // in the first half
  // The data time the match starts at.
  double start_time_s = 0.0;
  double half_s = 300.0;      // of data time: Division B's five minutes
  double half_time_s = 20.0;  // the break, shortened: nobody wants to watch robots stand
  // The play between two stoppages lasts a uniform time in this range (data seconds).
  double play_min_s = 30.0;
  double play_max_s = 90.0;
  std::string source_identifier = "ssl-producer";
  // Whether the game controller stops the play itself, at random: the paper's simulation has no
  // ball to go out of the field. A simulated match calls its stoppages (stop_for_goal() and the
  // others) and leaves this off.
  bool random_stoppages = true;
};

// What the match looks like at one moment.
struct ControllerPhase {
  Referee::Stage stage = Referee::NORMAL_FIRST_HALF_PRE;
  Referee::Command command = Referee::HALT;
  double until_s = 0.0;  // data time the phase ends at (the next phase starts)
};

class SimulatedGameController {
 public:
  // Throws std::invalid_argument for a config that makes no match (a non-positive half, an
  // empty play range, team names that are the same).
  explicit SimulatedGameController(GameControllerConfig config);

  // The message the game controller sends at data time `t_s`, the script advanced to it. Calls
  // come in non-decreasing time; a time before the previous call's is an error
  // (std::invalid_argument). The reference stays valid until the next call.
  const Referee& message_at(double t_s);

  // Stoppages the match calls at `at_s` (its time, not before the last message_at()'s), in
  // running play; each queues the restart the rules give:
  // - the ball out of the field: STOP, the restarting team places the ball at `placement` (feed
  //   coordinates, mm; the message's designated_position), then its free kick;
  // - a foul: STOP, then the other team's free kick (`restart_team`'s);
  // - a goal for `scorer`: STOP, then the other team's kick-off.
  void stop_for_ball_out(TeamColor restart_team, double at_s, std::optional<Point> placement);
  void stop_for_foul(TeamColor restart_team, double at_s);
  void stop_for_goal(TeamColor scorer, double at_s);
  // With stoppages called by the match, a ball placement lasts until the match says the ball
  // is on its spot: the restart follows from `at_s`.
  void ball_placed(double at_s);

  // The side the opponent attacks at the last message_at() time (the ends change at half time).
  AttackDirection opponent_attacks() const { return opponent_attacks_; }
  GameState state() const;
  const GameControllerConfig& config() const { return config_; }
  std::uint32_t matches_started() const { return matches_; }
  // The message as it stands (after the last message_at()).
  const Referee& message() const { return message_; }

 private:
  // Moves to the phase after the current one, which starts at `from_s`.
  void advance(double from_s);
  void start_match(double at_s);
  // A stoppage drawn at random, starting with its STOP at `at_s`: a ball out of the field, a
  // foul or a goal, with the restart queued after it.
  void start_stoppage(double at_s);
  void issue(Referee::Command command, double at_s);
  void set_sides();
  TeamColor our_color() const;
  Referee::Command for_team(Referee::Command yellow_command, TeamColor team) const;

  GameControllerConfig config_;
  std::mt19937_64 random_;
  Referee message_;
  ControllerPhase phase_;
  // The phases queued after the current one (a stoppage's STOP, placement, restart).
  struct QueuedPhase {
    Referee::Command command;
    double duration_s;
  };
  std::vector<QueuedPhase> queued_;
  double half_ends_s_ = 0.0;  // when the running half's play stops for good
  double last_t_s_ = -1e300;
  bool second_half_ = false;
  AttackDirection opponent_attacks_;
  std::optional<Point> placement_;  // where the queued ball placement puts the ball
  std::uint32_t matches_ = 0;
  std::uint32_t yellow_score_ = 0;
  std::uint32_t blue_score_ = 0;
};

// "match 1, NORMAL_SECOND_HALF, game running, opponent attacks -x, score 1:0 (yellow:blue)",
// for status lines.
std::string describe(const SimulatedGameController& game_controller);

struct RefereedFormation {
  // Sent first, on the referee group (live) or as a type-3 message (a log); none without a game
  // controller.
  std::optional<Referee> referee;
  SimulatedFormation formation;
};

// The paper's simulated vision with, optionally, its game controller: the opponent changes ends
// when the game controller says so. What ssl-producer sends and writes.
class RefereedSimulation {
 public:
  RefereedSimulation(SimulationConfig vision, std::optional<GameControllerConfig> game);

  RefereedFormation next();

  const SimulatedVision& vision() const { return vision_; }
  const SimulatedGameController* game_controller() const { return game_ ? &*game_ : nullptr; }

 private:
  SimulatedVision vision_;
  std::optional<SimulatedGameController> game_;
};

}  // namespace ssl_formation::sim
