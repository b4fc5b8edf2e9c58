// What an instance is filed under: the features, the key codec, the regressors, and the whole
// millimetres an instance keeps.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "ssl_formation/motion_model/motion_model.hpp"
#include "whole_mm.hpp"

namespace ssl_formation {
inline namespace motion_model {

std::int32_t whole_mm(double value) { return detail::whole_mm_of(value); }

WholePoint whole_mm(Point p) { return detail::whole_mm_of(p); }

bool MotionConfig::valid() const {
  return std::isfinite(step_s) && step_s > 0.0 && horizons >= 1 && horizons <= max_horizons &&
         std::isfinite(velocity_window_s) && velocity_window_s > 0.0 &&
         std::isfinite(settle_window_s) && settle_window_s > 0.0 &&
         std::isfinite(long_settle_window_s) && long_settle_window_s > 0.0 &&
         std::isfinite(tolerance_s) && tolerance_s >= 0.0 && std::isfinite(calibration_block_s) &&
         calibration_block_s > 0.0 && calibration_one_in >= 2 && calibration_capacity >= 1;
}

int MotionFeatures::cell(Point p) {
  const int x = clamped_cell((p.x + cells_x * cell_mm / 2.0) / cell_mm, cells_x);
  const int y = clamped_cell((p.y + cells_y * cell_mm / 2.0) / cell_mm, cells_y);
  return x * cells_y + y;
}

int MotionFeatures::team_phase(Point centroid, Point team_velocity) {
  const int place = centroid.x < -team_place_edge_mm ? 0 : centroid.x <= team_place_edge_mm ? 1 : 2;
  const bool moving = team_velocity.x * team_velocity.x + team_velocity.y * team_velocity.y >=
                      speed_limits_mm_s[0] * speed_limits_mm_s[0];
  return place * 2 + (moving ? 1 : 0);
}

int MotionFeatures::velocity_class(Point v) {
  const double speed_squared = v.x * v.x + v.y * v.y;
  int band = 0;
  while (band < static_cast<int>(speed_limits_mm_s.size()) &&
         speed_squared >= speed_limits_mm_s[band] * speed_limits_mm_s[band]) {
    ++band;
  }
  if (band == 0) return 0;
  // Eight sectors of 45 degrees centred on +x, +x+y, +y, ... (counter-clockwise), told apart
  // by comparisons with tan(22.5 degrees) rather than an atan2 per robot and frame.
  static_assert(directions == 8);
  constexpr double tan_22_5 = 0.41421356237309503;
  const double ax = std::abs(v.x), ay = std::abs(v.y);
  int sector = 0;
  if (ay <= tan_22_5 * ax) {
    sector = v.x > 0.0 ? 0 : 4;
  } else if (ax <= tan_22_5 * ay) {
    sector = v.y > 0.0 ? 2 : 6;
  } else {
    sector = v.x > 0.0 ? (v.y > 0.0 ? 1 : 7) : (v.y > 0.0 ? 3 : 5);
  }
  return 1 + (band - 1) * directions + sector;
}

std::uint32_t MotionFeatures::standing_context(double standing_s) {
  std::uint32_t bin = 1;
  for (const double limit : standing_limits_s) {
    if (standing_s < limit) return bin;
    ++bin;
  }
  return bin;
}

std::uint32_t MotionFeatures::game_context(GamePhase phase, double since_command_s) {
  if (phase == GamePhase::running) return running_game;
  if (phase == GamePhase::halt) return halt_game;
  // The other phases in all_game_phases' order after running and halt, three buckets each.
  std::uint32_t index = 0;
  for (const GamePhase p : all_game_phases) {
    if (p == GamePhase::running || p == GamePhase::halt) continue;
    if (p == phase) break;
    ++index;
  }
  std::uint32_t bucket = 0;
  while (bucket < since_command_limits_s.size() &&
         !(since_command_s < since_command_limits_s[bucket])) {
    ++bucket;
  }
  return 2 + index * since_command_buckets + bucket;
}

GamePhase MotionFeatures::phase_of_game_context(std::uint32_t game_context) {
  if (game_context == running_game || game_context >= game_contexts) return GamePhase::running;
  if (game_context == halt_game) return GamePhase::halt;
  std::uint32_t index = (game_context - 2) / since_command_buckets;
  for (const GamePhase p : all_game_phases) {
    if (p == GamePhase::running || p == GamePhase::halt) continue;
    if (index == 0) return p;
    --index;
  }
  return GamePhase::running;
}

int MotionFeatures::zone_of_cell(int cell) {
  // The cell's centre decides (no cell straddles an edge: the edges are multiples of cell_mm).
  const auto band = [](double centre_mm, const auto& edges) {
    int index = 0;
    while (index < static_cast<int>(edges.size()) && centre_mm >= edges[index]) ++index;
    return index;
  };
  const double x = (cell / cells_y + 0.5) * cell_mm - cells_x * cell_mm / 2.0;
  const double y = (cell % cells_y + 0.5) * cell_mm - cells_y * cell_mm / 2.0;
  return band(x, zone_length_edges_mm) * zones_y + band(y, zone_width_edges_mm);
}

namespace {
// Bit fields of a key, low to high: context 24, velocity class 8, cell 12, robot slot 8,
// level 4, horizon 8.
constexpr int context_shift = 0, velocity_shift = 24, cell_shift = 32, slot_shift = 44,
              level_shift = 52, horizon_shift = 56;
std::uint64_t field(MotionKey key, int shift, int bits) {
  return (key >> shift) & ((std::uint64_t{1} << bits) - 1);
}
}  // namespace

MotionKeyParts motion_key_parts(int horizon_index, const MotionInstance& i) {
  MotionKeyParts p;
  p.horizon_index = horizon_index;
  p.level = MotionLevel::robot;
  p.robot_slot = MotionFeatures::robot_slot(i.robot_id);
  p.cell = MotionFeatures::cell({static_cast<double>(i.x), static_cast<double>(i.y)});
  p.velocity_class =
      MotionFeatures::velocity_class({static_cast<double>(i.v_x), static_cast<double>(i.v_y)});
  p.context = i.context;
  return p;
}

MotionKey encode_motion_key(MotionKeyParts p) {
  switch (p.level) {
    case MotionLevel::all:
      p.velocity_class = 0;
      [[fallthrough]];
    case MotionLevel::velocity:
      p.cell = 0;
      // The coarse levels keep the game context alone: in HALT or STOP every robot's motion
      // differs from running play's whatever its place.
      p.context = MotionFeatures::robot_contexts * MotionFeatures::game_context_of(p.context);
      [[fallthrough]];
    case MotionLevel::zone:
      p.robot_slot = 0;
      [[fallthrough]];
    case MotionLevel::robot:
      break;
  }
  return static_cast<MotionKey>(p.horizon_index) << horizon_shift |
         static_cast<MotionKey>(p.level) << level_shift |
         static_cast<MotionKey>(p.robot_slot) << slot_shift |
         static_cast<MotionKey>(p.cell) << cell_shift |
         static_cast<MotionKey>(p.velocity_class) << velocity_shift |
         static_cast<MotionKey>(p.context & 0xffffffu) << context_shift;
}

MotionKeyParts decode_motion_key(MotionKey key) {
  MotionKeyParts p;
  p.horizon_index = static_cast<int>(field(key, horizon_shift, 8));
  p.level = static_cast<MotionLevel>(field(key, level_shift, 4));
  p.robot_slot = static_cast<int>(field(key, slot_shift, 8));
  p.cell = static_cast<int>(field(key, cell_shift, 12));
  p.velocity_class = static_cast<int>(field(key, velocity_shift, 8));
  p.context = static_cast<std::uint32_t>(field(key, context_shift, 24));
  return p;
}

MotionKey coarser_motion_key(MotionKey key) {
  MotionKeyParts p = decode_motion_key(key);
  if (p.level == MotionLevel::robot) p.cell = MotionFeatures::zone_of_cell(p.cell);
  if (p.level != MotionLevel::all)
    p.level = static_cast<MotionLevel>(static_cast<int>(p.level) + 1);
  return encode_motion_key(p);
}

MotionRegressors motion_regressors_of(const MotionKinematics& k, double horizon_s) {
  return {Point{k.velocity.x * horizon_s, k.velocity.y * horizon_s},
          Point{k.velocity_change.x * horizon_s, k.velocity_change.y * horizon_s}, k.to_recent_mean,
          k.to_settled_mean, Point{k.team_velocity.x * horizon_s, k.team_velocity.y * horizon_s}};
}

MotionKinematics MotionInstance::kinematics() const {
  const auto p = [](std::int32_t px, std::int32_t py) {
    return Point{static_cast<double>(px), static_cast<double>(py)};
  };
  return {p(v_x, v_y), p(a_x, a_y), p(g_x, g_y), p(s_x, s_y), p(t_x, t_y)};
}

}  // namespace motion_model
}  // namespace ssl_formation
