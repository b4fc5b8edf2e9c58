#pragma once
// What a saved motion table keeps exactly whatever was pruned: the sums of every key at the
// velocity and `all` levels (folded rows move into their parents' keys, never out of those
// levels), the instances and the held-out calibration sample.
#include <algorithm>
#include <utility>
#include <vector>

#include "ssl_formation/motion_model/motion_estimates.hpp"
#include "ssl_formation/motion_model/motion_table_pruning.hpp"

namespace ssl_formation::testing {

inline std::vector<std::pair<MotionKey, MotionRow>> coarse_motion_sums(const MotionTable& table) {
  const MotionLevelEstimates estimates(table, MotionModelSettings{});
  std::vector<std::pair<MotionKey, MotionRow>> out;
  for (std::size_t i = 0; i < estimates.size(); ++i) {
    if (static_cast<int>(decode_motion_key(estimates.key(i)).level) >=
        static_cast<int>(MotionLevel::velocity)) {
      out.emplace_back(estimates.key(i), estimates.sums(i));
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

// Whether two tables hold the same evidence at every level a pruning keeps exactly.
inline bool same_coarse_evidence(const MotionTable& a, const MotionTable& b) {
  if (!(a.config() == b.config()) || a.instances() != b.instances() ||
      a.held_out() != b.held_out() || coarse_motion_sums(a) != coarse_motion_sums(b)) {
    return false;
  }
  for (int h = 0; h < a.config().horizons; ++h) {
    if (a.calibration(h) != b.calibration(h)) return false;
  }
  return true;
}

// A table as the programs save it when it is within their budget: its rows that add nothing
// folded (table_budget.hpp).
inline MotionTable as_saved(const MotionTable& table) {
  return prune_motion_table(table, MotionModelSettings{}, MotionPruning{}).table;
}

}  // namespace ssl_formation::testing
