#include "ssl_formation/match/referee.hpp"

#include <array>
#include <cmath>
#include <utility>

#include "ssl_formation/base/wire_text.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation {
inline namespace match {

namespace {
constexpr std::array<std::string_view, game_state_count> game_state_names{
    "unknown",
    "halt",
    "stop",
    "running",
    "free_kick",
    "kickoff_preparation",
    "penalty_preparation",
    "ball_placement",
    "timeout",
};
}  // namespace

std::string_view to_string(GameState state) {
  return game_state_names[static_cast<std::size_t>(state)];
}

std::optional<GameState> parse_game_state(std::string_view text) {
  for (std::size_t i = 0; i < game_state_names.size(); ++i) {
    if (game_state_names[i] == text) return static_cast<GameState>(i);
  }
  return std::nullopt;
}

std::optional<GameState> game_state_of_command(int command) {
  switch (command) {
    case Referee::HALT:
      return GameState::halt;
    case Referee::STOP:
    case Referee::GOAL_YELLOW:
    case Referee::GOAL_BLUE:
      return GameState::stop;
    case Referee::NORMAL_START:
    case Referee::FORCE_START:
      return GameState::running;
    case Referee::PREPARE_KICKOFF_YELLOW:
    case Referee::PREPARE_KICKOFF_BLUE:
      return GameState::kickoff_preparation;
    case Referee::PREPARE_PENALTY_YELLOW:
    case Referee::PREPARE_PENALTY_BLUE:
      return GameState::penalty_preparation;
    case Referee::DIRECT_FREE_YELLOW:
    case Referee::DIRECT_FREE_BLUE:
    case Referee::INDIRECT_FREE_YELLOW:
    case Referee::INDIRECT_FREE_BLUE:
      return GameState::free_kick;
    case Referee::TIMEOUT_YELLOW:
    case Referee::TIMEOUT_BLUE:
      return GameState::timeout;
    case Referee::BALL_PLACEMENT_YELLOW:
    case Referee::BALL_PLACEMENT_BLUE:
      return GameState::ball_placement;
    default:
      return std::nullopt;
  }
}

bool is_running_play(GameState state) {
  return state == GameState::running || state == GameState::free_kick;
}

RefereeFollower::RefereeFollower(double source_timeout_s) : source_timeout_s_(source_timeout_s) {}

RefereeChange RefereeFollower::add(std::string_view payload, double receive_s) {
  Referee message;
  // Partial: a message whose command is a number this schema does not know lacks its (required)
  // command afterwards, and is counted as that rather than as undecodable.
  if (!message.ParsePartialFromArray(payload.data(), static_cast<int>(payload.size()))) {
    ++counters_.messages;
    ++counters_.undecodable;
    return {};
  }
  return add(message, receive_s);
}

RefereeChange RefereeFollower::add(const Referee& message, double receive_s) {
  ++counters_.messages;
  // A command this schema does not know says nothing usable, whoever sent it.
  const std::optional<GameState> state =
      message.has_command() ? game_state_of_command(message.command()) : std::nullopt;
  if (!state) {
    ++counters_.unknown_command;
    return {};
  }
  RefereeChange change;
  // Text from the wire, shortened and escaped (wire_text.hpp) before anything keeps or shows it.
  const std::string source = printable_wire_text(message.source_identifier());  // "": not given
  if (heard_ && source != view_.source) {
    // A second game controller (a test instance, a backup) while the first still speaks: the
    // first keeps the match, the way the game controller's own clients follow one source.
    if (!(receive_s - last_used_s_ > source_timeout_s_ || receive_s < last_used_s_)) {
      ++counters_.other_source;
      change.conflict = source != conflicting_source_;
      conflicting_source_ = source;
      return change;
    }
    ++counters_.source_switches;
    change.source = true;
  }
  if (heard_ && !change.source) {
    const Staleness why = staleness(message, receive_s);
    if (why != Staleness::fresh) {
      if (!resync_due(message, why, receive_s)) {
        // A replayed or stale message must not take the match back to an earlier state.
        ++counters_.stale;
        change.stale = true;
        return change;
      }
      ++counters_.resyncs;
      change.resync = true;
    }
  }
  ++counters_.used;
  last_used_s_ = receive_s;
  counter_refusals_in_a_row_ = 0;
  used_s_.push_back(receive_s);
  if (used_s_.size() > resync_refusals + resync_max_used) used_s_.pop_front();
  if (message.has_packet_timestamp()) last_timestamp_us_ = message.packet_timestamp();
  if (!heard_ || change.source || message.command() != view_.command ||
      message.command_counter() != view_.command_counter) {
    change.command = true;
    ++counters_.commands;
  }
  heard_ = true;
  view_.source = source;
  view_.state = *state;
  view_.command = message.command();
  view_.command_counter = message.command_counter();
  view_.stage = message.has_stage() ? message.stage() : view_.stage;
  const std::string yellow = printable_wire_text(message.yellow().name());
  const std::string blue = printable_wire_text(message.blue().name());
  if (yellow.empty() && blue.empty()) ++counters_.unnamed_teams;
  const bool take_over =
      names_.take_over(view_.yellow_name, view_.blue_name, yellow, blue, receive_s);
  counters_.refused_name_switches = names_.refused();
  if (take_over) {
    change.teams = true;
    view_.yellow_name = yellow;
    view_.blue_name = blue;
  }
  if (message.has_blue_team_on_positive_half() &&
      view_.blue_on_positive_half != message.blue_team_on_positive_half()) {
    change.sides = true;
    view_.blue_on_positive_half = message.blue_team_on_positive_half();
  }
  view_.designated_position.reset();
  if (message.has_designated_position()) {
    // Partially parsed: x and y are required, and may still be missing.
    const Referee::Point& at = message.designated_position();
    if (at.has_x() && at.has_y() && std::isfinite(at.x()) && std::isfinite(at.y())) {
      view_.designated_position = Point{at.x(), at.y()};
    }
  }
  return change;
}

RefereeFollower::Staleness RefereeFollower::staleness(const Referee& message,
                                                      double receive_s) const {
  const bool silence = receive_s - last_used_s_ > source_timeout_s_ || receive_s < last_used_s_;
  if (silence) return Staleness::fresh;  // a new start of the game controller (or a new log file)
  if (last_timestamp_us_ && message.has_packet_timestamp()) {
    const double since_s = (static_cast<double>(message.packet_timestamp()) -
                            static_cast<double>(*last_timestamp_us_)) *
                           1e-6;
    if (since_s < -max_timestamp_back_s) return Staleness::behind;
    if (since_s > receive_s - last_used_s_ + max_timestamp_ahead_s) return Staleness::ahead;
  }
  if (message.command_counter() < view_.command_counter) {
    // The counter starts again when the game controller restarts: then the stage is new too,
    // and the timestamp is the clock's now. A message of an earlier stage sent again has an
    // older timestamp: a replay, not a restart.
    const bool new_stage = message.has_stage() && message.stage() != view_.stage;
    const bool timestamp_goes_on = !last_timestamp_us_ || !message.has_packet_timestamp() ||
                                   message.packet_timestamp() >= *last_timestamp_us_;
    if (!(new_stage && timestamp_goes_on)) return Staleness::behind;
  }
  return Staleness::fresh;
}

bool RefereeFollower::resync_due(const Referee& message, Staleness why, double receive_s) {
  const auto old = [&](double at_s) {
    return receive_s - at_s > resync_window_s || at_s > receive_s;
  };
  while (!used_s_.empty() && old(used_s_.front())) used_s_.pop_front();
  while (!refused_.empty() && old(refused_.front().receive_s)) refused_.pop_front();
  const std::uint64_t timestamp = message.has_packet_timestamp() ? message.packet_timestamp() : 0;
  const bool time_goes_on = why == Staleness::behind && last_timestamp_us_ &&
                            message.has_packet_timestamp() && timestamp >= *last_timestamp_us_;
  counter_refusals_in_a_row_ = time_goes_on ? counter_refusals_in_a_row_ + 1 : 0;
  refused_.push_back(Refused{receive_s, timestamp, why == Staleness::ahead});
  // Bounded whatever the flood: the oldest refusals go first.
  constexpr std::size_t max_refused_kept = 4096;
  if (refused_.size() > max_refused_kept) refused_.pop_front();
  std::size_t ahead = 0;
  std::uint64_t newest_us = 0;
  for (const Refused& r : refused_) {
    ahead += r.ahead ? 1 : 0;
    newest_us = std::max(newest_us, r.timestamp_us);
  }
  const bool counter_forged = counter_refusals_in_a_row_ >= resync_counter_refusals;
  const bool newer_clock = ahead >= resync_refusals;
  const bool followed_gone =
      refused_.size() >= resync_refusals && used_s_.size() <= resync_max_used;
  // Taken up again with the newest of them, never with a replay older than the others.
  if (!(counter_forged || newer_clock || followed_gone) || timestamp < newest_us) return false;
  refused_.clear();
  used_s_.clear();
  counter_refusals_in_a_row_ = 0;
  return true;
}

std::string stage_name(int stage) {
  if (stage < 0 || !Referee::Stage_IsValid(stage)) return {};
  return Referee::Stage_Name(static_cast<Referee::Stage>(stage));
}

std::string describe(const RefereeFollower& referee) {
  if (!referee.heard()) return "no referee heard";
  const RefereeView& view = referee.view();
  std::string out = "game ";
  out += to_string(view.state);
  if (const std::string stage = stage_name(view.stage); !stage.empty()) {
    out += ", stage ";
    out += stage;
  }
  out += ", yellow '" + view.yellow_name + "', blue '" + view.blue_name + "'";
  if (view.blue_on_positive_half) {
    out += *view.blue_on_positive_half ? ", blue's goal on +x" : ", blue's goal on -x";
  }
  return out;
}

}  // namespace match
}  // namespace ssl_formation
