#pragma once
// The match as the options and the referee feed describe it: who the opponent is (its name and
// colour), which way it attacks, the game state, and why each is what it is. Training and
// prediction each follow one, and hand the opponent to their sampler.
//
// What wins: an explicit --opponent-color / --opponent-attacks, then the referee (the colour
// from the team names and --our-team or --opponent-team, the side from
// blue_team_on_positive_half), then inference of the side (--opponent-attacks auto), then the
// defaults (yellow, attacking +x), which are the behaviour without a referee feed.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/match/referee.hpp"

namespace ssl_formation {
inline namespace match {

// Why the opponent's colour or side is what it is.
enum class Because : std::uint8_t { default_setting, option, referee, inferred };
std::string_view to_string(Because because);  // "default", "option", "referee", "inferred"

// What the options ask for.
struct OpponentChoice {
  std::optional<TeamColor> color;          // --opponent-color yellow|blue
  std::optional<AttackDirection> attacks;  // --opponent-attacks +x|-x
  bool infer_attacks = false;              // --opponent-attacks auto
  std::string our_team;                    // --our-team: the opponent is the other team
  std::string opponent_team;               // --opponent-team
};

struct Opponent {
  TeamColor color = TeamColor::yellow;
  Because color_because = Because::default_setting;
  // None: the sampler infers it from where the goalkeeper stands.
  std::optional<AttackDirection> attacks = AttackDirection::positive_x;
  Because attacks_because = Because::default_setting;
  std::string name;  // the referee's name for the opponent; empty when unnamed or unknown
  // Set when a team was named in the options but the referee names no such team, saying so.
  std::string unresolved;
  friend bool operator==(const Opponent&, const Opponent&) = default;
};

// Options that fix the colour and the side (or infer the side), winning over the referee: what a
// program given --opponent-color and --opponent-attacks follows.
OpponentChoice fixed_opponent(TeamColor color, AttackDirection attacks, bool infer_attacks);

// Team names as the game controller spells them and as a user types them: equal ignoring case
// and the spaces around them.
bool same_team_name(std::string_view a, std::string_view b);
// The name without the spaces around it.
std::string_view trimmed_team_name(std::string_view name);

// The opponent the options and what the referee said (none: no referee heard) make.
Opponent resolve_opponent(const OpponentChoice& choice, const RefereeView* referee);

// "'ER-Force' blue (referee), attacks -x (referee)"; `attacks_now` is the side the sampler uses
// (the inferred one, for Because::inferred; none while unknown).
std::string describe(const Opponent& opponent, std::optional<AttackDirection> attacks_now);

// What training counts: --learn-during running (the default: only running play, and nothing
// across a change of command) or all (every state, as without a referee).
enum class LearnDuring : std::uint8_t { running, all };
std::optional<LearnDuring> parse_learn_during(std::string_view text);
std::string_view to_string(LearnDuring learn_during);

// The referee follower and the opponent it implies, kept in step.
class MatchFollower {
 public:
  explicit MatchFollower(OpponentChoice choice = {});

  // A referee message (a datagram or a log's type-3 payload) received at `receive_s`.
  RefereeChange add_referee(std::string_view payload, double receive_s);
  // A new stream (another log file): the referee is heard anew.
  void reset();

  const Opponent& opponent() const { return opponent_; }
  GameState game_state() const { return referee_.view().state; }
  const RefereeFollower& referee() const { return referee_; }
  const OpponentChoice& choice() const { return choice_; }
  // Whether the opponent is known: always unless the options name a team (--our-team,
  // --opponent-team) that the referee has not (yet) found.
  bool opponent_known() const { return opponent_.unresolved.empty(); }
  // The referee's name of the opponent the last time it was known by a name (empty if never):
  // a log over a whole day may name a team first and other teams after it.
  const std::string& last_named_opponent() const { return last_named_; }
  // Whether the opponent the options name was ever found in the referee's names (always true
  // when they name none).
  bool opponent_ever_known() const { return ever_known_; }
  // Whether learning may count now: never while a named opponent is not found (its colour is
  // not known: a log of other teams teaches nothing about it); else always without a referee
  // heard (the game state is not known) or with LearnDuring::all, else only in running play.
  bool learning(LearnDuring learn_during) const {
    if (!opponent_known()) return false;
    return learn_during == LearnDuring::all || !referee_.heard() ||
           is_running_play(referee_.view().state);
  }

 private:
  void remember_opponent();

  OpponentChoice choice_;
  RefereeFollower referee_;
  Opponent opponent_;
  std::string last_named_;
  bool ever_known_ = false;
};

}  // namespace match
}  // namespace ssl_formation
