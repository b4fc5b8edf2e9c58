#pragma once
// The motion model: where each opponent robot will be, in millimetres, k steps ahead, learned by
// counting. Beyond the paper's cells it sees each robot's velocity (from its last frames) and
// learns, per state, how the robot's real displacement differs from damped constant velocity.
//
// A state is (robot id, 0.5 m feature cell, velocity class, context): 8 directions x 3 speeds
// plus "standing"; the context is how long a standing robot has stood, where its team is and
// whether the team is on the move (MotionFeatures::context). Each row holds integer sums (count,
// displacement, extrapolated velocity and their products), so training is counting, tables merge
// by adding, and merging two tables equals training on both streams bit for bit. Prediction
// backs off from the robot's own row to its 3 m zone's row (every robot), to the velocity
// class's row, to damped constant velocity, each row shrunk towards the coarser one by its
// count: a young table predicts like damped constant velocity and an old one like what the
// opponent really does.
//
// Probabilities and radii are calibrated on held-out data kept inside the table: every
// `calibration_block_s` of the data clock whose hash falls in one `calibration_one_in` is held
// out of the rows, and a deterministic sample of its instances (the lowest hashes, so that it
// merges exactly too) is what MotionModel fits its calibration on.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/interval_gate.hpp"
#include "ssl_formation/base/probed_memory.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/motion_model/set_play_memory.hpp"
#include "ssl_formation/vision/robot_tracker.hpp"

namespace ssl_formation {
inline namespace motion_model {

// What a motion table's rows mean; saved with them, and equal for tables that merge.
struct MotionConfig {
  double step_s = 2.0;  // the table's step
  int horizons = 3;     // steps learned: k x step_s ahead for k = 1..horizons
  // A robot has a velocity once its track has gone on for half this window, and its change of
  // velocity is its acceleration over this window (both from its RobotTracker).
  double velocity_window_s = 0.1;
  // Instances are learned at most this often per robot: frames 16 ms apart say almost the same
  // thing. On the inner splits of both recordings, 10 a second forecast as well as 15 (2 s:
  // 10.7 / 11.9% below damped constant velocity against 10.6 / 11.7%; 0.2 s 0.5 mm worse) and 60
  // (every frame). Row updates are most of offline training's time, and 10 make a third fewer
  // than 15.
  double learn_interval_s = 0.1;
  // The horizons after the first are learned at one learning instant in this many: their
  // instances a tenth of a second apart share most of their path. On the inner splits of both
  // recordings and of A reshaped as a real log, learning the chained 1 s and 1.5 s steps 5 times
  // a second forecast them as well as 10 (within 1.6 mm either way, the radii's coverage within
  // a point). The first horizon keeps 10: at 5 the 0.2 s and 0.5 s steps lost 1-2 mm.
  static constexpr int later_horizons_every = 2;
  double settle_window_s = 0.5;       // MotionKinematics::to_recent_mean's window
  double long_settle_window_s = 2.0;  // MotionKinematics::to_settled_mean's
  double tolerance_s = 0.05;          // how far from an instant a position may be taken for it
  double calibration_block_s = 1.0;
  // One block in this many is held out: at one in ten, ten minutes of play held out about 40
  // blocks, and the 90% radius's coverage wandered by a few points between recordings.
  std::uint32_t calibration_one_in = 5;
  std::uint32_t calibration_capacity = 4096;  // instances kept per horizon
  static constexpr int max_horizons = 16;
  bool valid() const;
  friend bool operator==(const MotionConfig&, const MotionConfig&) = default;
};

// The state's parts, fixed by the format: feature cells of 500 mm over 14 x 10 m centred on the
// field (Division A with its boundary; anything beyond lands in an edge cell), robot ids 0-15
// (higher ids share one slot) and the velocity classes.
struct MotionFeatures {
  static constexpr double cell_mm = 500.0;
  static constexpr int cells_x = 28;
  static constexpr int cells_y = 20;
  static constexpr int cell_count = cells_x * cells_y;
  static constexpr int robot_slots = 17;
  static constexpr int directions = 8;
  static constexpr std::array<double, 3> speed_limits_mm_s{250.0, 750.0, 1500.0};
  static constexpr int velocity_classes =
      1 + directions * static_cast<int>(speed_limits_mm_s.size());

  static int cell(Point normalised);
  static int velocity_class(Point velocity_mm_s);
  // The context of a robot that has stood (slower than the first speed limit) this long: 1 to
  // 1 + standing_limits_s.size(); 0 is a moving robot's.
  static constexpr std::array<double, 3> standing_limits_s{0.5, 1.0, 2.0};
  static std::uint32_t standing_context(double standing_s);
  static constexpr std::uint32_t standing_contexts = 2 + standing_limits_s.size();
  // Where the team is and whether it is on the move: its centroid (normalised) more than
  // `team_place_edge_mm` into its own half, about the halfway line, or as far into the half it
  // attacks; and its mean velocity at or above the first speed limit (the team leaving its
  // set-play places together) or not. A robot standing in one spot leaves it for other places
  // when its team attacks than when it falls back, and sooner when the others have set off.
  static constexpr double team_place_edge_mm = 1000.0;
  static constexpr int team_phases = 3 * 2;
  static int team_phase(Point normalised_centroid, Point team_velocity_mm_s);
  // The game as the referee runs it (match/game_phase.hpp's GamePhase for the team predicted)
  // and how long its command has held: running play is one context; HALT and timeouts one
  // (nobody may move); each other phase three, by the seconds since its command in
  // `since_command_limits_s`, because a set play unfolds with time (a free kick is taken about
  // 0.7 s after its command in real matches; a halt's robots have 2 s to brake). The game
  // context is part of the key rather than a regressor: the phases differ in which regressors
  // matter (in HALT none does, in STOP the speed is capped), not by an offset a regressor adds.
  static constexpr std::array<double, 2> since_command_limits_s{1.0, 3.0};
  static constexpr std::uint32_t since_command_buckets = since_command_limits_s.size() + 1;
  static constexpr std::uint32_t running_game = 0;
  static constexpr std::uint32_t halt_game = 1;
  static constexpr std::uint32_t game_contexts =
      2 + (all_game_phases.size() - 2) * since_command_buckets;
  static std::uint32_t game_context(GamePhase phase, double since_command_s);
  static GamePhase phase_of_game_context(std::uint32_t game_context);
  // Whether the ball is in flight (a pass, a shot, a clearance): faster than this. The players
  // follow a ball on its way, and stand or close in on one at rest. Of the ball inputs tried
  // (docs/results.md: its position and velocity relative to the robot as regressors, the robot
  // nearest the ball, the ball's third of the field, the nearest robot of the other team), this
  // bit was the only one that helped on every tuning split; 0.5 and 2 m/s did no better.
  static constexpr double ball_flight_speed_mm_s = 1000.0;
  static bool ball_in_flight(Point ball_velocity_mm_s) {
    return ball_velocity_mm_s.x * ball_velocity_mm_s.x +
               ball_velocity_mm_s.y * ball_velocity_mm_s.y >=
           ball_flight_speed_mm_s * ball_flight_speed_mm_s;
  }
  static constexpr std::uint32_t ball_contexts = 2;
  // A row's context: the standing context, the team phase, the game context and whether the
  // ball is in flight, in that order of significance. The ball comes last so that the contexts
  // of tables learned before it (the ball at rest or unseen) keep their numbers.
  static constexpr std::uint32_t robot_contexts = standing_contexts * team_phases;
  static constexpr std::uint32_t context_count = robot_contexts * game_contexts * ball_contexts;
  static std::uint32_t context(std::uint32_t standing_context, int team_phase,
                               std::uint32_t game_context = running_game,
                               bool ball_in_flight = false) {
    return standing_context + standing_contexts * static_cast<std::uint32_t>(team_phase) +
           robot_contexts * (game_context + game_contexts * (ball_in_flight ? 1U : 0U));
  }
  static std::uint32_t game_context_of(std::uint32_t context) {
    return context / robot_contexts % game_contexts;
  }
  // The game phase a row's context files the robot under.
  static GamePhase phase_of_context(std::uint32_t context) {
    return phase_of_game_context(game_context_of(context));
  }
  static bool ball_in_flight_of(std::uint32_t context) {
    return context / (robot_contexts * game_contexts) != 0;
  }
  // Zones: where every robot's rows are pooled, 3 m across, numbered like cells. The length in
  // quarters (own half in two, the attacked half in two) and the width in a centre lane and two
  // wings, on a Division A field; beyond them, the edge zones. Set plays put each role at places
  // that vary by a few hundred millimetres from one run to the next: the 0.5 m cells split what
  // one role does there among many rows, and pooling every robot over a zone gathers it again.
  static constexpr std::array<double, 3> zone_length_edges_mm{-3000.0, 0.0, 3000.0};
  static constexpr std::array<double, 2> zone_width_edges_mm{-1500.0, 1500.0};
  static constexpr int zones_y = static_cast<int>(zone_width_edges_mm.size()) + 1;
  static constexpr int zone_count = (static_cast<int>(zone_length_edges_mm.size()) + 1) * zones_y;
  static int zone_of_cell(int cell);
  static int robot_slot(std::uint32_t robot_id) {
    return robot_id < 16 ? static_cast<int>(robot_id) : 16;
  }

  // A robot seen further from where it last was than it can have moved is a jump, not motion:
  // a vision ghost carrying its id, two ids swapped, a robot put down elsewhere, or a change of
  // ends not yet noticed. Real logs have them (docs/simulation.md), and one jump of metres
  // counts in a row's sums of squares as thousands of ordinary instances. The limit is above any
  // SSL robot's top speed (about 4 m/s), with room for the vision's noise and for the offset
  // between two cameras' views of one robot at their seam.
  static constexpr double jump_speed_mm_s = 8000.0;
  static constexpr double jump_slack_mm = 150.0;
  static bool is_jump(Point from, double from_s, Point to, double to_s) {
    const double reach = jump_slack_mm + jump_speed_mm_s * std::abs(to_s - from_s);
    const double dx = to.x - from.x;
    const double dy = to.y - from.y;
    return dx * dx + dy * dy > reach * reach;
  }
};

// The back-off levels, finest first: the robot's own row (cell, velocity class, context), every
// robot's in the cell's zone (velocity class, context), every robot's with the velocity class in
// the game context, every robot's in the game context (the coarse levels leave the standing
// time, the team phase and the ball out). Below them, the horizon's pooled root (or
// for HALT the rules' prior: see MotionModel).
enum class MotionLevel : std::uint8_t { robot = 0, zone = 1, velocity = 2, all = 3 };
inline constexpr int motion_levels = 4;

// A row's key: the horizon, the level and the features that level keeps (the others zero).
struct MotionKeyParts {
  int horizon_index = 0;
  MotionLevel level = MotionLevel::robot;
  int robot_slot = 0;
  int cell = 0;  // the zone (MotionFeatures::zone_of_cell) at the zone level
  int velocity_class = 0;
  std::uint32_t context = 0;  // MotionFeatures::context
  friend bool operator==(const MotionKeyParts&, const MotionKeyParts&) = default;
};
using MotionKey = std::uint64_t;
// The slot where `key`'s search starts in an open-addressing table of `mask + 1` slots (a power
// of two), probed linearly from there: the key's bits mixed, then masked. MotionRowMap's index
// and MotionModel's estimates both use it. Inline: every lookup in either table calls it.
inline std::size_t motion_key_slot(MotionKey key, std::size_t mask) {
  key ^= key >> 31;
  key *= 0x7fb5d329728ea185ULL;
  key ^= key >> 27;
  return static_cast<std::size_t>(key) & mask;
}
// Packs the parts `level` keeps; decode(encode(p)) is p with the dropped parts zero.
MotionKey encode_motion_key(MotionKeyParts parts);
MotionKeyParts decode_motion_key(MotionKey key);
// The finest key of an instance learned `horizon_index + 1` steps ahead.
struct MotionInstance;
MotionKeyParts motion_key_parts(int horizon_index, const MotionInstance& instance);
// The key of the next coarser level (all's parent is itself).
MotionKey coarser_motion_key(MotionKey key);

// What the model knows of a robot's recent motion, normalised (mm, mm/s).
struct MotionKinematics {
  Point velocity;         // now, from the robot's tracker
  Point velocity_change;  // the tracker's acceleration times the velocity window
  Point to_recent_mean;   // from the robot to its mean position over the settle window
  Point to_settled_mean;  // the same over the long settle window
  Point team_velocity;    // the mean velocity of the formation's robots that have one
};

// The regressors the model fits a displacement with, for one horizon:
//   e  the velocity times the horizon (what constant velocity predicts);
//   q  the change of velocity times the horizon (braking, accelerating, turning);
//   g  towards the mean position over the settle window (a robot circling or wobbling about a
//      spot has the spot there);
//   G  the same over the long settle window (where the robot has been lately);
//   t  the team's mean velocity times the horizon (a team moves from one set-play position to
//      the next together: when the others set off, a robot still standing is about to).
inline constexpr int motion_regressors = 5;
inline constexpr int team_velocity_regressor = 4;  // t
using MotionRegressors = std::array<Point, motion_regressors>;
MotionRegressors motion_regressors_of(const MotionKinematics& kinematics, double horizon_s);

// Integer sums over a row's instances (mm and mm^2): the count, the displacements d, each
// regressor x_i, |d|^2, d.x_i and x_i.x_j (i <= j). Sums of integers, so merging tables equals
// training on both streams exactly.
struct MotionRow {
  static constexpr int r = motion_regressors;
  static constexpr std::size_t size = 1 + 2 + 2 * r + 1 + r + r * (r + 1) / 2;
  std::array<std::int64_t, size> sums{};

  std::int64_t n() const { return sums[0]; }
  std::int64_t d(int axis) const { return sums[1 + axis]; }
  std::int64_t x(int i, int axis) const { return sums[3 + 2 * i + axis]; }
  std::int64_t dd() const { return sums[3 + 2 * r]; }
  std::int64_t dx(int i) const { return sums[4 + 2 * r + i]; }
  std::int64_t xx(int i, int j) const { return sums[4 + 3 * r + pair_index(i, j)]; }

  // Adds one instance: displacement d and regressors x, in whole millimetres.
  void add(const std::array<std::int64_t, 2>& d,
           const std::array<std::array<std::int64_t, 2>, r>& x);
  void add(const MotionRow& other);
  // The same sums with regressor `i` taken as zero in every instance: a fit of them leaves it
  // out.
  MotionRow without_regressor(int i) const;
  friend bool operator==(const MotionRow&, const MotionRow&) = default;

 private:
  static constexpr int pair_index(int i, int j) {
    if (i > j) return pair_index(j, i);
    return i * r - i * (i - 1) / 2 + (j - i);
  }
};

// One learned instance, rounded to whole millimetres.
struct MotionInstance {
  std::uint32_t robot_id = 0;
  std::int32_t x = 0, y = 0;      // normalised position then
  std::int32_t d_x = 0, d_y = 0;  // displacement to the position horizon later
  std::int32_t v_x = 0, v_y = 0;  // MotionKinematics then, rounded
  std::int32_t a_x = 0, a_y = 0;
  std::int32_t g_x = 0, g_y = 0;
  std::int32_t s_x = 0, s_y = 0;
  std::int32_t t_x = 0, t_y = 0;  // the team's mean velocity, rounded
  std::uint32_t context = 0;
  MotionKinematics kinematics() const;
  friend bool operator==(const MotionInstance&, const MotionInstance&) = default;
};

std::int32_t whole_mm(double value);  // rounded and clamped to +-1e9
// whole_mm of each coordinate, the two at once.
struct WholePoint {
  std::int32_t x = 0, y = 0;
};
WholePoint whole_mm(Point p);

// The values of an instance besides its robot id and context, in the order table files store
// them.
inline constexpr std::array<std::int32_t MotionInstance::*, 14> motion_instance_values{
    &MotionInstance::x,   &MotionInstance::y,   &MotionInstance::d_x, &MotionInstance::d_y,
    &MotionInstance::v_x, &MotionInstance::v_y, &MotionInstance::a_x, &MotionInstance::a_y,
    &MotionInstance::g_x, &MotionInstance::g_y, &MotionInstance::s_x, &MotionInstance::s_y,
    &MotionInstance::t_x, &MotionInstance::t_y};

// Rows by key: the rows one after the other in the order they first came, found through an
// open-addressing index of (key, row number) slots (linear probing, at most half full). Training
// adds to a row per robot, horizon and learning instant, all over a table larger than the caches:
// the index is small and the rows are packed, and prefetch() lets a caller overlap the misses of
// several rows (a node map's allocation and pointer chase per row was most of the training time).
class MotionRowMap {
 public:
  MotionRow& operator[](MotionKey key);
  const MotionRow* find(MotionKey key) const;
  // Rows are numbered in the order they came, and keep their number.
  static constexpr std::uint32_t no_row = ~std::uint32_t{0};
  std::uint32_t row_number(MotionKey key) const;  // no_row if not in the map
  MotionRow& row(std::uint32_t number) {
    return blocks_[number / rows_per_block][number % rows_per_block];
  }
  const MotionRow& row(std::uint32_t number) const {
    return blocks_[number / rows_per_block][number % rows_per_block];
  }
  // Hints that a row will be used soon: fetches `key`'s index slot, or row `number`, into the
  // cache.
  void prefetch_slot(MotionKey key) const;
  void prefetch_row(std::uint32_t number) const;
  std::size_t size() const { return row_keys_.size(); }
  std::size_t capacity() const { return slots_.size(); }  // index slots
  std::size_t memory_bytes() const;
  // Every row, in no particular order.
  template <typename Visit>
  void for_each(Visit&& visit) const {
    for (std::size_t i = 0; i < row_keys_.size(); ++i) {
      visit(row_keys_[i], row(static_cast<std::uint32_t>(i)));
    }
  }
  friend bool operator==(const MotionRowMap& a, const MotionRowMap& b);

 private:
  static constexpr MotionKey empty_key = ~MotionKey{0};  // no key has every bit set
  struct Slot {
    MotionKey key = empty_key;
    std::uint32_t row = 0;  // into the blocks and row_keys_
  };
  void grow();
  std::vector<Slot, ProbedAllocator<Slot>> slots_;
  std::vector<MotionKey> row_keys_;
  // The rows in blocks of a fixed size: a growing table adds a block instead of copying every
  // row into a buffer twice the size (and faulting in its fresh pages) each time it doubles,
  // which was a tenth of training on a single log. Rows keep their numbers; their addresses
  // hold too, except that a copied map's last block moves once, at its first new row (nothing
  // keeps a row's address across an insert).
  // A block fills one huge page (ProbedAllocator): a table filled while training takes a page
  // fault per 2 MiB instead of one per 4 KiB (those were a tenth of training on a real log).
  static constexpr std::size_t rows_per_block = huge_page_bytes / sizeof(MotionRow);
  using Block = std::vector<MotionRow, ProbedAllocator<MotionRow>>;
  std::vector<Block> blocks_;
};

// A calibration instance and its rank (lower is kept).
struct HeldOutInstance {
  std::uint64_t hash = 0;
  MotionInstance instance;
  friend bool operator==(const HeldOutInstance&, const HeldOutInstance&) = default;
};

// The counts of the motion model: the finest rows (the coarser levels are their sums, built by
// MotionModel) and the held-out calibration sample per horizon.
class MotionTable {
 public:
  explicit MotionTable(MotionConfig config = {});

  const MotionConfig& config() const { return config_; }

  // Learns that a robot at `instance` moved by its displacement `horizon_index + 1` steps later,
  // as a row count or, for a held-out time, as a calibration candidate. `time_s` is when the
  // instance started (the data clock), which decides whether it is held out.
  void add(int horizon_index, double time_s, const MotionInstance& instance);
  // What add() takes, for adding many at once.
  struct Learned {
    int horizon_index = 0;
    double time_s = 0.0;
    MotionInstance instance;
  };
  // add() for each, in order, with the same result; the rows are fetched for all of them before
  // any is counted, so that their cache misses overlap.
  void add(std::span<const Learned> learned);
  // Adds a row's sums (loading a file).
  void add_row(MotionKey key, const MotionRow& row);
  // Offers a calibration instance (loading a file, merging).
  void add_held_out(int horizon_index, const HeldOutInstance& held_out);

  // Adds every count and calibration instance of `other`. Throws std::invalid_argument if the
  // configurations differ.
  void merge(const MotionTable& other);

  std::uint64_t instances() const { return instances_; }     // counted in rows
  std::uint64_t held_out() const { return held_out_seen_; }  // offered, kept or not
  // Loading a file: how many held-out instances the saved table had been offered.
  void restore_held_out_seen(std::uint64_t seen) { held_out_seen_ = seen; }
  std::size_t rows() const { return rows_.size(); }
  std::size_t memory_bytes() const;
  // Rows in increasing key order, for saving and comparing.
  std::vector<std::pair<MotionKey, MotionRow>> sorted_rows() const;
  // The held-out sample of one horizon, in increasing hash order.
  std::vector<HeldOutInstance> calibration(int horizon_index) const;
  const MotionRowMap& row_map() const { return rows_; }
  // The opponent's kick-offs (set_play_memory.hpp): merged and saved with the rows.
  const SetPlayMemory& set_plays() const { return set_plays_; }
  SetPlayMemory& set_plays() { return set_plays_; }

  bool is_held_out(double time_s) const;
  friend bool operator==(const MotionTable& a, const MotionTable& b);

 private:
  // Counts an instance that is not held out into its row.
  void count(int horizon_index, MotionRow& row, const MotionInstance& instance);

  MotionConfig config_;
  MotionRowMap rows_;
  // Per horizon, the calibration candidates: every instance among the `calibration_capacity`
  // lowest-ranked offered so far, and possibly some more (at most as many again). When full they
  // are cut back to the lowest `capacity`, and the highest of those becomes the bar every later
  // candidate must rank below. A candidate then costs a comparison and a copy, where keeping a
  // heap of exactly `capacity` cost two heap updates for about half of all held-out instances.
  struct HeldOutSample {
    std::vector<HeldOutInstance> candidates;
    std::optional<HeldOutInstance> bar;  // set by the first cut
  };
  std::vector<HeldOutSample> held_out_;
  SetPlayMemory set_plays_;
  std::uint64_t instances_ = 0;
  std::uint64_t held_out_seen_ = 0;
};

// Each robot's recent positions on the data clock (normalised), for velocities and for the
// positions `k` steps back that training learns from. Forgets everything after a gap, a time
// going backwards or a change of attack direction.
class MotionHistory {
 public:
  explicit MotionHistory(const MotionConfig& config);

  struct Entry {
    double time_s = 0.0;
    Point position;
    MotionKinematics kinematics;  // valid if has_velocity
    bool has_velocity = false;
    std::uint32_t context = 0;  // MotionFeatures::context
  };
  // Records a formation: an entry at its time for each robot observed in it (a robot carried
  // over from an earlier frame keeps its latest entry, and its velocity still counts in the
  // team's). Every robot's kinematics are then latest(id)->kinematics. A robot whose position
  // jumped (MotionFeatures::is_jump) starts its track again there: nothing is learned across
  // the jump and its velocity starts anew.
  // `game_context` (MotionFeatures::game_context) and whether the ball moving at
  // `ball_velocity` (normalised mm/s; zero when no ball is seen) is in flight go into every new
  // entry's context.
  void add(const Formation& formation, std::uint32_t game_context = MotionFeatures::running_game,
           Point ball_velocity = {});
  void clear();

  const Entry* latest(std::uint32_t robot_id) const;
  // The entry nearest (within the tolerance) to the latest entry's time minus `steps` steps,
  // 1 to the configuration's horizons. Not const: it moves the robot's cursor for `steps`.
  const Entry* steps_before_latest(std::uint32_t robot_id, int steps);

  // Whether an instant at `time_s` is one to learn from (once per `interval_s`); if so it is
  // remembered as the last one.
  bool take_learning_instant(double time_s, double interval_s);
  // The last learning instant taken, if any since the last clear.
  std::optional<double> last_learning_instant_s() const { return learning_gate_.last_s(); }
  // Learning instants taken since the last clear, the last one included.
  std::uint64_t learning_instants() const { return learning_instants_; }

 private:
  // One robot's entries in a ring buffer addressed by absolute sequence numbers, with cursors
  // that only move forward (time does): every frame adds an entry per robot, and the searches
  // for "the start of the settle windows" and "k steps before" are a step or two, not a binary
  // search.
  struct Track {
    std::vector<Entry> ring;  // a power-of-two size
    // The entries' times again, packed: the cursors' scans read only these, from a few cache
    // lines instead of one 112-byte entry each.
    std::vector<double> times;
    // The running sums for the settle windows' means, packed with the positions for the same
    // reason: the windows' first entries are 30 and 120 frames back, out of the nearest cache.
    struct Running {
      Point position;
      Point sum;  // of the positions up to this one since the track last had no entry kept
    };
    std::vector<Running> running;
    // The three rings' size (a power of two, or 0 before the first entry), kept rather than
    // computed from a vector's at every access: the cursors' scans make several a frame, and an
    // entry's size is not a power of two (a division by it, made a multiplication).
    std::uint64_t capacity = 0;
    std::uint64_t begin = 0, end = 0;  // the kept entries' sequence numbers, [begin, end)
    std::uint64_t settle_cursor = 0, long_settle_cursor = 0;
    // k steps before the latest entry; moved by steps_before_latest, not by add.
    std::array<std::uint64_t, MotionConfig::max_horizons> horizon_cursor{};
    std::optional<double> still_since_s;  // when the robot last came to a stand, if it stands
    RobotTracker tracker;                 // the velocity and acceleration
    const Entry& at(std::uint64_t seq) const { return ring[seq & (capacity - 1)]; }
    Entry& at(std::uint64_t seq) { return ring[seq & (capacity - 1)]; }
    double time_at(std::uint64_t seq) const { return times[seq & (capacity - 1)]; }
    double& time_at(std::uint64_t seq) { return times[seq & (capacity - 1)]; }
    const Running& running_at(std::uint64_t seq) const { return running[seq & (capacity - 1)]; }
    Running& running_at(std::uint64_t seq) { return running[seq & (capacity - 1)]; }
    // Grows the rings if full: at(end) is then a free slot.
    void make_room() {
      if (end - begin == capacity) grow();
    }
    void grow();
    void clear();
  };
  // Inline (defined in motion_model.cpp, its only user): add calls it for every robot and
  // frame, steps_before_latest for every horizon.
  inline const Entry* nearest(const Track& track, std::uint64_t after, double time_s) const;

  MotionConfig config_;
  double keep_s_;
  std::vector<Track> tracks_;  // by robot id
  std::optional<double> last_time_s_;
  IntervalGate learning_gate_;
  std::uint64_t learning_instants_ = 0;
  AttackDirection attacks_ = AttackDirection::positive_x;
};

// Training's part: after `history.add(now)`, counts every robot of `now` against where it was
// k steps earlier, for each horizon, at most once per learn_interval_s of the data clock (the
// history remembers when it last learned; a clear or a clock going back starts over). Nothing is
// learned from where a robot was before `learn_from_s` (the start of the referee's current
// command, for learning in running play: no instance spans a change of command).
void learn_motion(MotionTable& table, MotionHistory& history, const Formation& now,
                  double learn_from_s = -std::numeric_limits<double>::infinity());

}  // namespace motion_model
}  // namespace ssl_formation
