#include "ssl_formation/base/grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ssl_formation {
namespace {

const FieldSize division_b{9000.0, 6000.0};

TEST(Grid, CellsAtTheFieldEdges) {
  const Grid grid(3, 2);
  EXPECT_EQ(grid.cell_of({-4500.0, -3000.0}, division_b), (Cell{0, 0}));
  EXPECT_EQ(grid.cell_of({4500.0, 3000.0}, division_b), (Cell{2, 1}));  // far edge clamps in
  EXPECT_EQ(grid.cell_of({-1500.0, 0.0}, division_b), (Cell{1, 1}));    // on a boundary: upper cell
  EXPECT_EQ(grid.cell_of({-1500.001, -0.001}, division_b), (Cell{0, 0}));
  EXPECT_EQ(grid.cell_of({1499.0, 2999.0}, division_b), (Cell{1, 1}));
}

TEST(Grid, PointsOutsideTheFieldClampToEdgeCells) {
  const Grid grid(3, 2);
  EXPECT_EQ(grid.cell_of({-4800.0, -3300.0}, division_b), (Cell{0, 0}));  // boundary area
  EXPECT_EQ(grid.cell_of({1e9, -1e9}, division_b), (Cell{2, 0}));
  EXPECT_EQ(grid.cell_of({-1e30, 1e30}, division_b), (Cell{0, 1}));
}

TEST(Grid, AttackDirectionRotation) {
  const Grid grid(3, 2);
  const Point feed{-4000.0, 2500.0};  // deep in the -x half, upper side
  EXPECT_EQ(grid.cell_of(normalise(feed, AttackDirection::positive_x), division_b), (Cell{0, 1}));
  EXPECT_EQ(grid.cell_of(normalise(feed, AttackDirection::negative_x), division_b), (Cell{2, 0}));
  EXPECT_EQ(normalise(normalise(feed, AttackDirection::negative_x), AttackDirection::negative_x),
            feed);
}

TEST(Grid, CellCentresMapBackToTheirCell) {
  for (const Grid grid : {Grid(1, 1), Grid(3, 2), Grid(12, 9), Grid(16, 12)}) {
    for (int x = 0; x < grid.length(); ++x) {
      for (int y = 0; y < grid.width(); ++y) {
        EXPECT_EQ(grid.cell_of(grid.centre_of({x, y}, division_b), division_b), (Cell{x, y}));
      }
    }
  }
  EXPECT_EQ(Grid(3, 2).centre_of({0, 0}, division_b), (Point{-3000.0, -1500.0}));
}

TEST(Grid, ParseAndLimits) {
  EXPECT_EQ(Grid::parse("3x2"), Grid(3, 2));
  EXPECT_EQ(Grid::parse("16x12"), Grid(16, 12));
  const auto not_a_grid = Grid::parse("3by2");
  ASSERT_FALSE(not_a_grid);
  EXPECT_NE(not_a_grid.error().message.find("LxW"), std::string::npos);
  EXPECT_FALSE(Grid::parse("0x2"));
  EXPECT_FALSE(Grid::parse("20x20"));
  EXPECT_THROW(Grid(0, 1), std::invalid_argument);
}

TEST(FieldSize, RejectsZeroNegativeAndNonFinite) {
  EXPECT_TRUE((FieldSize{9000, 6000}.valid()));
  EXPECT_FALSE((FieldSize{0, 6000}.valid()));
  EXPECT_FALSE((FieldSize{9000, -1}.valid()));
  EXPECT_FALSE((FieldSize{std::numeric_limits<double>::infinity(), 6000}.valid()));
  EXPECT_FALSE((FieldSize{std::nan(""), 6000}.valid()));
}

}  // namespace
}  // namespace ssl_formation
