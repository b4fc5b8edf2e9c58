// The motion history: each robot's recent observations, from which instances are learned and
// velocities read.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "prefetch.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "whole_mm.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ssl_formation {
inline namespace motion_model {

namespace {
// No robot data for this long: the play moved on.
constexpr double forget_after_gap_s = RobotTracker::forget_after_s;
}  // namespace

MotionHistory::MotionHistory(const MotionConfig& config)
    : config_(config),
      keep_s_(config.horizons * config.step_s +
              std::max(
                  {config.velocity_window_s, config.settle_window_s, config.long_settle_window_s}) +
              2.0 * config.tolerance_s) {}

void MotionHistory::Track::grow() {
  const std::size_t size = std::max<std::size_t>(64, capacity * 2);
  std::vector<Entry> grown(size);
  std::vector<double> grown_times(size);
  std::vector<Running> grown_running(size);
  for (std::uint64_t seq = begin; seq < end; ++seq) {
    grown[seq & (size - 1)] = at(seq);
    grown_times[seq & (size - 1)] = time_at(seq);
    grown_running[seq & (size - 1)] = running_at(seq);
  }
  ring = std::move(grown);
  times = std::move(grown_times);
  running = std::move(grown_running);
  capacity = size;
}

void MotionHistory::Track::clear() {
  begin = end;
  settle_cursor = long_settle_cursor = end;
  tracker.reset();
  horizon_cursor.fill(end);
  still_since_s.reset();
}

void MotionHistory::clear() {
  for (Track& track : tracks_) track.clear();
  last_time_s_.reset();
  learning_gate_.reset();
  learning_instants_ = 0;
}

bool MotionHistory::take_learning_instant(double time_s, double interval_s) {
  if (!learning_gate_.pass(time_s, interval_s)) return false;
  ++learning_instants_;
  return true;
}

inline const MotionHistory::Entry* MotionHistory::nearest(const Track& track, std::uint64_t after,
                                                          double time_s) const {
  // `after` is the first entry at or after time_s: it or the one before it is the nearest.
  const Entry* best = nullptr;
  double best_gap = config_.tolerance_s + 1e-9;
  if (after < track.end && track.time_at(after) - time_s <= best_gap) {
    best = &track.at(after);
    best_gap = track.time_at(after) - time_s;
  }
  if (after > track.begin && time_s - track.time_at(after - 1) <= best_gap) {
    best = &track.at(after - 1);
  }
  return best;
}

void MotionHistory::add(const Formation& formation, std::uint32_t game_context,
                        Point ball_velocity) {
  const double t = formation.time_s;
  if (last_time_s_ && (t <= *last_time_s_ || t - *last_time_s_ > forget_after_gap_s ||
                       formation.opponent_attacks != attacks_)) {
    clear();
  }
  last_time_s_ = t;
  attacks_ = formation.opponent_attacks;
  const double limit = MotionFeatures::speed_limits_mm_s[0];
  // The team's mean velocity, summed as each robot gets its own (in the formation's order).
  Point team{};
  int with_velocity = 0;
  // Every robot's track made first, so that the loops index them without a size check each (a
  // Track's size is no power of two: a vector's size() is a multiplication).
  std::uint32_t highest_id = 0;
  for (const FormationRobot& robot : formation.robots) {
    highest_id = std::max(highest_id, robot.robot_id);
  }
  if (!formation.robots.empty() && highest_id >= tracks_.size()) tracks_.resize(highest_id + 1);
  for (const FormationRobot& robot : formation.robots) {
    Track& track = tracks_[robot.robot_id];
    if (!robot.observed) {
      // No entry: the robot's latest is still its last observation, and counts for the team.
      if (track.end > track.begin && track.at(track.end - 1).has_velocity) {
        const Point velocity = track.at(track.end - 1).kinematics.velocity;
        team.x += velocity.x;
        team.y += velocity.y;
        ++with_velocity;
      }
      continue;
    }
    if (track.end > track.begin) {
      const Track::Running& last = track.running_at(track.end - 1);
      if (MotionFeatures::is_jump(last.position, track.time_at(track.end - 1), robot.position, t)) {
        track.clear();
      }
    }
    while (track.begin < track.end && track.time_at(track.begin) < t - keep_s_) ++track.begin;
    // Cursors: the first entry at or after each window's start.
    const auto advance = [&](std::uint64_t& cursor, double from_s) {
      // Moved in a local: a cursor stored through its reference at each step cost a store per
      // entry passed.
      std::uint64_t at = std::max(cursor, track.begin);
      while (at < track.end && track.time_at(at) < from_s) ++at;
      cursor = at;
    };
    advance(track.settle_cursor, t - config_.settle_window_s);
    advance(track.long_settle_cursor, t - config_.long_settle_window_s);

    // The new entry is written in place, in the ring's next free slot (made first, so that no
    // pointer into the ring moves after this) and counts once it is complete.
    track.make_room();
    const Track::Running* last =
        track.end > track.begin ? &track.running_at(track.end - 1) : nullptr;
    Track::Running& running = track.running_at(track.end);
    running.position = robot.position;
    running.sum = {robot.position.x + (last ? last->sum.x : 0.0),
                   robot.position.y + (last ? last->sum.y : 0.0)};
    // Every field is written below (no `entry = Entry{}`: zeroing the whole slot first was a
    // fifth of this function's time).
    Entry& entry = track.at(track.end);
    entry.time_s = t;
    entry.position = robot.position;
    MotionKinematics& k = entry.kinematics;
    k.team_velocity = {};  // set after the loop if any robot of the formation has a velocity
    track.tracker.observe(t, robot.position);
    // A velocity once the track has gone on for half the velocity window: before that the
    // filter has seen too little of the robot to tell its motion from the vision's noise.
    if (track.tracker.observations() >= 2 &&
        t - track.tracker.first_s() > config_.velocity_window_s / 2.0) {
      k.velocity = track.tracker.velocity();
      entry.has_velocity = true;
      // The change of velocity over one velocity window at the filter's acceleration now.
      const Point acceleration = track.tracker.acceleration();
      k.velocity_change = {acceleration.x * config_.velocity_window_s,
                           acceleration.y * config_.velocity_window_s};
      // From the robot to its mean position since the window's first entry (the new one
      // included), from the running sums. They run unbroken over every kept entry (they restart
      // only when none is kept), so the number of positions summed is that of sequence numbers.
      const auto to_mean_since = [&](std::uint64_t first_seq) {
        if (first_seq >= track.end) return Point{};
        const Track::Running& first = track.running_at(first_seq);
        const double n = static_cast<double>(track.end - first_seq + 1);
        return Point{(running.sum.x - first.sum.x + first.position.x) / n - robot.position.x,
                     (running.sum.y - first.sum.y + first.position.y) / n - robot.position.y};
      };
      k.to_recent_mean = to_mean_since(track.settle_cursor);
      k.to_settled_mean = to_mean_since(track.long_settle_cursor);
      // How long a standing robot has stood: one that has held its place for a while is about
      // to leave it (set plays hold each position for a second or two).
      const bool standing =
          k.velocity.x * k.velocity.x + k.velocity.y * k.velocity.y < limit * limit;
      if (!standing) {
        track.still_since_s.reset();
      } else if (!track.still_since_s) {
        track.still_since_s = t;
      }
      // The standing context for now: the team's phase is added below, once the team's mean
      // velocity is known.
      entry.context = standing ? MotionFeatures::standing_context(t - *track.still_since_s) : 0;
      team.x += k.velocity.x;
      team.y += k.velocity.y;
      ++with_velocity;
    } else {
      entry.has_velocity = false;
      entry.context = 0;
      k.velocity = k.velocity_change = k.to_recent_mean = k.to_settled_mean = {};
    }
    track.time_at(track.end) = t;
    ++track.end;
  }
  // The team's mean velocity and phase go into every new entry, now that each robot has its own.
  if (with_velocity > 0) team = {team.x / with_velocity, team.y / with_velocity};
  const int team_phase = MotionFeatures::team_phase(formation.centroid, team);
  const bool ball_in_flight = MotionFeatures::ball_in_flight(ball_velocity);
  for (const FormationRobot& robot : formation.robots) {
    if (!robot.observed) continue;
    Track& track = tracks_[robot.robot_id];
    Entry& entry = track.at(track.end - 1);
    entry.kinematics.team_velocity = team;
    entry.context =
        MotionFeatures::context(entry.context, team_phase, game_context, ball_in_flight);
  }
}

const MotionHistory::Entry* MotionHistory::latest(std::uint32_t robot_id) const {
  if (robot_id >= tracks_.size()) return nullptr;
  const Track& track = tracks_[robot_id];
  return track.end > track.begin ? &track.at(track.end - 1) : nullptr;
}

const MotionHistory::Entry* MotionHistory::steps_before_latest(std::uint32_t robot_id, int steps) {
  if (robot_id >= tracks_.size() || steps < 1 || steps > config_.horizons) return nullptr;
  Track& track = tracks_[robot_id];
  if (track.end == track.begin) return nullptr;
  // The cursor moves only when asked (learning is 10 times a second, frames come 60): to the
  // first entry before the latest one at or after the latest's time minus the steps, else the
  // latest. The target only grows between two clears, so its earlier place is a lower bound.
  const double time_s = track.time_at(track.end - 1) - steps * config_.step_s;
  std::uint64_t& cursor = track.horizon_cursor[static_cast<std::size_t>(steps - 1)];
  cursor = std::max(cursor, track.begin);
  while (cursor < track.end - 1 && track.time_at(cursor) < time_s) ++cursor;
  return nearest(track, cursor, time_s);
}

void learn_motion(MotionTable& table, MotionHistory& history, const Formation& now,
                  double learn_from_s) {
  const MotionConfig& config = table.config();
  // A robot not seen since the last learning instant (its camera's packets missed it) was
  // learned from there already.
  const std::optional<double> previous_s = history.last_learning_instant_s();
  if (!history.take_learning_instant(now.time_s, config.learn_interval_s)) return;
  const int horizons = (history.learning_instants() - 1) % MotionConfig::later_horizons_every == 0
                           ? config.horizons
                           : 1;
  // Gathered, then counted a batch at a time (MotionTable::add's prefetching), in this order.
  // The buffer outlives the call (per thread: learn_motion never reenters itself), so that 3 KiB
  // are not zeroed at every learning instant; each entry used is written in full first.
  static thread_local std::array<MotionTable::Learned, 48> batch;
  // The entries learned from are 30 to 90 frames back, out of the nearest cache: all of them
  // are found and fetched first, so that their misses overlap.
  static thread_local std::vector<const MotionHistory::Entry*> thens;
  thens.clear();
  for (const FormationRobot& robot : now.robots) {
    const MotionHistory::Entry* latest = history.latest(robot.robot_id);
    const bool learned_already =
        !robot.observed && previous_s && latest && latest->time_s <= *previous_s;
    for (int k = 1; k <= horizons; ++k) {
      const MotionHistory::Entry* then =
          learned_already ? nullptr : history.steps_before_latest(robot.robot_id, k);
      if (then) detail::prefetch_object(*then);
      thens.push_back(then);
    }
  }
  std::size_t pending = 0;
  std::size_t next_then = 0;
  for (const FormationRobot& robot : now.robots) {
    for (int k = 1; k <= horizons; ++k) {
      const MotionHistory::Entry* then = thens[next_then++];
      if (!then || !then->has_velocity || then->time_s >= now.time_s ||
          then->time_s < learn_from_s) {
        continue;
      }
      MotionTable::Learned& learned = batch[pending++];
      learned.horizon_index = k - 1;
      learned.time_s = then->time_s;
      MotionInstance& instance = learned.instance;
      instance.robot_id = robot.robot_id;
      const MotionKinematics& kinematics = then->kinematics;
      const auto set_whole_mm = [](std::int32_t& x, std::int32_t& y, Point p) {
        const WholePoint whole = detail::whole_mm_of(p);
        x = whole.x;
        y = whole.y;
      };
      set_whole_mm(instance.x, instance.y, then->position);
      set_whole_mm(instance.v_x, instance.v_y, kinematics.velocity);
      set_whole_mm(instance.a_x, instance.a_y, kinematics.velocity_change);
      set_whole_mm(instance.g_x, instance.g_y, kinematics.to_recent_mean);
      set_whole_mm(instance.s_x, instance.s_y, kinematics.to_settled_mean);
      set_whole_mm(instance.t_x, instance.t_y, kinematics.team_velocity);
      set_whole_mm(instance.d_x, instance.d_y,
                   Point{robot.position.x - then->position.x, robot.position.y - then->position.y});
      instance.context = then->context;
      if (pending == batch.size()) {
        table.add(std::span<const MotionTable::Learned>(batch.data(), pending));
        pending = 0;
      }
    }
  }
  table.add(std::span<const MotionTable::Learned>(batch.data(), pending));
}

}  // namespace motion_model
}  // namespace ssl_formation
