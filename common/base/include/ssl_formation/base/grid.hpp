#pragma once
// The field grid of the paper (§3.1): L columns along the field length and W rows along its
// width, with the attack-direction normalisation the paper proposes as further work
// (docs/models.md).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "ssl_formation/base/result.hpp"

namespace ssl_formation {
inline namespace base {

// A point on the field in millimetres, centre of the field at (0, 0).
struct Point {
  double x = 0.0;
  double y = 0.0;
  friend bool operator==(const Point&, const Point&) = default;
};

// Field size in millimetres (the playing area without the boundary).
struct FieldSize {
  double length_mm = 9000.0;  // Division B
  double width_mm = 6000.0;
  friend bool operator==(const FieldSize&, const FieldSize&) = default;
  bool valid() const;
};

// "12000 x 9000 mm (Division A)": the size and the SSL division it implies (A: 12 x 9 m,
// B: 9 x 6 m; anything else is said to be neither), for the daemons' logs.
std::string describe(const FieldSize& field);

// A grid cell: x counts columns along the length, y rows along the width.
struct Cell {
  int x = 0;
  int y = 0;
  friend bool operator==(const Cell&, const Cell&) = default;
};

// Which way the opponent attacks in the feed's coordinates. The model always sees an opponent
// attacking towards +x; the other side is rotated by 180 degrees.
enum class AttackDirection { positive_x, negative_x };

std::optional<AttackDirection> parse_attack_direction(std::string_view text);  // "+x" or "-x"
std::string_view to_string(AttackDirection direction);
// The other end: the side the opponent attacks after the teams changed ends.
constexpr AttackDirection opposite(AttackDirection direction) {
  return direction == AttackDirection::positive_x ? AttackDirection::negative_x
                                                  : AttackDirection::positive_x;
}

// The rotation is its own inverse, so the same call undoes it for output.
inline Point normalise(Point feed_point, AttackDirection opponent_attacks) {
  if (opponent_attacks == AttackDirection::positive_x) return feed_point;
  return Point{-feed_point.x, -feed_point.y};
}

// The cell, 0 to cells - 1, holding a position measured in cells from the first cell's edge;
// positions before the first cell or past the last land in it. NaN never comes here (the sampler
// rejects it). Clamped in double first, so that huge positions cannot overflow the int
// conversion; then truncated, which for a value in [0, cells - 1] is its floor (one below 0
// clamps to 0 either way) without floor's code: this runs for every robot of every sample.
inline int clamped_cell(double position_in_cells, int cells) {
  return static_cast<int>(std::clamp(position_in_cells, 0.0, static_cast<double>(cells - 1)));
}

class Grid {
 public:
  // Upper bound on L*W: keeps S = (L*W)^3 within 32-bit state indices.
  static constexpr int max_cells = 256;

  // Throws std::invalid_argument for sizes outside 1..max_cells cells.
  Grid(int length_cells, int width_cells);

  // Parses "LxW" such as "3x2"; the error names the text and what is wrong with it.
  static Result<Grid> parse(std::string_view text);

  int length() const { return length_; }  // L, columns along x
  int width() const { return width_; }    // W, rows along y
  int cell_count() const { return length_ * width_; }
  std::string to_string() const;  // "3x2"

  // The cell of a point of the normalised field, clamped so that the boundary area and
  // anything beyond land in the edge cells. Inline, as centre_of: both run for every robot of
  // every packet, and a call into another file's code costs a cold page per packet.
  Cell cell_of(Point normalised_point, const FieldSize& field) const {
    return Cell{
        clamped_cell((normalised_point.x + field.length_mm / 2.0) / field.length_mm * length_,
                     length_),
        clamped_cell((normalised_point.y + field.width_mm / 2.0) / field.width_mm * width_,
                     width_)};
  }
  Point centre_of(Cell cell, const FieldSize& field) const {
    return Point{(cell.x + 0.5) * field.length_mm / length_ - field.length_mm / 2.0,
                 (cell.y + 0.5) * field.width_mm / width_ - field.width_mm / 2.0};
  }

  // Cells numbered x*W + y, the digit order of the state index.
  int cell_id(Cell cell) const { return cell.x * width_ + cell.y; }
  Cell cell_from_id(int id) const { return Cell{id / width_, id % width_}; }
  bool contains(Cell cell) const {
    return cell.x >= 0 && cell.x < length_ && cell.y >= 0 && cell.y < width_;
  }

  friend bool operator==(const Grid&, const Grid&) = default;

 private:
  int length_;
  int width_;
};

}  // namespace base
}  // namespace ssl_formation
