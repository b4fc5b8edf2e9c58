#include "ssl_formation/base/state.hpp"

#include <gtest/gtest.h>

namespace ssl_formation {
namespace {

TEST(StateCodec, MatchesThePapersExpansionForAll216StatesOf3x2) {
  const StateCodec codec(Grid(3, 2));
  ASSERT_EQ(codec.state_count(), 216u);
  int checked = 0;
  for (int tx = 0; tx < 3; ++tx)
    for (int ty = 0; ty < 2; ++ty)
      for (int px = 0; px < 3; ++px)
        for (int py = 0; py < 2; ++py)
          for (int vx = 0; vx < 3; ++vx)
            for (int vy = 0; vy < 2; ++vy) {
              const StateIndex paper =
                  static_cast<StateIndex>(vy + 2 * vx + 6 * py + 12 * px + 36 * ty + 72 * tx);
              const RobotState state{{tx, ty}, {px, py}, {vx, vy}};
              ASSERT_EQ(codec.encode(state), paper);
              ASSERT_EQ(codec.decode(paper), state);
              ++checked;
            }
  EXPECT_EQ(checked, 216);
}

TEST(StateCodec, GoldenValue) {
  const StateCodec codec(Grid(3, 2));
  EXPECT_EQ(codec.encode({{1, 1}, {2, 1}, {2, 1}}), 143u);
  EXPECT_EQ(codec.describe(143), "143 centroid=(1,1) position=(2,1) previous=(2,1) velocity=(0,0)");
}

TEST(StateCodec, RoundTripOnEveryGridSize) {
  for (const Grid grid : {Grid(1, 1), Grid(3, 2), Grid(6, 4), Grid(12, 9), Grid(16, 12)}) {
    const StateCodec codec(grid);
    const std::uint64_t cells = static_cast<std::uint64_t>(grid.cell_count());
    ASSERT_EQ(codec.state_count(), cells * cells * cells) << grid.to_string();
    // Every index for small grids; a stride that still touches every digit for large ones.
    const StateIndex stride = codec.state_count() > 100000 ? 997 : 1;
    for (StateIndex index = 0; index < codec.state_count(); index += stride) {
      ASSERT_EQ(codec.encode(codec.decode(index)), index) << grid.to_string();
    }
    const StateIndex last = codec.state_count() - 1;
    EXPECT_EQ(codec.decode(last), (RobotState{{grid.length() - 1, grid.width() - 1},
                                              {grid.length() - 1, grid.width() - 1},
                                              {grid.length() - 1, grid.width() - 1}}));
  }
}

TEST(StateCodec, VelocityIsPositionMinusPrevious) {
  const StateCodec codec(Grid(3, 2));
  const StateIndex index = codec.encode({{1, 0}, {2, 1}, {0, 0}});
  EXPECT_EQ(codec.decode(index).velocity(), (Cell{2, 1}));
}

}  // namespace
}  // namespace ssl_formation
