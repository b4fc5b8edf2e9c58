#pragma once
// The referee feed (the game controller's Referee messages): the game state the
// last command left the match in, the teams' names and which half each defends, followed from
// one game controller. Pure: the daemons feed it from the referee multicast group, the offline
// tools from a log's type-3 messages, each with its own receive clock (time is an input).
//
//   RefereeFollower referee;
//   const RefereeChange change = referee.add(payload, receive_s);
//   if (change.command) ... referee.view().state ...

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/match/team_name_gate.hpp"

class Referee;

namespace ssl_formation {
inline namespace match {

// The match's state as the followed game controller's last command left it.
enum class GameState : std::uint8_t {
  unknown,  // no referee message yet (or none that could be read)
  halt,
  stop,                 // also the deprecated GOAL_YELLOW / GOAL_BLUE, which a STOP follows
  running,              // after NORMAL_START or FORCE_START
  free_kick,            // DIRECT_FREE_* (and the deprecated INDIRECT_FREE_*)
  kickoff_preparation,  // PREPARE_KICKOFF_*
  penalty_preparation,  // PREPARE_PENALTY_*
  ball_placement,       // BALL_PLACEMENT_*
  timeout,              // TIMEOUT_*
};
inline constexpr int game_state_count = 9;
std::string_view to_string(GameState state);  // "running", "ball_placement", ...
std::optional<GameState> parse_game_state(std::string_view text);
// The game state a command (Referee::Command's number) leaves the match in; none for a number
// the wire format does not define.
std::optional<GameState> game_state_of_command(int command);

// Whether the robots play freely, which is what learning in running play counts: after
// NORMAL_START or FORCE_START, and in a free kick. The game controller issues no NORMAL_START
// after a free kick (play goes on under DIRECT_FREE until the next STOP or HALT), so a free
// kick's command covers the play that follows it too.
bool is_running_play(GameState state);

// What the followed game controller said last.
struct RefereeView {
  GameState state = GameState::unknown;
  int command = -1;  // Referee::Command's number; -1 before the first message
  std::uint32_t command_counter = 0;
  int stage = -1;           // Referee::Stage's number; -1 before the first message
  std::string yellow_name;  // empty: the game controller was not told the name
  std::string blue_name;
  // True when blue's goal is on the +x side of the vision frame; none while the game controller
  // has not said (older ones never do).
  std::optional<bool> blue_on_positive_half;
  // Where the ball is to be placed (designated_position, millimetres, feed coordinates), as the
  // last message used says: the game controller sends it with a ball placement's command. None
  // when that message had none (or a part of it missing or not finite).
  std::optional<Point> designated_position;
  std::string source;  // the source_identifier followed ("" from a game controller without one)
};

// What one message changed in the view.
struct RefereeChange {
  bool command = false;   // a new command (or a new game controller's first)
  bool teams = false;     // a team name changed
  bool sides = false;     // blue_team_on_positive_half changed (the teams changed ends)
  bool source = false;    // another game controller is followed from now on
  bool conflict = false;  // this message came from a second game controller, and was not used
  bool stale = false;     // from the followed one, but older than what it said: not used
  bool resync = false;    // used after all: what was followed before was the stale one
  bool any() const { return command || teams || sides || source; }
};

// Every referee message by what became of it.
struct RefereeCounters {
  std::uint64_t messages = 0;
  std::uint64_t used = 0;             // from the followed game controller
  std::uint64_t undecodable = 0;      // not a Referee message at all: not used
  std::uint64_t unknown_command = 0;  // a command number the wire format does not define: not used
  std::uint64_t other_source = 0;     // from a second game controller while one is followed
  // From the followed game controller but stale or replayed: a command counter that went back,
  // a packet timestamp more than max_timestamp_back_s before its last (or far ahead of it).
  std::uint64_t stale = 0;
  // Times the follower took up the followed game controller's messages again after refusing
  // them: a replay heard first, a log looping back, one forged message that ran ahead.
  std::uint64_t resyncs = 0;
  std::uint64_t source_switches = 0;  // the followed one fell silent and another took over
  std::uint64_t unnamed_teams = 0;    // messages that name neither team (used all the same)
  // New team names that did not take over: they did not hold for name_hold_s of the followed
  // game controller's messages, or came when max_name_switches teams had already switched within
  // name_switch_window_s (spoofed names on a shared network, a half-configured tool).
  std::uint64_t refused_name_switches = 0;
  std::uint64_t commands = 0;  // new commands followed
};

class RefereeFollower {
 public:
  // A followed game controller silent for this long gives way to the next one heard.
  static constexpr double default_source_timeout_s = 2.0;
  // A message of the followed game controller whose packet timestamp is this much before the
  // last one used is stale (a replay), and one whose timestamp runs this much plus the time
  // between the two messages ahead of it is forged: neither is used.
  static constexpr double max_timestamp_back_s = 1.0;
  static constexpr double max_timestamp_ahead_s = 10.0;
  // What was followed is given up for the newest of the refused messages when
  // - resync_counter_refusals in a row had a counter behind it but a timestamp that goes on (the
  //   last message used was a forged one whose counter ran ahead);
  // - within resync_window_s, resync_refusals were refused as ahead of it (a newer clock: the
  //   first message heard was a replay);
  // - or that many were refused while at most resync_max_used were used (what was followed fell
  //   silent: a log started over, a forged timestamp ran ahead).
  // Replays mixed into a live game controller's messages do none of these.
  static constexpr std::size_t resync_counter_refusals = 3;
  static constexpr double resync_window_s = 2.0;
  static constexpr std::size_t resync_refusals = 10;
  static constexpr std::size_t resync_max_used = 2;
  // When new team names take over (team_name_gate.hpp).
  static constexpr double name_hold_s = TeamNameGate::name_hold_s;
  static constexpr int max_name_switches = TeamNameGate::max_name_switches;
  static constexpr double name_switch_window_s = TeamNameGate::name_switch_window_s;

  explicit RefereeFollower(double source_timeout_s = default_source_timeout_s);

  // A referee datagram or a log's type-3 payload, received at `receive_s` (any clock that
  // increases; the daemons' steady clock, a log's receive time). Bad input is counted, never
  // thrown.
  RefereeChange add(std::string_view payload, double receive_s);
  RefereeChange add(const Referee& message, double receive_s);

  // Forgets the game controller and what it said (a new log file), keeping the counters.
  void reset() {
    heard_ = false;
    view_ = RefereeView{};
    last_timestamp_us_.reset();
    conflicting_source_.clear();
    names_.reset();
    used_s_.clear();
    refused_.clear();
    counter_refusals_in_a_row_ = 0;
  }

  // Whether a message has been followed yet.
  bool heard() const { return heard_; }
  const RefereeView& view() const { return view_; }
  const RefereeCounters& counters() const { return counters_; }

 private:
  // Whether `message`, from the followed game controller, is older than what it said last: see
  // RefereeCounters::stale. A restarted game controller, whose counter starts again from 0, is
  // told apart by a silence of source_timeout_s, or by a new stage with a timestamp that does
  // not go back.
  enum class Staleness { fresh, behind, ahead };
  Staleness staleness(const Referee& message, double receive_s) const;
  // Notes a refused message and says whether it is to be used after all (resync_window_s).
  bool resync_due(const Referee& message, Staleness why, double receive_s);

  double source_timeout_s_;
  bool heard_ = false;
  double last_used_s_ = 0.0;
  std::optional<std::uint64_t> last_timestamp_us_;  // packet_timestamp of the last message used
  TeamNameGate names_;
  // The followed game controller's messages within resync_window_s: when each used one came,
  // and each refused one's arrival, timestamp and why.
  struct Refused {
    double receive_s = 0.0;
    std::uint64_t timestamp_us = 0;
    bool ahead = false;
  };
  std::deque<double> used_s_;
  std::deque<Refused> refused_;
  std::size_t counter_refusals_in_a_row_ = 0;
  RefereeView view_;
  RefereeCounters counters_;
  std::string conflicting_source_;  // the last second game controller reported
};

// Referee::Stage's name for its number ("NORMAL_FIRST_HALF"), or "" for one the wire format does
// not define (and -1, before the first message).
std::string stage_name(int stage);

// "game running, stage NORMAL_FIRST_HALF, yellow 'TIGERs Mannheim', blue 'ER-Force', blue's goal
// on +x", or "no referee heard", for status lines.
std::string describe(const RefereeFollower& referee);

}  // namespace match
}  // namespace ssl_formation
