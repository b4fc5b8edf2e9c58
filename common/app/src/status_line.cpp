#include "ssl_formation/app/status_line.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "ssl_formation/app/daemon.hpp"

namespace ssl_formation::app {

namespace {

std::string pair(std::string_view name, std::string_view value) {
  std::string out;
  out.reserve(name.size() + 1 + value.size());
  out.append(name).append("=").append(value);
  return out;
}

constexpr std::string_view problems_label = "problems:";
// Between what goes well and the problems, so that the eye finds them.
constexpr std::string_view problems_separator = " | ";

}  // namespace

StatusLine& StatusLine::figure(std::string_view name, std::string_view value) {
  items_.push_back({pair(name, value), true});
  return *this;
}

StatusLine& StatusLine::figure(std::string_view name, std::uint64_t value) {
  if (value != 0) items_.push_back({pair(name, std::to_string(value)), true});
  return *this;
}

StatusLine& StatusLine::note(std::string_view text) {
  items_.push_back({std::string(text), true});
  return *this;
}

StatusLine& StatusLine::detail(std::string_view name, std::string_view value) {
  items_.push_back({pair(name, value), false});
  return *this;
}

StatusLine& StatusLine::detail(std::string_view name, std::uint64_t value) {
  if (value != 0) items_.push_back({pair(name, std::to_string(value)), false});
  return *this;
}

StatusLine& StatusLine::problem(std::string_view name, std::uint64_t value,
                                std::string_view group) {
  if (value != 0) problems_.push_back({std::string(name), value, std::string(group)});
  return *this;
}

std::string StatusLine::render(const Choice& choice) const {
  std::string out;
  const auto add = [&out](const std::string& item) {
    if (!out.empty()) out += ' ';
    out += item;
  };
  for (const bool figures : {true, false}) {
    for (std::size_t i = 0; i < items_.size(); ++i) {
      if (choice.shown[i] && items_[i].figure == figures) add(items_[i].text);
    }
  }
  if (problems_.empty()) return out;
  if (!out.empty()) out += problems_separator;
  out += problems_label;
  for (std::size_t i = 0; i < problems_.size(); ++i) {
    const Problem& problem = problems_[i];
    if (!choice.grouped || problem.group.empty()) {
      out.append(" ").append(pair(problem.name, std::to_string(problem.value)));
      continue;
    }
    // A group's sum where its first problem would be.
    const auto first = std::find_if(problems_.begin(), problems_.end(),
                                    [&](const Problem& p) { return p.group == problem.group; });
    if (first != problems_.begin() + static_cast<std::ptrdiff_t>(i)) continue;
    std::uint64_t sum = 0;
    for (const Problem& p : problems_) {
      if (p.group == problem.group) sum += p.value;
    }
    out.append(" ").append(pair(problem.group, std::to_string(sum)));
  }
  return out;
}

StatusLine::Choice StatusLine::choose(std::size_t max_chars, bool grouped) const {
  Choice choice{std::vector<bool>(items_.size(), false), grouped};
  // Each figure that fits, so that a long one does not take the game state with it.
  bool every_figure = true;
  for (std::size_t i = 0; i < items_.size(); ++i) {
    if (!items_[i].figure) continue;
    choice.shown[i] = true;
    if (render(choice).size() > max_chars) {
      choice.shown[i] = false;
      every_figure = false;
    }
  }
  // Then the details in their order up to the first that does not fit: the same layout from
  // one line to the next. None in the place of a figure.
  if (!every_figure) return choice;
  for (std::size_t i = 0; i < items_.size(); ++i) {
    if (items_[i].figure) continue;
    choice.shown[i] = true;
    if (render(choice).size() > max_chars) {
      choice.shown[i] = false;
      break;
    }
  }
  return choice;
}

StatusLine::Choice StatusLine::choose(std::size_t max_chars) const {
  Choice each = choose(max_chars, false);
  for (std::size_t i = 0; i < items_.size(); ++i) {
    if (items_[i].figure && !each.shown[i]) return choose(max_chars, true);
  }
  return each;
}

std::string StatusLine::text(std::size_t max_chars) const { return render(choose(max_chars)); }

std::vector<std::string> StatusLine::left_out(std::size_t max_chars) const {
  const Choice choice = choose(max_chars);
  std::vector<std::string> out;
  for (const bool figures : {true, false}) {
    for (std::size_t i = 0; i < items_.size(); ++i) {
      if (!choice.shown[i] && items_[i].figure == figures) out.push_back(items_[i].text);
    }
  }
  if (choice.grouped) {
    for (const Problem& problem : problems_) {
      if (!problem.group.empty()) out.push_back(pair(problem.name, std::to_string(problem.value)));
    }
  }
  return out;
}

void StatusLine::log(std::string_view what, StatusMoment moment) const {
  const std::string_view program = spdlog::default_logger_raw()->name();
  const std::size_t room = status_text_chars(program, what);
  spdlog::info("{}: {}", what, text(room));
  if (moment != StatusMoment::at_stop) return;
  // The rest, a line at a time within the same limit.
  const std::string more = std::string(what) + ", more";
  const std::size_t more_room = status_text_chars(program, more);
  std::string line;
  for (const std::string& item : left_out(room)) {
    if (!line.empty() && line.size() + 1 + item.size() > more_room) {
      spdlog::info("{}: {}", more, line);
      line.clear();
    }
    if (!line.empty()) line += ' ';
    line += item;
  }
  if (!line.empty()) spdlog::info("{}: {}", more, line);
}

std::size_t status_text_chars(std::string_view program, std::string_view what) {
  const std::size_t before = info_prefix_chars(program) + what.size() + 2;  // "<what>: "
  // Room for the first figures whatever the names.
  constexpr std::size_t least = 40;
  return before + least <= max_status_line_chars ? max_status_line_chars - before : least;
}

}  // namespace ssl_formation::app
