#include "ssl_formation/match/team_name_gate.hpp"

namespace ssl_formation {
inline namespace match {

bool TeamNameGate::take_over(const std::string& followed_yellow, const std::string& followed_blue,
                             const std::string& yellow, const std::string& blue, double receive_s) {
  // A clock that went back (a log started over): the hold and the window start anew.
  if (candidate_ && receive_s < candidate_->since_s) candidate_.reset();
  if (!switches_s_.empty() && receive_s < switches_s_.back()) switches_s_.clear();
  if (yellow == followed_yellow && blue == followed_blue) {
    // The names followed again: a candidate in between did not hold.
    if (candidate_) ++refused_;
    candidate_.reset();
    return false;
  }
  // The first names heard since the start (or reset()) take over at once; after that, names
  // that go empty and come back must hold like any others.
  if (!named_) {
    named_ = true;
    return true;
  }
  if (!candidate_ || candidate_->yellow != yellow || candidate_->blue != blue) {
    if (candidate_) ++refused_;  // another candidate came in between
    candidate_ = Candidate{yellow, blue, receive_s};
    return false;
  }
  if (receive_s - candidate_->since_s < name_hold_s) return false;
  while (!switches_s_.empty() && receive_s - switches_s_.front() >= name_switch_window_s) {
    switches_s_.pop_front();
  }
  if (switches_s_.size() >= static_cast<std::size_t>(max_name_switches)) {
    // Held, but too many switches lately: refused, and it must hold anew after the window.
    ++refused_;
    candidate_->since_s = receive_s;
    return false;
  }
  switches_s_.push_back(receive_s);
  candidate_.reset();
  return true;
}

}  // namespace match
}  // namespace ssl_formation
