#pragma once
// When the team names a game controller sends take over from the ones followed. A forged or
// replayed referee message must not rename the opponent (and so switch the trainer's table) on
// its own: names other than the ones followed take over only once every message of the followed
// game controller has said them for name_hold_s, and at most max_name_switches times within
// name_switch_window_s. The first names heard take over at once.

#include <cstdint>
#include <deque>
#include <optional>
#include <string>

namespace ssl_formation {
inline namespace match {

class TeamNameGate {
 public:
  static constexpr double name_hold_s = 1.0;
  static constexpr int max_name_switches = 3;
  static constexpr double name_switch_window_s = 60.0;

  // Whether the names `yellow` and `blue` of a used message, received at `receive_s`, take over
  // from `followed_yellow` and `followed_blue` now. A clock that goes back starts the hold and
  // the window anew.
  bool take_over(const std::string& followed_yellow, const std::string& followed_blue,
                 const std::string& yellow, const std::string& blue, double receive_s);
  // Names that did not take over: they did not hold, another pair came in between, or too many
  // switches came within the window.
  std::uint64_t refused() const { return refused_; }
  // Forgets what was said (a new log file), keeping the count of refusals.
  void reset() {
    candidate_.reset();
    named_ = false;
    switches_s_.clear();
  }

 private:
  // Names other than the followed ones, said by every message since `since_s`.
  struct Candidate {
    std::string yellow;
    std::string blue;
    double since_s = 0.0;
  };
  std::optional<Candidate> candidate_;
  bool named_ = false;             // names were taken over since the start or reset()
  std::deque<double> switches_s_;  // when names took over, within the window
  std::uint64_t refused_ = 0;
};

}  // namespace match
}  // namespace ssl_formation
