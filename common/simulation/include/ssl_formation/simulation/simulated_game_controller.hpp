#pragma once
// The game controller of a simulation: the referee messages that go with the paper's simulated
// opponent or a simulated match, so the daemons, the demo and the tests run with a referee as
// they do at a tournament. It names the teams, runs two halves with the ends
// changed at half time, and stops the play as a real match does: a ball out of the field (STOP,
// ball placement, a free kick), a foul (STOP, a free kick) and a goal (STOP, a kick-off). For
// the paper's opponent, which has no ball, it stops the play at random; a match calls the
// stoppages its ball makes.
//
// With a GameShape (the default for a match) the game spends its time as recorded Division A
// matches do (docs/simulation.md): running play in stretches mostly of a few seconds with a long
// tail, and each stoppage a STOP, now and then a HALT or a team's timeout (then STOP again), most
// restarts after a ball placement of a few seconds, a few with FORCE_START. The referee then also
// stops the play for what a match does not play out (a foul, a robot to take off): the match
// asks stoppage_due() and calls the stoppage with where the ball is to be placed.
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

namespace ssl_formation::simulation {

// A duration drawn from bands by weight, each band uniform: a typical length and a long tail.
struct DurationBands {
  struct Band {
    double weight = 1.0;
    double min_s = 0.0;
    double max_s = 0.0;
  };
  std::vector<Band> bands;
  // Throws std::invalid_argument, naming `what`, unless there is a band, every weight is >= 0
  // and some > 0, and every band has 0 < min <= max, finite.
  void check(const std::string& what) const;
  double draw(std::mt19937_64& random) const;
};

// How a game spends its time, shaped like recorded Division A matches (docs/simulation.md: running
// play 32-43% of the time, halt 13-20%, timeout 0-4%, ball placement 26-29%, stop 11-14%, free
// kicks 2-3%, kick-offs under 1%; running stretches of a median 1-3 s, 90th percentile 10-14 s;
// placements of 4-6 s, halts of 5-6 s; a free kick taken 0.7 s after its command). The defaults
// give a simulated match about those shares (tests/simulation/match_shape_test.cpp measures
// them); the long tails make the means longer than the medians, as in the recordings.
struct GameShape {
  // Running play from its restart to the next stoppage the referee calls (a match's own, a shot
  // out of the field, may come first).
  DurationBands running{{{0.5, 0.4, 3.0}, {0.28, 3.0, 14.0}, {0.22, 14.0, 60.0}}};
  // A STOP before what follows it (a HALT, a placement, the restart).
  DurationBands stop{{{1.0, 0.7, 1.8}}};
  // A STOP after a goal, while the teams go back to their halves.
  DurationBands goal_stop{{{1.0, 4.0, 8.0}}};
  DurationBands halt{{{0.75, 4.5, 6.5}, {0.25, 8.0, 25.0}}};
  DurationBands timeout{{{1.0, 10.0, 30.0}}};
  // A ball placement lasts at least this; with a match, until the ball is on its spot (30 s at
  // most, as the rules give it).
  DurationBands ball_placement{{{0.85, 4.0, 6.0}, {0.15, 6.0, 12.0}}};
  // Of the stoppages: the share with a HALT after their STOP, and with a team's timeout.
  double halt_share = 0.27;
  double timeout_share = 0.01;
  // Of the restarts after a foul: the share with FORCE_START (the referee restarts at once, no
  // placement); of the others, the share placed before their free kick (the ball out of the
  // field is always placed).
  double force_start_share = 0.12;
  double placement_share = 0.95;
  // Of the stoppages the game controller makes itself without a match (the paper's opponent
  // has no ball to score with): the share that are goals. Of a match's shots, the share that
  // score (kick-offs take under 1% of a real match) and the share the keeper saves, play going
  // on; the others go out of the field.
  double goal_share = 0.05;
  double shot_goal_share = 0.15;
  double shot_saved_share = 0.4;
  double kickoff_preparation_s = 2.0;
  // The STOP in which the teams walk to their kick-off places after the half-time break.
  double line_up_s = 8.0;
  // A free kick is taken this long after its command (the match takes it).
  double kick_delay_s = 0.7;
  // Throws std::invalid_argument for a shape that makes no game (a share outside 0-1, a band
  // with no length).
  void check() const;
};

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
  // Without a shape: the play between two stoppages lasts a uniform time in this range (data
  // seconds).
  double play_min_s = 30.0;
  double play_max_s = 90.0;
  std::string source_identifier = "ssl-producer";
  // Whether the game controller stops the play itself, at random: the paper's simulation has no
  // ball to go out of the field. A simulated match calls its stoppages (stop_for_goal() and the
  // others) and leaves this off.
  bool random_stoppages = true;
  // How the game spends its time; none: the plain game of earlier versions (STOP, placement,
  // restart; no HALT or timeout outside the breaks). RefereedSimulation (the paper's opponent,
  // which moves on whatever the referee says) plays the plain game.
  std::optional<GameShape> shape = GameShape{};
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
  // empty play range, team names that are the same, a shape that makes no game).
  explicit SimulatedGameController(GameControllerConfig config);

  // The message the game controller sends at data time `t_s`, the script advanced to it. Calls
  // come in non-decreasing time; a time before the previous call's is an error
  // (std::invalid_argument). The reference stays valid until the next call.
  const Referee& message_at(double t_s);

  // Stoppages the match calls at `at_s` (its time, not before the last message_at()'s), in
  // running play; each queues the restart the rules give:
  // - the ball out of the field: STOP, the restarting team places the ball at `placement` (feed
  //   coordinates, mm; the message's designated_position), then its free kick;
  // - a foul: STOP, then the other team's free kick (`restart_team`'s), after a placement at
  //   `placement` if one is given and the shape draws one;
  // - a goal for `scorer`: STOP, then the other team's kick-off.
  // With a shape, a HALT or a timeout may come after the STOP, and a restart may be FORCE_START.
  void stop_for_ball_out(TeamColor restart_team, double at_s, std::optional<Point> placement);
  void stop_for_foul(TeamColor restart_team, double at_s,
                     std::optional<Point> placement = std::nullopt);
  void stop_for_goal(TeamColor scorer, double at_s);
  // With stoppages called by the match, a ball placement lasts until the match says the ball
  // is on its spot (and, with a shape, at least its drawn length): the restart follows.
  void ball_placed(double at_s);
  // With stoppages called by the match and a shape: whether the referee stops the running play
  // at `t_s` (not before the last message_at()'s) for what the match does not play out, its
  // drawn length being over. The match then calls stop_for_foul().
  bool stoppage_due(double t_s) const;

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
  // A stoppage's STOP at `at_s` lasting `stop_s`, and with a shape now and then a HALT or a
  // timeout after it (then STOP again); what follows is queued after.
  void begin_stoppage(double at_s, double stop_s);
  // A free kick for `team` (or with a shape now and then FORCE_START), after a placement at
  // `placement` when `place` (a spot, or none when nobody knows where the ball is).
  void queue_free_kick(TeamColor team, bool place, std::optional<Point> placement);
  void issue(Referee::Command command, double at_s);
  void set_sides();
  TeamColor our_color() const;
  Referee::Command for_team(Referee::Command yellow_command, TeamColor team) const;
  Referee::TeamInfo& team_info(TeamColor team);
  double draw_unit();

  GameControllerConfig config_;
  std::mt19937_64 random_;
  Referee message_;
  ControllerPhase phase_;
  // The phases queued after the current one (a stoppage's STOP, placement, restart).
  struct QueuedPhase {
    Referee::Command command;
    double duration_s;
    // A placement the match carries out: it lasts until the ball is placed, and at least
    // duration_s.
    bool until_placed = false;
  };
  std::vector<QueuedPhase> queued_;
  double half_ends_s_ = 0.0;  // when the running half's play stops for good
  double last_t_s_ = -1e300;
  bool second_half_ = false;
  AttackDirection opponent_attacks_;
  std::optional<Point> placement_;           // where the queued ball placement puts the ball
  double placement_at_least_until_s_ = 0.0;  // a placement the match carries out lasts this long
  // With a shape and stoppages called by the match: when the referee stops the running play.
  double play_stops_s_ = 1e300;
  // A timeout running: the team's timeout time left when it started, and when it started.
  std::uint32_t timeout_time_at_start_us_ = 0;
  double timeout_started_s_ = 0.0;
  std::uint32_t matches_ = 0;
  std::uint32_t yellow_score_ = 0;
  std::uint32_t blue_score_ = 0;
};

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

}  // namespace ssl_formation::simulation
