#pragma once
// The opponent's kick-offs as it played them, and a kick-off now forecast from the nearest of
// them (issue 29). A team's kick-off is its most repeated set play: the ball on the centre spot,
// every robot at a place of its own, the same routine after NORMAL_START match after match
// (restarts are where a team's set plays repeat, docs/simulation.md). The motion model's
// rows file a robot by its 0.5 m cell and velocity, so a routine's few runs are split among
// many rows and held towards what every robot does; here a run is kept whole.
//
// Training records an episode per kick-off of the opponent's: the formation 10 times a second
// from the prepare command to the end of its restart window, and on for the table's horizons
// (where the robots went). Forecasting at a kick-off of the opponent's takes the earlier
// snapshots of the same stage (preparation or taken) within `since_tolerance_s` of the same
// seconds since the command, ranks them by how far the formation is from today's (mean squared
// distance over the robots seen in both, the robot's own distance weighed `own_weight` times
// more), and moves the forecast towards where the robot went from the `analogs` nearest, by a
// weight that grows with how near they are (a Gaussian of `formation_scale_mm`, against
// `prior_weight`). On the tuning seeds 11/12 (and 13/14, and 11/12 with 3 mm of noise) the
// opponent's kick-offs at 1 s were 24-37% nearer than the model alone.
//
// Episodes are kept in their sorted order, so two memories merge into the one training on both
// streams gives, whatever the order.
#include <array>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/match/game_phase.hpp"

namespace ssl_formation {
inline namespace motion_model {

// Where a kick-off stands: prepared (before NORMAL_START), taken (after it, within the restart
// window) or over (later: kept only as where the robots went).
enum class SetPlayStage : std::uint32_t { preparation = 0, taken = 1, over = 2 };
inline constexpr std::uint32_t set_play_stages = 3;

struct SetPlaySnapshot {
  static constexpr int robot_slots = 16;  // robot ids 0-15 (SSL's ids)
  std::int32_t offset_ms = 0;             // since the episode's first snapshot
  std::int32_t since_command_ms = 0;
  SetPlayStage stage = SetPlayStage::preparation;
  std::uint32_t seen = 0;                                           // a bit per robot id
  std::array<std::array<std::int32_t, 2>, robot_slots> position{};  // normalised, whole mm
  bool has(std::uint32_t robot_id) const { return robot_id < 16 && (seen >> robot_id & 1U) != 0; }
  Point at(std::uint32_t robot_id) const {
    return {static_cast<double>(position[robot_id][0]), static_cast<double>(position[robot_id][1])};
  }
  auto operator<=>(const SetPlaySnapshot&) const = default;
};

struct SetPlayEpisode {
  std::vector<SetPlaySnapshot> snapshots;  // in time order, the first at offset 0
  auto operator<=>(const SetPlayEpisode&) const = default;
  bool operator==(const SetPlayEpisode&) const = default;
};

// Where a set play is taking each robot of a moment, per step, and how much that counts against
// the model's forecast (0: nothing to say): recall() fills it from the earlier kick-offs,
// advise_ball_placement from the path of the robot placing the ball.
struct SetPlayAdvice {
  struct Robot {
    std::array<Point, 16> position{};
    std::array<double, 16> weight{};
  };
  std::vector<Robot> robots;  // in the order of the robots asked about
  bool any = false;
};

class SetPlayMemory {
 public:
  static constexpr double snapshot_interval_s = 0.1;
  static constexpr std::size_t max_episodes = 512;
  static constexpr std::size_t max_snapshots_per_episode = 600;  // a minute
  static_assert(max_episodes <= 0xffff && max_snapshots_per_episode <= 0xffff);
  static constexpr double since_tolerance_s = 0.3;
  static constexpr double formation_scale_mm = 200.0;
  static constexpr double own_weight = 4.0;
  static constexpr int analogs = 4;
  static constexpr double prior_weight = 0.3;
  // An end point is the snapshot within this of `offset + horizon`.
  static constexpr std::int32_t end_tolerance_ms = 60;

  // Keeps `episode` (at least one snapshot before it is over), in sorted order; past
  // max_episodes the highest in that order goes.
  void add(SetPlayEpisode episode);
  void merge(const SetPlayMemory& other);
  const std::vector<SetPlayEpisode>& episodes() const { return episodes_; }
  bool empty() const { return episodes_.empty(); }
  std::size_t snapshots() const;
  std::size_t memory_bytes() const;
  // Whether a snapshot is one a file may hold: robots seen are ids 0-15, times not negative, a
  // known stage. The episode's snapshots in time order starting at 0 (`valid_episode`).
  static bool valid_episode(const SetPlayEpisode& episode);

  // For the robots of `formation` (normalised) at a kick-off of the opponent's at `stage`,
  // `since_command_s` after its command: where the earlier kick-offs put each `step_s` x
  // 1..steps later. `out` is reused.
  void recall(const Formation& formation, SetPlayStage stage, double since_command_s, double step_s,
              int steps, SetPlayAdvice& out) const;

  // Equal episodes (the index follows from them).
  friend bool operator==(const SetPlayMemory& a, const SetPlayMemory& b) {
    return a.episodes_ == b.episodes_;
  }

 private:
  // Every snapshot but those over, by stage and seconds since the command: a recall reads the
  // few within its tolerance instead of every snapshot of every kick-off (a full memory is
  // 5 MB, and a scan of it took 0.4 ms a frame). Kept in step with the episodes by add().
  struct IndexEntry {
    std::uint32_t key;  // index_key(stage, since_command_ms)
    std::uint16_t episode, snapshot;
    auto operator<=>(const IndexEntry&) const = default;
  };
  static std::uint32_t index_key(SetPlayStage stage, std::int32_t since_command_ms);
  std::vector<SetPlayEpisode> episodes_;  // sorted
  std::vector<IndexEntry> index_;         // sorted
};

// Training's part: follows the match sample by sample and hands each finished kick-off of the
// opponent's to a memory.
class SetPlayRecorder {
 public:
  // `trail_s`: how long to record after the kick-off's restart window (the table's horizons).
  explicit SetPlayRecorder(double trail_s) : trail_s_(trail_s) {}
  // A sample at `time_s` (the data clock) in `phase`, the referee's game state `state`
  // (kick-off preparation or not), `since_command_s` after its command.
  void record(double time_s, GamePhase phase, bool preparing, double since_command_s,
              const Formation& formation, SetPlayMemory& memory);
  // The stream ends (or breaks): the kick-off under way is kept as far as it got.
  void finish(SetPlayMemory& memory);

 private:
  double trail_s_;
  std::optional<SetPlayEpisode> open_;
  double start_s_ = 0.0;
  double last_s_ = 0.0;
  std::optional<double> over_since_s_;  // when the open kick-off's restart window ended
};

}  // namespace motion_model
}  // namespace ssl_formation
