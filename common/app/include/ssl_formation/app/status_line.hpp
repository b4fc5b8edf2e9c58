#pragma once
// The status lines every program logs each --status-interval and once as it stops, built one way
// everywhere: short enough to read at a glance while a match runs, with what a team looks at
// first, and silent about everything that is fine.
//
//   [18:58:53.104] ssl-trainer: info: status: packets=362 formations=360 table_transitions=3366
//     game=halt opponent=yellow(default) attacks=+x(referee) states_seen=20 | problems: late=2
//
// - figures come first, in the order added: the packets, what was learned or predicted, the game;
// - details follow, in the order added, up to the first that does not fit, once every figure is
//   on the line;
// - problems come last, after "problems:", and are never left out: a kernel drop, a parse error or
//   a refused robot is always on the line once it happened. When they crowd the figures out, the
//   problems of a group show as one sum ("input_refused=41" for "non_finite=3 late=38"), and at
//   stop the parts follow.
// A counter at zero is left out, wherever it goes: a reader (a test, a script) takes a name that
// is not on the line as 0. Every value is name=value with no space inside a number, so "name=N"
// can be read back from the line.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ssl_formation::app {

// The longest a status line may be, all of it: the time, the program and "info: status: " too.
// Only problems can make a line longer (see StatusLine::text).
inline constexpr std::size_t max_status_line_chars = 199;

// When a status line is logged: each --status-interval, or once as the program stops, when
// whatever did not fit follows on lines of its own.
enum class StatusMoment { periodic, at_stop };

class StatusLine {
 public:
  // Always on the line: "game=running".
  StatusLine& figure(std::string_view name, std::string_view value);
  // On the line when non-zero: "packets=362".
  StatusLine& figure(std::string_view name, std::uint64_t value);
  // Words without a name, always on the line among the figures: "no vision packets yet".
  StatusLine& note(std::string_view text);
  // On the line while it has room: "fast_path=99.4%".
  StatusLine& detail(std::string_view name, std::string_view value);
  // On the line when non-zero, while it has room: "referee_messages=360".
  StatusLine& detail(std::string_view name, std::uint64_t value);
  // On the line whenever non-zero, after "problems:", never left out: "kernel_drops=12". With a
  // `group`, summed with the group's other problems when the line has no room for each.
  StatusLine& problem(std::string_view name, std::uint64_t value, std::string_view group = {});

  // The line (what follows "status: ") in at most `max_chars` characters: every problem, each
  // figure that fits, and once every figure is on the line the details in their order up to the
  // first that does not fit. When the problems leave a figure out, the groups of problems show as
  // sums instead. Longer than `max_chars` only when the problems alone, summed by group, are:
  // that is the one way to hide no problem that happened, which matters more than the length
  // (and a line with that many kinds of problems at once is rare).
  std::string text(std::size_t max_chars) const;
  // What text(max_chars) leaves out or sums, as "name=value" each, figures first.
  std::vector<std::string> left_out(std::size_t max_chars) const;

  // Logs "<what>: <text>" at info level within max_status_line_chars, for the program named in
  // the default logger (init_logging). At stop what did not fit follows on lines of its own
  // ("<what>, more: ..."), so the last word has every non-zero counter.
  void log(std::string_view what = "status", StatusMoment moment = StatusMoment::periodic) const;

 private:
  struct Item {
    std::string text;
    bool figure = false;  // else a detail
  };
  struct Problem {
    std::string name;
    std::uint64_t value = 0;
    std::string group;  // empty: shown on its own
  };
  // What goes on the line: which items, and whether the groups of problems are summed.
  struct Choice {
    std::vector<bool> shown;
    bool grouped = false;
  };
  std::string render(const Choice& choice) const;
  Choice choose(std::size_t max_chars) const;
  Choice choose(std::size_t max_chars, bool grouped) const;

  std::vector<Item> items_;  // figures and details, in the order added
  std::vector<Problem> problems_;
};

// The room a status line of `program` has for its text after "<what>: ".
std::size_t status_text_chars(std::string_view program, std::string_view what);

}  // namespace ssl_formation::app
