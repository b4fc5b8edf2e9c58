#pragma once
// A simulated opponent that moves like a team (issue 15): the opponent runs a playbook's plays,
// each step's targets held for a while with variation from run to run and loose play between
// plays; our team marks it man to man; both goalkeepers keep to their lines; the ball goes with
// the play (at the holder's feet, passed, shot). Every robot drives within SSL robots' speed and
// acceleration (TeamMotion), so nothing jumps; frames come at the frame rate, as SSL-Vision
// sends them, split among cameras, with noise and lost packets if asked.
//
// With a game controller the match follows its referee as the rules have robots do: in HALT and
// timeouts every robot brakes and stands exactly still, in STOP and ball placement robots drive
// at 1.5 m/s at most and keep out of 0.5 m around the ball (but the robot placing it), free kicks
// are taken the shape's kick delay after their command. With a GameShape (the default) the
// referee also stops the play for what the match does not play out (a foul): the match then says
// where the ball is to be placed.
//
// Deterministic for a seed. Positions are normalised (the opponent attacks +x) until they are
// put on the wire, where the opponent attacks `opponent_attacks`.
//
//   MatchSimulation match(config);
//   const MatchFrame frame = match.next();  // frame.packets: geometry when due, then detections

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/simulation/playbook.hpp"
#include "ssl_formation/simulation/robot_motion.hpp"
#include "ssl_formation/simulation/simulated_game_controller.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::simulation {

enum class Division { a, b };
// 11 robots a team on 12 x 9 m (A), 6 on 9 x 6 m (B).
int team_size_of(Division division);
FieldSize field_of(Division division);

struct MatchSimulationConfig {
  std::uint64_t seed = 1;
  Division division = Division::a;
  Playbook playbook;  // at least one play
  double frame_rate_hz = 60.0;
  double start_time_s = 0.0;  // t_capture of the first frame
  int cameras = 4;
  double camera_overlap_mm = 200.0;
  double jitter_mm = 0.0;  // Gaussian noise on every detected position
  double drop_rate = 0.0;  // probability that a camera's packet is lost
  TeamColor opponent_color = TeamColor::yellow;
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  double geometry_interval_s = 3.0;
  MotionLimits limits;
  // How much a play's run varies: targets move by up to this fraction of the half field, and
  // steps are held from (1 - v) to (1 + v) times as long.
  double position_variation = 0.06;
  double timing_variation = 0.25;
  // Loose play between two plays lasts a uniform time in this range (seconds).
  double loose_play_min_s = 1.5;
  double loose_play_max_s = 4.0;
  // The match's game controller, its stoppages called by the play (a goal, the ball out of the
  // field) and, with its shape (the default: a game shaped like real ones, docs/simulation.md), by
  // the referee; its colour, side and start time are the match's. None: no referee, and restarts
  // happen at once.
  std::optional<GameControllerConfig> game;
};

struct MatchFrame {
  std::uint64_t index = 0;
  double t_capture = 0.0;
  std::uint32_t frame_number = 0;
  std::vector<Point> opponent;  // normalised mm, by robot id (before noise)
  std::vector<Point> ours;      // normalised mm, by robot id
  Point ball;                   // normalised mm
  std::string play;             // what the opponent runs now; "" in loose play
  int play_step = -1;           // -1 in loose play, and before a restart's kick
  AttackDirection opponent_attacks = AttackDirection::positive_x;  // in the feed, now
  // The game controller's message, sent before the frame's packets; none without one.
  std::optional<Referee> referee;
  // What goes on the wire for this frame, in order: a geometry packet when one is due, then one
  // detection packet per camera (minus the dropped ones).
  std::vector<SSL_WrapperPacket> packets;
  int dropped_packets = 0;
};

class MatchSimulation {
 public:
  // Throws std::invalid_argument for a config it cannot run (no plays, a frame rate that is not
  // positive, cameras outside 1 to 8, ...).
  explicit MatchSimulation(MatchSimulationConfig config);

  MatchFrame next();

  const MatchSimulationConfig& config() const { return config_; }
  const FieldSize& field() const { return field_; }
  // Every robot, the opponent's first (ids 0 to n-1), then ours.
  const TeamMotion& robots() const { return robots_; }
  std::uint64_t plays_started() const { return plays_started_; }
  std::uint64_t passes() const { return passes_; }
  std::uint64_t shots() const { return shots_; }
  std::uint64_t goals() const { return goals_; }
  const SimulatedGameController* game_controller() const { return game_ ? &*game_ : nullptr; }

 private:
  // What the robots do, as the referee's command has it.
  enum class Mode {
    opponent_play,        // running play, the opponent's ball (or nobody's)
    our_possession,       // running play, our ball until the opponent wins it back
    stopped,              // STOP: slow, away from the ball
    halted,               // HALT and timeouts: every robot brakes and stands still
    kickoff_preparation,  // both teams in their halves, the kicker at the ball
    ball_placement,       // the ball carried to where the free kick will be
    lining_up,            // a STOP before a half's kick-off: the teams walk to their places
  };

  struct Ball {
    Point position;
    Point velocity;
    int holder = -1;       // the robot (index into robots_) with the ball; -1 if none
    int receiver = -1;     // who is to have it next (index): a pass's target or a fetcher
    bool rolling = false;  // a pass on its way to the receiver
    bool shot = false;     // on its way to the goal
  };

  void start_play(double now_s, PlayRestart restart);
  void start_loose_play(double now_s);
  void advance_play(double now_s);
  // Sets the opponent's targets for the current step, with this run's variation.
  void aim_at_step();
  // Who has the ball after `step` (it names one): its robot, or for one the division does not
  // field, the robot nearest to that robot's target.
  int receiver_for(const PlayStep& step) const;
  void update_targets(double now_s);
  void move_ball(double dt_s, double now_s);
  // A shot over the goal line: a goal and a kick-off, or wide and a free kick.
  void restart(double now_s);
  // Follows a new command or stage of the game controller's.
  void follow_referee(const Referee& message, double now_s);
  // The ball over the goal line after a shot, with a game controller: a goal, a corner for the
  // opponent or a goal kick for us, each called as the stoppage it is.
  void call_stoppage(double now_s);
  // The referee stops the play for what the match does not play out (GameShape): a foul, a
  // free kick for either team, the ball placed a few metres from where it is.
  void call_foul(double now_s);
  // Our side wins the ball (a goal kick, our kick-off): it keeps it for a while.
  void start_our_possession(double now_s);
  bool ours(int robot) const { return robot >= team_size_; }
  Point robot_position(int robot) const {
    return robots_.position(static_cast<std::size_t>(robot));
  }
  void build_packets(MatchFrame& frame);
  Point on_field(Point fraction) const;  // a playbook point in normalised mm
  Point inside_field(Point p) const;

  MatchSimulationConfig config_;
  std::optional<SimulatedGameController> game_;
  AttackDirection attacks_;  // where the opponent attacks in the feed now
  Mode mode_ = Mode::opponent_play;
  std::uint32_t command_counter_ = 0;  // the last command followed
  int stage_ = -1;                     // the last stage followed
  double possession_ends_s_ = 0.0;     // our possession: when the opponent wins the ball
  bool holding_play_ = false;          // a restart's play waits at its first step
  // The held play's own taker kicks (a kick-off, or a corner: it places the ball where it
  // starts); else the robot nearest to the ball (after a foul, it places it) kicks, a pass to
  // the play's first receiver.
  bool taker_kicks_ = true;
  bool kickoff_by_opponent_ = true;  // whose kick-off is being prepared
  Point placement_;                  // where the ball is being placed (normalised)
  Point placement_behind_;           // where the placing robot stands from the ball it carries
  double kick_at_s_ = 0.0;           // a free kick: its taker waits with the ball until then
  FieldSize field_;
  int team_size_ = 0;
  std::mt19937_64 random_;
  std::mt19937_64 noise_random_;
  TeamMotion robots_;
  std::vector<Point> targets_;       // every robot's target, normalised mm
  std::vector<Point> play_targets_;  // the opponent's targets from the play, by robot id
  Ball ball_;

  int play_ = -1;  // index into the playbook; -1 in loose play
  int step_ = 0;
  double step_ends_s_ = 0.0;
  std::vector<Point> play_offsets_;  // this run's variation, one per robot id
  double hold_scale_ = 1.0;

  std::uint64_t frames_ = 0;
  std::uint32_t frame_number_ = 0;
  GeometrySchedule geometry_;
  std::uint64_t plays_started_ = 0;
  std::uint64_t passes_ = 0;
  std::uint64_t shots_ = 0;
  std::uint64_t goals_ = 0;
};

}  // namespace ssl_formation::simulation
