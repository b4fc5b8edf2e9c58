#pragma once
// The paper's simulated vision (§4.1): three pre-designed plays of three formations each, for six
// opponent robots on a Division B field, and random formations. Each cycle picks uniformly among
// {one random formation, play 1, play 2, play 3}, so 90% of formations come from plays.
//
// Deterministic for a seed: the same seed gives the same packets, which is what lets tests
// compare a daemon's table with the library's.

#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::simulation {

inline constexpr int robots_per_team = 6;
inline constexpr int play_count = 3;
inline constexpr int formations_per_play = 3;

using TeamPositions = std::array<Point, robots_per_team>;  // index = robot id, normalised mm

// Play p (0-based), formation f: positions with the opponent attacking +x on a 9 x 6 m field.
const TeamPositions& play_formation(int play, int formation);

struct SimulationConfig {
  std::uint64_t seed = 1;
  double step_s = 2.0;        // data clock advance per formation
  double start_time_s = 0.0;  // t_capture of the first formation
  int cameras = 1;
  double camera_overlap_mm = 200.0;
  double jitter_mm = 0.0;  // Gaussian noise on every detected position
  double drop_rate = 0.0;  // probability that a camera's packet is lost
  TeamColor opponent_color = TeamColor::yellow;
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  FieldSize field{9000.0, 6000.0};
  double geometry_interval_s = 3.0;  // of data time
};

enum class FormationSource { random, play };

struct SimulatedFormation {
  std::uint64_t index = 0;  // 0, 1, 2, ... in order
  FormationSource source = FormationSource::random;
  int play = -1;       // 0-2 when source == play
  int play_step = -1;  // 0-2 when source == play
  double t_capture = 0.0;
  std::uint32_t frame_number = 0;
  TeamPositions opponent;  // normalised, before jitter
  // What goes on the wire for this formation, in order: a geometry packet when one is due, then
  // one detection packet per camera (minus the dropped ones).
  std::vector<SSL_WrapperPacket> packets;
  int dropped_packets = 0;
};

// What a simulation's instant looks like to SSL-Vision's cameras, in the feed's coordinates.
struct SeenInstant {
  std::uint32_t frame_number = 0;
  double t_capture = 0.0;
  TeamColor opponent_color = TeamColor::yellow;
  std::span<const Point> opponent;  // by robot id
  std::span<const Point> ours;      // by robot id
  float opponent_facing = 0.0F;
  float our_facing = 0.0F;
  Point ball;
};

struct CameraLayout {
  int cameras = 1;
  FieldSize field{9000.0, 6000.0};
  double overlap_mm = 200.0;
  double drop_rate = 0.0;  // probability that a camera's packet is lost
};

// Appends one detection packet per camera of `layout` to `packets`: the robots and the ball in
// its area (overlaps seen twice), each packet lost with the drop rate (drawn from `random` once
// a packet is built, camera by camera). Returns how many were lost. Both simulations' packets
// come from here.
int append_camera_packets(const CameraLayout& layout, const SeenInstant& instant,
                          std::mt19937_64& random, std::vector<SSL_WrapperPacket>& packets);

// Throws std::invalid_argument unless there are 1 to 8 cameras, the drop rate is a probability
// and the jitter a finite, non-negative number of millimetres: what both simulations check.
void check_camera_settings(int cameras, double drop_rate, double jitter_mm);

// SSL-Vision sends its geometry now and then: at the first instant, then once `interval_s` has
// passed since the last.
class GeometrySchedule {
 public:
  explicit GeometrySchedule(double interval_s) : interval_s_(interval_s) {}
  // Whether a geometry packet goes with the instant at `t_s` (and, if so, it counts as sent).
  bool due(double t_s) {
    if (sent_ && t_s < next_s_) return false;
    sent_ = true;
    next_s_ = t_s + interval_s_;
    return true;
  }

 private:
  double interval_s_;
  double next_s_ = 0.0;
  bool sent_ = false;
};

class SimulatedVision {
 public:
  explicit SimulatedVision(SimulationConfig config);

  SimulatedFormation next();
  // The t_capture next() gives its formation.
  double next_t_capture() const {
    return config_.start_time_s + static_cast<double>(formations_) * config_.step_s;
  }
  // From the next formation on, the opponent attacks `direction` in the feed (and our team
  // defends the other end): the teams change ends at half time.
  void set_opponent_attacks(AttackDirection direction) { config_.opponent_attacks = direction; }

  const SimulationConfig& config() const { return config_; }

  // The area camera `camera` of `cameras` covers, overlap included (feed coordinates).
  struct Area {
    double min_x, max_x, min_y, max_y;
    bool contains(Point p) const {
      return p.x >= min_x && p.x <= max_x && p.y >= min_y && p.y <= max_y;
    }
  };
  static Area camera_area(int camera, int cameras, const FieldSize& field, double overlap_mm);

 private:
  TeamPositions random_formation();
  void build_packets(SimulatedFormation& formation);

  SimulationConfig config_;
  std::mt19937_64 random_;
  std::uint64_t formations_ = 0;
  std::uint32_t frame_number_ = 0;
  GeometrySchedule geometry_;
  int current_play_ = -1;  // -1: the next formation starts a new cycle
  int current_step_ = 0;
};

}  // namespace ssl_formation::simulation
