#include "ssl_formation/motion_model/set_play_memory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace motion_model {

namespace {

double squared_distance(Point a, Point b) {
  return (a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y);
}

std::int32_t whole_ms(double seconds) {
  return static_cast<std::int32_t>(std::lround(std::clamp(seconds, 0.0, 2.0e6) * 1000.0));
}

}  // namespace

std::uint32_t SetPlayMemory::index_key(SetPlayStage stage, std::int32_t since_command_ms) {
  constexpr std::int32_t most_ms = (1 << 24) - 1;  // four and a half hours
  return static_cast<std::uint32_t>(stage) << 24 |
         static_cast<std::uint32_t>(std::clamp(since_command_ms, 0, most_ms));
}

void SetPlayMemory::add(SetPlayEpisode episode) {
  const bool before_over =
      std::any_of(episode.snapshots.begin(), episode.snapshots.end(),
                  [](const SetPlaySnapshot& s) { return s.stage != SetPlayStage::over; });
  if (!before_over || !valid_episode(episode)) return;
  const auto at = std::upper_bound(episodes_.begin(), episodes_.end(), episode);
  const auto position = static_cast<std::uint16_t>(at - episodes_.begin());
  // The episodes after it move up one; its snapshots join the index in order.
  for (IndexEntry& entry : index_) {
    if (entry.episode >= position) ++entry.episode;
  }
  const auto old_end = static_cast<std::ptrdiff_t>(index_.size());
  for (std::size_t i = 0; i < episode.snapshots.size(); ++i) {
    const SetPlaySnapshot& s = episode.snapshots[i];
    if (s.stage == SetPlayStage::over) continue;
    index_.push_back(
        {index_key(s.stage, s.since_command_ms), position, static_cast<std::uint16_t>(i)});
  }
  std::sort(index_.begin() + old_end, index_.end());
  std::inplace_merge(index_.begin(), index_.begin() + old_end, index_.end());
  episodes_.insert(at, std::move(episode));
  if (episodes_.size() > max_episodes) {
    const auto last = static_cast<std::uint16_t>(episodes_.size() - 1);
    std::erase_if(index_, [last](const IndexEntry& entry) { return entry.episode == last; });
    episodes_.pop_back();
  }
}

void SetPlayMemory::merge(const SetPlayMemory& other) {
  for (const SetPlayEpisode& episode : other.episodes_) add(episode);
}

std::size_t SetPlayMemory::snapshots() const {
  std::size_t n = 0;
  for (const SetPlayEpisode& episode : episodes_) n += episode.snapshots.size();
  return n;
}

std::size_t SetPlayMemory::memory_bytes() const {
  std::size_t bytes =
      episodes_.capacity() * sizeof(SetPlayEpisode) + index_.capacity() * sizeof(IndexEntry);
  for (const SetPlayEpisode& episode : episodes_) {
    bytes += episode.snapshots.capacity() * sizeof(SetPlaySnapshot);
  }
  return bytes;
}

bool SetPlayMemory::valid_episode(const SetPlayEpisode& episode) {
  const auto& s = episode.snapshots;
  if (s.empty() || s.size() > max_snapshots_per_episode || s.front().offset_ms != 0) return false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (static_cast<std::uint32_t>(s[i].stage) >= set_play_stages || s[i].since_command_ms < 0 ||
        (s[i].seen >> SetPlaySnapshot::robot_slots) != 0) {
      return false;
    }
    if (i > 0 && s[i].offset_ms <= s[i - 1].offset_ms) return false;
  }
  return true;
}

void SetPlayMemory::recall(const Formation& formation, SetPlayStage stage, double since_command_s,
                           double step_s, int steps, SetPlayAdvice& out) const {
  out.robots.assign(formation.robots.size(), SetPlayAdvice::Robot{});
  out.any = false;
  if (episodes_.empty() || !std::isfinite(since_command_s)) return;
  std::array<Point, SetPlaySnapshot::robot_slots> now{};
  std::uint32_t seen = 0;
  int robots_now = 0;
  for (const FormationRobot& robot : formation.robots) {
    if (robot.robot_id >= SetPlaySnapshot::robot_slots) continue;
    now[robot.robot_id] = robot.position;
    seen |= 1U << robot.robot_id;
    ++robots_now;
  }
  if (robots_now == 0) return;
  // The candidates: snapshots of the same stage at about the same seconds since the command,
  // whose formation has all but two of today's robots; by mean squared distance.
  struct Candidate {
    double team_mm2;
    const SetPlayEpisode* episode;
    std::size_t index;
  };
  std::vector<Candidate> candidates;
  const std::int32_t since_ms = whole_ms(since_command_s);
  const auto tolerance_ms = static_cast<std::int32_t>(std::lround(since_tolerance_s * 1000.0));
  const auto first = std::lower_bound(index_.begin(), index_.end(),
                                      IndexEntry{index_key(stage, since_ms - tolerance_ms), 0, 0});
  const auto last =
      std::upper_bound(index_.begin(), index_.end(),
                       IndexEntry{index_key(stage, since_ms + tolerance_ms), 0xffff, 0xffff});
  for (auto entry = first; entry < last; ++entry) {
    const SetPlayEpisode& episode = episodes_[entry->episode];
    const SetPlaySnapshot& s = episode.snapshots[entry->snapshot];
    const std::uint32_t both = s.seen & seen;
    int n = 0;
    double sum = 0.0;
    for (std::uint32_t id = 0; id < SetPlaySnapshot::robot_slots; ++id) {
      if ((both >> id & 1U) == 0) continue;
      sum += squared_distance(now[id], s.at(id));
      ++n;
    }
    if (n == 0 || n < robots_now - 2) continue;
    candidates.push_back({sum / n, &episode, entry->snapshot});
  }
  if (candidates.empty()) return;
  // Each robot's own ranking adds its own distance; the nearest few teams are enough to rank.
  const std::size_t shortlist = std::min<std::size_t>(candidates.size(), 4 * analogs);
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(shortlist),
                    candidates.end(),
                    [](const Candidate& a, const Candidate& b) { return a.team_mm2 < b.team_mm2; });
  candidates.resize(shortlist);
  const int reach = std::min(steps, static_cast<int>(SetPlaySnapshot::robot_slots));
  std::vector<std::pair<double, const Candidate*>> ranked;
  for (std::size_t r = 0; r < formation.robots.size(); ++r) {
    const std::uint32_t id = formation.robots[r].robot_id;
    if (id >= SetPlaySnapshot::robot_slots) continue;
    ranked.clear();
    for (const Candidate& c : candidates) {
      const SetPlaySnapshot& s = c.episode->snapshots[c.index];
      if (!s.has(id)) continue;
      ranked.emplace_back(c.team_mm2 + own_weight * squared_distance(now[id], s.at(id)), &c);
    }
    std::sort(ranked.begin(), ranked.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    SetPlayAdvice::Robot& advice = out.robots[r];
    for (int k = 1; k <= reach; ++k) {
      const auto horizon_ms = static_cast<std::int32_t>(std::lround(k * step_s * 1000.0));
      double weights = 0.0;
      Point moved{};
      int used = 0;
      for (const auto& [distance_mm2, c] : ranked) {
        if (used == analogs) break;
        const auto& snapshots = c->episode->snapshots;
        const SetPlaySnapshot& from = snapshots[c->index];
        // Where the robot was `horizon` later in that kick-off.
        const std::int32_t due = from.offset_ms + horizon_ms;
        const auto end = std::lower_bound(
            snapshots.begin() + static_cast<std::ptrdiff_t>(c->index), snapshots.end(),
            due - end_tolerance_ms,
            [](const SetPlaySnapshot& s, std::int32_t t) { return s.offset_ms < t; });
        if (end == snapshots.end() || end->offset_ms > due + end_tolerance_ms || !end->has(id)) {
          continue;
        }
        const double w = std::exp(-distance_mm2 / (2.0 * formation_scale_mm * formation_scale_mm));
        const Point then = from.at(id), later = end->at(id);
        moved.x += w * (later.x - then.x);
        moved.y += w * (later.y - then.y);
        weights += w;
        ++used;
      }
      if (weights <= 0.0) continue;
      const std::size_t step = static_cast<std::size_t>(k - 1);
      advice.position[step] = {now[id].x + moved.x / weights, now[id].y + moved.y / weights};
      advice.weight[step] = weights / (weights + prior_weight);
      out.any = true;
    }
  }
}

void SetPlayRecorder::record(double time_s, GamePhase phase, bool preparing, double since_command_s,
                             const Formation& formation, SetPlayMemory& memory) {
  const bool kickoff = phase == GamePhase::kickoff_opponent;
  if (open_ && (time_s < last_s_ || time_s > last_s_ + 1.0)) finish(memory);  // a break
  if (!open_) {
    if (!kickoff) return;
    open_.emplace();
    start_s_ = time_s;
    last_s_ = -std::numeric_limits<double>::infinity();
    over_since_s_.reset();
  }
  if (kickoff && over_since_s_) {
    // A new kick-off right after the last one's window (prepared and taken again).
    finish(memory);
    record(time_s, phase, preparing, since_command_s, formation, memory);
    return;
  }
  if (!kickoff && !over_since_s_) over_since_s_ = time_s;
  if (over_since_s_ && time_s > *over_since_s_ + trail_s_ + SetPlayMemory::snapshot_interval_s) {
    finish(memory);
    return;
  }
  if (time_s < last_s_ + SetPlayMemory::snapshot_interval_s - 1e-9) return;
  if (open_->snapshots.size() >= SetPlayMemory::max_snapshots_per_episode) return;
  last_s_ = time_s;
  SetPlaySnapshot s;
  s.offset_ms = whole_ms(time_s - start_s_);
  s.since_command_ms = whole_ms(std::isfinite(since_command_s) ? since_command_s : 0.0);
  s.stage = !kickoff    ? SetPlayStage::over
            : preparing ? SetPlayStage::preparation
                        : SetPlayStage::taken;
  for (const FormationRobot& robot : formation.robots) {
    // A robot carried over from the camera packet before is where it was a frame ago: kept, as
    // the forecast will see it.
    if (robot.robot_id >= SetPlaySnapshot::robot_slots) continue;
    s.seen |= 1U << robot.robot_id;
    s.position[robot.robot_id] = {whole_mm(robot.position.x), whole_mm(robot.position.y)};
  }
  if (!open_->snapshots.empty() && s.offset_ms <= open_->snapshots.back().offset_ms) return;
  open_->snapshots.push_back(s);
}

void SetPlayRecorder::finish(SetPlayMemory& memory) {
  if (open_) memory.add(std::move(*open_));
  open_.reset();
  over_since_s_.reset();
}

}  // namespace motion_model
}  // namespace ssl_formation
