#include "ssl_formation/grid.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace ssl_formation {

bool FieldSize::valid() const {
  return std::isfinite(length_mm) && std::isfinite(width_mm) && length_mm > 0.0 && width_mm > 0.0;
}

std::optional<AttackDirection> parse_attack_direction(std::string_view text) {
  if (text == "+x" || text == "x" || text == "positive") return AttackDirection::positive_x;
  if (text == "-x" || text == "negative") return AttackDirection::negative_x;
  return std::nullopt;
}

std::string_view to_string(AttackDirection direction) {
  return direction == AttackDirection::positive_x ? "+x" : "-x";
}

Point normalise(Point feed_point, AttackDirection opponent_attacks) {
  if (opponent_attacks == AttackDirection::positive_x) return feed_point;
  return Point{-feed_point.x, -feed_point.y};
}

Grid::Grid(int length_cells, int width_cells) : length_(length_cells), width_(width_cells) {
  if (length_cells < 1 || width_cells < 1 || length_cells > max_cells || width_cells > max_cells ||
      length_cells * width_cells > max_cells) {
    throw std::invalid_argument("grid " + std::to_string(length_cells) + "x" +
                                std::to_string(width_cells) +
                                " is out of range: each side at least 1 and at most " +
                                std::to_string(max_cells) + " cells in all");
  }
}

std::optional<Grid> Grid::parse(std::string_view text, std::string* error) {
  auto fail = [&](std::string reason) -> std::optional<Grid> {
    if (error) *error = std::move(reason);
    return std::nullopt;
  };
  const auto separator = text.find_first_of("xX");
  if (separator == std::string_view::npos) {
    return fail("grid '" + std::string(text) + "' is not of the form LxW, for example 3x2");
  }
  int length = 0;
  int width = 0;
  const auto parse_int = [](std::string_view part, int& out) {
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), out);
    return ec == std::errc() && end == part.data() + part.size() && !part.empty();
  };
  if (!parse_int(text.substr(0, separator), length) ||
      !parse_int(text.substr(separator + 1), width)) {
    return fail("grid '" + std::string(text) + "' is not of the form LxW, for example 3x2");
  }
  try {
    return Grid(length, width);
  } catch (const std::invalid_argument& e) {
    return fail(e.what());
  }
}

std::string Grid::to_string() const {
  return std::to_string(length_) + "x" + std::to_string(width_);
}

Cell Grid::cell_of(Point point, const FieldSize& field) const {
  // NaN never reaches here (the sampler rejects it); clamping in double first keeps huge
  // coordinates from overflowing the int conversion.
  const double fx = std::floor((point.x + field.length_mm / 2.0) / field.length_mm * length_);
  const double fy = std::floor((point.y + field.width_mm / 2.0) / field.width_mm * width_);
  return Cell{static_cast<int>(std::clamp(fx, 0.0, static_cast<double>(length_ - 1))),
              static_cast<int>(std::clamp(fy, 0.0, static_cast<double>(width_ - 1)))};
}

Point Grid::centre_of(Cell cell, const FieldSize& field) const {
  return Point{(cell.x + 0.5) * field.length_mm / length_ - field.length_mm / 2.0,
               (cell.y + 0.5) * field.width_mm / width_ - field.width_mm / 2.0};
}

}  // namespace ssl_formation
