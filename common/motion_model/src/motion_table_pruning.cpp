#include "ssl_formation/motion_model/motion_table_pruning.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace ssl_formation {

namespace {

// How much better a key's own estimate fits its instances than its parent's does.
double fold_gain(const MotionLevelEstimates& estimates, std::size_t number, std::size_t parent) {
  const std::uint32_t context = decode_motion_key(estimates.key(number)).context;
  // Never read: forecasts in HALT start at the velocity level.
  if (motion_finest_level_read(context) != MotionLevel::robot) {
    return -std::numeric_limits<double>::infinity();
  }
  const GamePhase phase = MotionFeatures::phase_of_context(context);
  // Outside running play each robot makes for a place of its own: at the restarts (kick-offs,
  // free kicks, placements, penalties) the same one every time or the same one relative to the
  // ball, at STOP away from the ball and back into its shape. A robot's row holds the few
  // stoppages of a match, and its mean is most of what the model knows there. On the tuning
  // seeds folding them cost 0.6-1.7% at kick-offs (3 to 4), 0.63% at our free kicks (5 to 6)
  // and up to 0.36% at STOP, the most after the restarts. They are kept whatever they gain, and
  // folded only after every row of running play when a budget demands it (the least useful of
  // them first).
  const bool restart = phase != GamePhase::running;
  constexpr double restart_bonus = 1e12;
  // Judged as the forecasts read it: without the team's velocity where the phase leaves it
  // out, with the row's mean where the phase keeps it.
  const MotionRow& sums = estimates.sums(number);
  const MotionRow row =
      motion_team_velocity_holds(phase) ? sums : sums.without_regressor(team_velocity_regressor);
  const double mean_weight = motion_mean_holds(phase) ? 1.0 : 0.0;
  const double gain = motion_log_likelihood(row, estimates.estimate(number), mean_weight) -
                      motion_log_likelihood(row, estimates.estimate(parent), mean_weight);
  return restart ? restart_bonus + gain : gain;
}

}  // namespace

MotionPruned prune_motion_table(const MotionTable& table, const MotionModelSettings& settings,
                                const MotionPruning& pruning) {
  const MotionLevelEstimates estimates(table, settings);
  const std::size_t keys = estimates.size();
  constexpr std::uint32_t none = MotionRowMap::no_row;

  std::vector<std::uint32_t> parent(keys, none);
  std::vector<double> gain(keys, 0.0);
  std::vector<char> kept(keys, 1);
  std::vector<char> stored(keys, 0);                  // has a row of its own in the file
  std::vector<std::uint32_t> kept_children(keys, 0);  // a zone's robot rows still kept
  table.row_map().for_each(
      [&](MotionKey key, const MotionRow&) { stored[estimates.number(key)] = 1; });
  std::size_t rows = table.rows();

  const auto level_of = [&](std::size_t i) { return decode_motion_key(estimates.key(i)).level; };
  for (std::size_t i = 0; i < keys; ++i) {
    const MotionLevel level = level_of(i);
    if (level != MotionLevel::robot && level != MotionLevel::zone) continue;
    parent[i] = estimates.number(coarser_motion_key(estimates.key(i)));
    gain[i] = fold_gain(estimates, i, parent[i]);
  }
  std::size_t folded = 0;
  // Folding `i` into its parent: the parent gets a stored row if it had none (one row moves),
  // or takes the folded row's sums into its own (one row fewer).
  const auto fold = [&](std::size_t i) {
    kept[i] = 0;
    ++folded;
    if (stored[i]) {
      if (stored[parent[i]]) --rows;
      stored[parent[i]] = 1;
      stored[i] = 0;
    }
    if (level_of(i) == MotionLevel::robot) --kept_children[parent[i]];
  };
  // Robot rows first, then the zones all of whose robot rows went.
  for (std::size_t i = 0; i < keys; ++i) {
    if (level_of(i) == MotionLevel::robot) ++kept_children[parent[i]];
  }
  for (std::size_t i = 0; i < keys; ++i) {
    if (level_of(i) == MotionLevel::robot && !(gain[i] > pruning.min_gain_nats)) fold(i);
  }
  for (std::size_t i = 0; i < keys; ++i) {
    if (level_of(i) == MotionLevel::zone && kept_children[i] == 0 &&
        !(gain[i] > pruning.min_gain_nats)) {
      fold(i);
    }
  }

  // Over the budget: the least useful rows go first, a zone once none of its robots is left.
  if (pruning.max_rows > 0 && rows > pruning.max_rows) {
    using Candidate = std::pair<double, std::uint32_t>;
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> queue;
    for (std::size_t i = 0; i < keys; ++i) {
      const MotionLevel level = level_of(i);
      if (kept[i] &&
          (level == MotionLevel::robot || (level == MotionLevel::zone && kept_children[i] == 0))) {
        queue.emplace(gain[i], static_cast<std::uint32_t>(i));
      }
    }
    while (rows > pruning.max_rows && !queue.empty()) {
      const std::uint32_t i = queue.top().second;
      queue.pop();
      fold(i);
      const std::uint32_t zone = parent[i];
      if (level_of(i) == MotionLevel::robot && kept[zone] && kept_children[zone] == 0) {
        queue.emplace(gain[zone], zone);
      }
    }
  }

  MotionTable out(table.config());
  table.row_map().for_each([&](MotionKey key, const MotionRow& row) {
    std::uint32_t i = estimates.number(key);
    while (!kept[i]) i = parent[i];
    out.add_row(estimates.key(i), row);
  });
  for (int h = 0; h < table.config().horizons; ++h) {
    for (const HeldOutInstance& held : table.calibration(h)) out.add_held_out(h, held);
  }
  out.restore_held_out_seen(table.held_out());
  out.set_plays() = table.set_plays();
  const std::size_t rows_after = out.rows();
  return MotionPruned{std::move(out), table.rows(), rows_after, folded};
}

}  // namespace ssl_formation
