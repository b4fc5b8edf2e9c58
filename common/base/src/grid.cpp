#include "ssl_formation/base/grid.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace ssl_formation {
inline namespace base {

bool FieldSize::valid() const {
  return std::isfinite(length_mm) && std::isfinite(width_mm) && length_mm > 0.0 && width_mm > 0.0;
}

std::string describe(const FieldSize& field) {
  const auto mm = [](double value) { return std::to_string(std::lround(value)); };
  std::string text = mm(field.length_mm) + " x " + mm(field.width_mm) + " mm";
  if (field == FieldSize{12000.0, 9000.0}) return text + " (Division A)";
  if (field == FieldSize{9000.0, 6000.0}) return text + " (Division B)";
  return text + " (neither Division A nor B)";
}

std::optional<AttackDirection> parse_attack_direction(std::string_view text) {
  if (text == "+x" || text == "x" || text == "positive") return AttackDirection::positive_x;
  if (text == "-x" || text == "negative") return AttackDirection::negative_x;
  return std::nullopt;
}

std::string_view to_string(AttackDirection direction) {
  return direction == AttackDirection::positive_x ? "+x" : "-x";
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

Result<Grid> Grid::parse(std::string_view text) {
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

}  // namespace base
}  // namespace ssl_formation
