#pragma once
// A robot's state (paper §3.1): the team centroid cell, its own cell and its previous cell,
// and the state index (docs/models.md), a mixed-radix number whose digits are
// (tx, ty, px, py, vx, vy), so index = (t*C + p)*C + v with C = L*W cells numbered x*W + y.

#include <cstdint>
#include <string>

#include "ssl_formation/base/grid.hpp"

namespace ssl_formation {
inline namespace base {

using StateIndex = std::uint32_t;

struct RobotState {
  Cell centroid;
  Cell position;
  Cell previous;
  Cell velocity() const { return Cell{position.x - previous.x, position.y - previous.y}; }
  friend bool operator==(const RobotState&, const RobotState&) = default;
};

class StateCodec {
 public:
  explicit StateCodec(Grid grid)
      : grid_(grid), cells_(static_cast<StateIndex>(grid.cell_count())) {}

  const Grid& grid() const { return grid_; }
  StateIndex cell_count() const { return cells_; }
  // S = (L*W)^3.
  StateIndex state_count() const { return cells_ * cells_ * cells_; }

  StateIndex encode(const RobotState& state) const {
    return compose(static_cast<StateIndex>(grid_.cell_id(state.centroid)),
                   static_cast<StateIndex>(grid_.cell_id(state.position)),
                   static_cast<StateIndex>(grid_.cell_id(state.previous)));
  }
  RobotState decode(StateIndex index) const {
    return RobotState{grid_.cell_from_id(static_cast<int>(centroid_id(index))),
                      grid_.cell_from_id(static_cast<int>(position_id(index))),
                      grid_.cell_from_id(static_cast<int>(previous_id(index)))};
  }

  // Index arithmetic on cell ids, for the hot paths that never need a Cell.
  StateIndex compose(StateIndex centroid, StateIndex position, StateIndex previous) const {
    return (centroid * cells_ + position) * cells_ + previous;
  }
  StateIndex centroid_id(StateIndex index) const { return index / (cells_ * cells_); }
  StateIndex position_id(StateIndex index) const { return (index / cells_) % cells_; }
  StateIndex previous_id(StateIndex index) const { return index % cells_; }

  // "INDEX centroid=(TX,TY) position=(PX,PY) previous=(VX,VY) velocity=(DX,DY)"
  std::string describe(StateIndex index) const;

 private:
  Grid grid_;
  StateIndex cells_;
};

}  // namespace base
}  // namespace ssl_formation
