#pragma once
// The JSON messages the field view page receives over its WebSocket: one "prediction" per
// FormationPrediction the predictor multicasts (with our own robots and the field), and a
// "status" every half second. Pure functions: the server only forwards the text.

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "ball_trail.hpp"
#include "field_markings.hpp"
#include "formation_prediction.pb.h"
#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_formation/pipeline/live_score.hpp"
#include "team_robots.hpp"

namespace ssl_formation::predictor::web {

// What the page needs to draw the field: its size and markings (from the feed's geometry, or the
// rules'), the grid and who attacks where.
struct FieldViewSetup {
  FieldSize field;
  Grid grid{3, 2};
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  TeamColor opponent_color = TeamColor::yellow;
  ViewMarkings markings = markings_for(FieldSize{}, std::nullopt);
};

// {"type":"prediction","frame":..,"t":..,"field":{..,"markings":{..}},"grid":{..},
//  "model":"paper"|"motion","centroid":{"cell":[x,y],"centre":[x,y]},
//  "opponent":[{"id","x","y","cell"}],"ours":[{"id","x","y"}],
//  "ball":null|{"x","y","path":[[x,y],..]},
//  "steps":[{"step","horizon_s","centroid":{..},"centroid_p","centroid_unseen","formation_p",
//  "confidence","robots":[{"id","cell","centre":[x,y],"p","unseen"
//  [,"position":[x,y],"radius_50_mm","radius_90_mm"]}]}],...}
// Cell centres and positions are in the feed's coordinates (the attack-direction rotation
// undone). horizon_s is how far ahead the step is (the message's horizon_seconds, or step x
// step_seconds from an older predictor); position and the radii come only for robots whose
// message states them (the motion model), and "model" is "paper" when the message names none.
std::string prediction_json(const proto::FormationPrediction& message, const FieldViewSetup& setup,
                            std::span<const TeamRobot> ours, const BallTrail& ball);

// The figures of LiveScore for the predictions made in one phase of the game.
struct PhaseLiveScore {
  GamePhase phase = GamePhase::running;
  std::vector<LiveScore::Horizon> horizons;
};

struct FieldViewStatus {
  FieldViewSetup setup;
  std::uint64_t packets = 0;
  double packets_per_s = 0.0;
  // Seconds since the last datagram, on the server's own clock (never the data's t_capture, which
  // is the simulator's or camera's); none yet: empty. Written as at least 0.
  std::optional<double> since_packet_s;
  // The server's wall clock (Unix ms) when the last datagram arrived and when this status was
  // written, so a page can tell how old the status itself is without comparing its own clock
  // with the data's.
  std::optional<std::int64_t> last_packet_unix_ms;
  std::optional<std::int64_t> server_unix_ms;
  std::uint64_t parse_errors = 0;
  std::uint64_t kernel_drops = 0;
  std::uint64_t formations = 0;
  std::uint64_t predictions = 0;
  bool table_loaded = false;
  std::uint64_t table_transitions = 0;
  std::uint64_t table_formations = 0;  // the table's metadata.samples
  // The motion model's instances counted in the table; empty for a table without its counts.
  std::optional<std::uint64_t> table_motion_instances;
  std::uint64_t table_states_seen = 0;
  std::uint64_t table_reloads = 0;
  std::optional<std::int64_t> table_loaded_unix_ms;  // wall clock of the last (re)load
  std::string table_error;                           // the last failed load, if any
  std::uint64_t clients = 0;
  std::uint64_t dropped_frames = 0;
  std::span<const TeamRobot> ours;
  const BallTrail* ball = nullptr;  // none: no ball drawn
  // Who the opponent is and why, and the game state (MatchFollower).
  std::string opponent;  // describe(Opponent, side in use): "'Them' blue (referee), attacks ..."
  std::string game_state = "unknown";
  // How far the predictions have lately been, against everyone staying (LiveScore), per step.
  std::vector<LiveScore::Horizon> live_score;
  std::vector<PhaseLiveScore> live_score_by_phase;  // the phases with figures, in their order
  std::string referee = "no referee heard";         // describe(RefereeFollower)
  // What the followed game controller said last, for the page's banner; referee_heard false:
  // none heard.
  bool referee_heard = false;
  RefereeView referee_view;
  GamePhase phase = GamePhase::running;  // the phase of the game now, for the opponent followed
};

// {"type":"status",<setup>,"packets","packets_per_s","since_packet_s","last_packet_unix_ms",
//  "server_unix_ms","parse_errors","kernel_drops","formations","predictions",
//  "table":{"loaded","transitions","formations","motion_instances","states_seen","reloads",
//  "loaded_unix_ms","error"},"clients","dropped_frames","ours":[..],"ball":..,
//  "match":{"opponent","game_state","phase","referee","heard","stage","for_team":"opponent"|"us",
//  "yellow","blue","designated_position":[x,y]},
//  "live_score":[{"horizon_s","model_mm","persistence_mm","robots"}],
//  "live_score_by_phase":[{"phase","horizons":[..]}]} (null for what is unknown)
std::string status_json(const FieldViewStatus& status);

}  // namespace ssl_formation::predictor::web
