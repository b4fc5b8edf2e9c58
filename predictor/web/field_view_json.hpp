#pragma once
// The JSON messages the field view page receives over its WebSocket: one "prediction" per
// FormationPrediction the predictor multicasts (with our own robots and the field), and a
// "status" every half second. Pure functions: the server only forwards the text.

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "formation_prediction.pb.h"
#include "ssl_formation/formation.hpp"
#include "ssl_formation/grid.hpp"
#include "team_robots.hpp"

namespace ssl_formation::predictor::web {

// What the page needs to draw the field: its size (from the feed's geometry), the grid and who
// attacks where.
struct FieldViewSetup {
  FieldSize field;
  Grid grid{3, 2};
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  TeamColor opponent_color = TeamColor::yellow;
};

// {"type":"prediction","frame":..,"t":..,"field":{..},"grid":{..},"centroid":{"cell":[x,y],
//  "centre":[x,y]},"opponent":[{"id","x","y","cell"}],"ours":[{"id","x","y"}],
//  "steps":[{"step","centroid":{..},"centroid_p","centroid_unseen","formation_p","confidence",
//  "robots":[{"id","cell","centre":[x,y],"p","unseen"}]}],...}
// Cell centres are in the feed's coordinates (the attack-direction rotation undone).
std::string prediction_json(const proto::FormationPrediction& message, const FieldViewSetup& setup,
                            std::span<const TeamRobot> ours);

struct FieldViewStatus {
  FieldViewSetup setup;
  std::uint64_t packets = 0;
  double packets_per_s = 0.0;
  std::optional<double> since_packet_s;  // wall seconds since the last datagram; none yet: empty
  std::uint64_t parse_errors = 0;
  std::uint64_t kernel_drops = 0;
  std::uint64_t formations = 0;
  std::uint64_t predictions = 0;
  bool table_loaded = false;
  std::uint64_t table_transitions = 0;
  std::uint64_t table_formations = 0;
  std::uint64_t table_states_seen = 0;
  std::uint64_t table_reloads = 0;
  std::optional<std::int64_t> table_loaded_unix_ms;  // wall clock of the last (re)load
  std::string table_error;                           // the last failed load, if any
  std::uint64_t clients = 0;
  std::uint64_t dropped_frames = 0;
  std::span<const TeamRobot> ours;
};

std::string status_json(const FieldViewStatus& status);

}  // namespace ssl_formation::predictor::web
