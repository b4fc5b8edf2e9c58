#pragma once
// Keeping a motion table small: a row is stored only where it says something its coarser row
// does not. The rest are folded into their parent (added to the parent key's stored row), so
// every coarser key's sums stay what they were and training, merging and scouting go on adding
// rows as before; only the folded keys' forecasts change, to their parent's.
//
// A robot's row is judged by how much better its own estimate fits the instances it summed than
// its parent's estimate does (MotionLevelEstimates, motion_log_likelihood). A zone's row may be
// folded once every robot row beneath it is; the velocity and `all` levels are always kept
// (there are a few thousand of them at most). The robot and zone rows of HALT are never read
// (motion_finest_level_read), so they are always folded; those of STOP and the restarts are
// kept, unless a budget leaves no other choice.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ssl_formation/motion_model/motion_estimates.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
inline namespace motion_model {

struct MotionPruning {
  // A row of running play is kept when its own estimate fits its instances better than its
  // parent's by more than this many nats (twice the usual log-likelihood:
  // motion_log_likelihood). A row of a few instances is shrunk to its parent and gains nothing;
  // a robot that truly moves otherwise than its zone gains in proportion to its instances. The
  // rows of the other states are always kept (motion_table_pruning.cpp says why). Tuned on
  // simulated seeds 3 (training) to 4 (test) and 5 to 6, 600 s each, 4 horizons of 0.5 s: 1
  // kept 20,179 of 32,543 and 25,156 of 38,347 rows and moved no state's mean error at any
  // horizon by more than 0.29% and 0.36%; 3 and more lost over 0.5% in running play.
  double min_gain_nats = 1.0;
  // At most this many stored rows (0: no bound): the rows that gain least are folded first,
  // beyond min_gain_nats, until the table fits.
  std::size_t max_rows = 0;
};

struct MotionPruned {
  MotionTable table;
  std::size_t rows_before = 0;
  std::size_t rows_after = 0;
  std::size_t folded = 0;  // robot and zone rows folded into their parent
};

// The judgement of every robot and zone row of a table, made once: how much better its own
// estimate fits than its parent's. The table can then be pruned to any number of rows without
// estimating every key again (a budget's tries), and the estimates, a copy of every key's sums,
// are let go before the pruned table is built. `table` must outlive the pruner.
class MotionPruner {
 public:
  MotionPruner(const MotionTable& table, const MotionModelSettings& settings);
  // `table` with the rows that add nothing folded into their parents. The held-out calibration
  // sample, the kick-offs and the instance count are kept as they are. A table that was pruned
  // before prunes again the same way: its folded rows are already at their parent's key.
  MotionPruned prune(const MotionPruning& pruning) const;

 private:
  const MotionTable& table_;
  std::vector<MotionKey> keys_;             // every key with counts, at every level
  std::vector<MotionLevel> levels_;         // of keys_
  std::vector<std::uint32_t> parents_;      // robot and zone keys' parent (others: none)
  std::vector<double> gains_;               // robot and zone keys' (fold_gain)
  std::vector<std::uint32_t> stored_keys_;  // the key of each stored row, in for_each order
};

// MotionPruner(table, settings).prune(pruning).
MotionPruned prune_motion_table(const MotionTable& table, const MotionModelSettings& settings,
                                const MotionPruning& pruning);

}  // namespace motion_model
}  // namespace ssl_formation
