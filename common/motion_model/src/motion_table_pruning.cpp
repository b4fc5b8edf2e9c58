#include "ssl_formation/motion_model/motion_table_pruning.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace ssl_formation {
inline namespace motion_model {

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

MotionPruner::MotionPruner(const MotionTable& table, const MotionModelSettings& settings)
    : table_(table) {
  const MotionLevelEstimates estimates(table, settings);
  const std::size_t keys = estimates.size();
  keys_.resize(keys);
  levels_.resize(keys);
  parents_.assign(keys, MotionRowMap::no_row);
  gains_.assign(keys, 0.0);
  for (std::size_t i = 0; i < keys; ++i) {
    keys_[i] = estimates.key(i);
    levels_[i] = decode_motion_key(keys_[i]).level;
    if (levels_[i] != MotionLevel::robot && levels_[i] != MotionLevel::zone) continue;
    parents_[i] = estimates.number(coarser_motion_key(keys_[i]));
    gains_[i] = fold_gain(estimates, i, parents_[i]);
  }
  stored_keys_.reserve(table.rows());
  table.row_map().for_each(
      [&](MotionKey key, const MotionRow&) { stored_keys_.push_back(estimates.number(key)); });
}

MotionPruned MotionPruner::prune(const MotionPruning& pruning) const {
  const MotionTable& table = table_;
  const std::size_t keys = keys_.size();
  std::vector<char> kept(keys, 1);
  std::vector<char> stored(keys, 0);                  // has a row of its own in the file
  std::vector<std::uint32_t> kept_children(keys, 0);  // a zone's robot rows still kept
  for (const std::uint32_t number : stored_keys_) stored[number] = 1;
  std::size_t rows = table.rows();

  std::size_t folded = 0;
  // Folding `i` into its parent: the parent gets a stored row if it had none (one row moves),
  // or takes the folded row's sums into its own (one row fewer).
  const auto fold = [&](std::size_t i) {
    kept[i] = 0;
    ++folded;
    if (stored[i]) {
      if (stored[parents_[i]]) --rows;
      stored[parents_[i]] = 1;
      stored[i] = 0;
    }
    if (levels_[i] == MotionLevel::robot) --kept_children[parents_[i]];
  };
  // Robot rows first, then the zones all of whose robot rows went.
  for (std::size_t i = 0; i < keys; ++i) {
    if (levels_[i] == MotionLevel::robot) ++kept_children[parents_[i]];
  }
  for (std::size_t i = 0; i < keys; ++i) {
    if (levels_[i] == MotionLevel::robot && !(gains_[i] > pruning.min_gain_nats)) fold(i);
  }
  for (std::size_t i = 0; i < keys; ++i) {
    if (levels_[i] == MotionLevel::zone && kept_children[i] == 0 &&
        !(gains_[i] > pruning.min_gain_nats)) {
      fold(i);
    }
  }

  // Over the budget: the least useful rows go first, a zone once none of its robots is left.
  if (pruning.max_rows > 0 && rows > pruning.max_rows) {
    using Candidate = std::pair<double, std::uint32_t>;
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> queue;
    for (std::size_t i = 0; i < keys; ++i) {
      const MotionLevel level = levels_[i];
      if (kept[i] &&
          (level == MotionLevel::robot || (level == MotionLevel::zone && kept_children[i] == 0))) {
        queue.emplace(gains_[i], static_cast<std::uint32_t>(i));
      }
    }
    while (rows > pruning.max_rows && !queue.empty()) {
      const std::uint32_t i = queue.top().second;
      queue.pop();
      fold(i);
      const std::uint32_t zone = parents_[i];
      if (levels_[i] == MotionLevel::robot && kept[zone] && kept_children[zone] == 0) {
        queue.emplace(gains_[zone], zone);
      }
    }
  }

  MotionTable out(table.config());
  std::size_t row = 0;
  table.row_map().for_each([&](MotionKey, const MotionRow& sums) {
    std::uint32_t i = stored_keys_[row++];
    while (!kept[i]) i = parents_[i];
    out.add_row(keys_[i], sums);
  });
  for (int h = 0; h < table.config().horizons; ++h) {
    for (const HeldOutInstance& held : table.calibration(h)) out.add_held_out(h, held);
  }
  out.restore_held_out_seen(table.held_out());
  out.set_plays() = table.set_plays();
  const std::size_t rows_after = out.rows();
  return MotionPruned{std::move(out), table.rows(), rows_after, folded};
}

MotionPruned prune_motion_table(const MotionTable& table, const MotionModelSettings& settings,
                                const MotionPruning& pruning) {
  return MotionPruner(table, settings).prune(pruning);
}

}  // namespace motion_model
}  // namespace ssl_formation
