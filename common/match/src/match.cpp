#include "ssl_formation/match/match.hpp"

#include <cctype>
#include <utility>

namespace ssl_formation {
inline namespace match {

std::string_view to_string(Because because) {
  switch (because) {
    case Because::option:
      return "option";
    case Because::referee:
      return "referee";
    case Because::inferred:
      return "inferred";
    case Because::default_setting:
      break;
  }
  return "default";
}

std::string_view trimmed_team_name(std::string_view name) {
  while (!name.empty() && std::isspace(static_cast<unsigned char>(name.front()))) {
    name.remove_prefix(1);
  }
  while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back()))) {
    name.remove_suffix(1);
  }
  return name;
}

OpponentChoice fixed_opponent(TeamColor color, AttackDirection attacks, bool infer_attacks) {
  OpponentChoice choice;
  choice.color = color;
  if (infer_attacks) {
    choice.infer_attacks = true;
  } else {
    choice.attacks = attacks;
  }
  return choice;
}

bool same_team_name(std::string_view a, std::string_view b) {
  a = trimmed_team_name(a);
  b = trimmed_team_name(b);
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i]))) {
      return false;
    }
  }
  return true;
}

Opponent resolve_opponent(const OpponentChoice& choice, const RefereeView* referee) {
  Opponent opponent;
  if (choice.color) {
    opponent.color = *choice.color;
    opponent.color_because = Because::option;
  } else if (!choice.our_team.empty() || !choice.opponent_team.empty()) {
    const bool by_our_name = choice.opponent_team.empty();
    const std::string& named = by_our_name ? choice.our_team : choice.opponent_team;
    const bool yellow = referee && same_team_name(named, referee->yellow_name);
    const bool blue = referee && same_team_name(named, referee->blue_name);
    if (yellow != blue) {
      // The named team's colour, or the other one when the name is ours.
      opponent.color = yellow != by_our_name ? TeamColor::yellow : TeamColor::blue;
      opponent.color_because = Because::referee;
    } else {
      const std::string which = (by_our_name ? "our team '" : "the opponent '") + named + "'";
      if (!referee) {
        opponent.unresolved = "no referee heard yet to find " + which + " by";
      } else if (yellow) {
        opponent.unresolved = "the referee gives both teams the name of " + which;
      } else {
        opponent.unresolved = "the referee names neither team " + which + " (yellow '" +
                              referee->yellow_name + "', blue '" + referee->blue_name + "')";
      }
    }
  }
  // Unresolved, the colour is only the default: the team playing it is not the one named.
  if (referee && opponent.unresolved.empty()) {
    opponent.name = opponent.color == TeamColor::yellow ? referee->yellow_name : referee->blue_name;
  }
  if (choice.attacks) {
    opponent.attacks = *choice.attacks;
    opponent.attacks_because = Because::option;
  } else if (referee && referee->blue_on_positive_half) {
    // A team attacks the goal it does not defend.
    const bool blue_attacks_negative = *referee->blue_on_positive_half;
    const bool negative = (opponent.color == TeamColor::blue) == blue_attacks_negative;
    opponent.attacks = negative ? AttackDirection::negative_x : AttackDirection::positive_x;
    opponent.attacks_because = Because::referee;
  } else if (choice.infer_attacks) {
    opponent.attacks.reset();
    opponent.attacks_because = Because::inferred;
  }
  return opponent;
}

std::string describe(const Opponent& opponent, std::optional<AttackDirection> attacks_now) {
  std::string out;
  if (!opponent.name.empty()) out += "'" + opponent.name + "' ";
  out += to_string(opponent.color);
  out += " (";
  out += to_string(opponent.color_because);
  out += "), attacks ";
  out += attacks_now ? to_string(*attacks_now) : std::string_view("unknown yet");
  out += " (";
  out += to_string(opponent.attacks_because);
  out += ")";
  if (!opponent.unresolved.empty()) out += "; " + opponent.unresolved;
  return out;
}

std::optional<LearnDuring> parse_learn_during(std::string_view text) {
  if (text == "running") return LearnDuring::running;
  if (text == "all") return LearnDuring::all;
  return std::nullopt;
}

std::string_view to_string(LearnDuring learn_during) {
  return learn_during == LearnDuring::all ? "all" : "running";
}

MatchFollower::MatchFollower(OpponentChoice choice)
    : choice_(std::move(choice)), opponent_(resolve_opponent(choice_, nullptr)) {
  remember_opponent();
}

RefereeChange MatchFollower::add_referee(std::string_view payload, double receive_s) {
  const RefereeChange change = referee_.add(payload, receive_s);
  if (change.any()) {
    opponent_ = resolve_opponent(choice_, &referee_.view());
    remember_opponent();
  }
  return change;
}

void MatchFollower::reset() {
  referee_.reset();
  opponent_ = resolve_opponent(choice_, nullptr);
  last_named_.clear();
  ever_known_ = false;
  remember_opponent();
}

void MatchFollower::remember_opponent() {
  if (!opponent_known()) return;
  ever_known_ = true;
  if (!opponent_.name.empty()) last_named_ = opponent_.name;
}

}  // namespace match
}  // namespace ssl_formation
