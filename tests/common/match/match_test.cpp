// The match (common/match/src/match.cpp): who the opponent is and which way it attacks, from the
// options and the referee, and when learning may count.

#include "ssl_formation/match/match.hpp"

#include <gtest/gtest.h>

#include <string>

#include "ssl_gc_referee_message.pb.h"

namespace sf = ssl_formation;

namespace {

using sf::AttackDirection;
using sf::Because;
using sf::TeamColor;

sf::RefereeView view(const std::string& yellow, const std::string& blue,
                     std::optional<bool> blue_on_positive_half = std::nullopt) {
  sf::RefereeView v;
  v.state = sf::GameState::running;
  v.command = Referee::NORMAL_START;
  v.yellow_name = yellow;
  v.blue_name = blue;
  v.blue_on_positive_half = blue_on_positive_half;
  return v;
}

Referee::TeamInfo team(const std::string& name) {
  Referee::TeamInfo info;
  info.set_name(name);
  info.set_score(0);
  info.set_red_cards(0);
  info.set_yellow_cards(0);
  info.set_timeouts(4);
  info.set_timeout_time(300000000);
  info.set_goalkeeper(0);
  return info;
}

std::string payload(Referee::Command command, std::uint32_t counter, const std::string& yellow,
                    const std::string& blue, std::optional<bool> blue_on_positive_half) {
  Referee m;
  m.set_packet_timestamp(1);
  m.set_stage(Referee::NORMAL_FIRST_HALF);
  m.set_command(command);
  m.set_command_counter(counter);
  m.set_command_timestamp(1);
  *m.mutable_yellow() = team(yellow);
  *m.mutable_blue() = team(blue);
  if (blue_on_positive_half) m.set_blue_team_on_positive_half(*blue_on_positive_half);
  m.set_source_identifier("gc");
  EXPECT_TRUE(m.IsInitialized());
  return m.SerializeAsString();
}

TEST(SameTeamName, CaseAndSurroundingSpacesAreIgnored) {
  EXPECT_TRUE(sf::same_team_name("ER-Force", "ER-Force"));
  EXPECT_TRUE(sf::same_team_name("  tigers MANNHEIM\t", "TIGERs Mannheim"));
  EXPECT_TRUE(sf::same_team_name("er-force", " ER-FORCE "));
  EXPECT_FALSE(sf::same_team_name("ER-Force", "ER Force"));
  EXPECT_FALSE(sf::same_team_name("TIGERs", "TIGERs Mannheim"));
  EXPECT_FALSE(sf::same_team_name("RoboTeam", "KIKS"));
}

TEST(ResolveOpponent, WithoutARefereeTheDefaultsHold) {
  const sf::Opponent plain = sf::resolve_opponent({}, nullptr);
  EXPECT_EQ(plain.color, TeamColor::yellow);
  EXPECT_EQ(plain.color_because, Because::default_setting);
  EXPECT_EQ(plain.attacks, AttackDirection::positive_x);
  EXPECT_EQ(plain.attacks_because, Because::default_setting);
  EXPECT_EQ(plain.name, "");
  EXPECT_EQ(plain.unresolved, "");
  sf::OpponentChoice infer;
  infer.infer_attacks = true;
  const sf::Opponent inferred = sf::resolve_opponent(infer, nullptr);
  EXPECT_EQ(inferred.color, TeamColor::yellow);
  EXPECT_EQ(inferred.attacks, std::nullopt);
  EXPECT_EQ(inferred.attacks_because, Because::inferred);
  // A referee that says nothing of the sides leaves inference to it too.
  const sf::RefereeView silent = view("A", "B");
  EXPECT_EQ(sf::resolve_opponent(infer, &silent).attacks_because, Because::inferred);
  EXPECT_EQ(sf::resolve_opponent({}, &silent).attacks, AttackDirection::positive_x);
  EXPECT_EQ(sf::resolve_opponent({}, &silent).attacks_because, Because::default_setting);
}

TEST(ResolveOpponent, TheOptionsWinOverTheReferee) {
  const sf::RefereeView referee = view("Us", "Them", true);  // would make blue attack -x
  sf::OpponentChoice choice;
  choice.color = TeamColor::yellow;
  choice.attacks = AttackDirection::positive_x;
  choice.our_team = "Us";  // would make blue the opponent
  choice.infer_attacks = true;
  const sf::Opponent opponent = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(opponent.color, TeamColor::yellow);
  EXPECT_EQ(opponent.color_because, Because::option);
  EXPECT_EQ(opponent.attacks, AttackDirection::positive_x);
  EXPECT_EQ(opponent.attacks_because, Because::option);
  EXPECT_EQ(opponent.name, "Us");
  choice.color = TeamColor::blue;
  choice.attacks = AttackDirection::negative_x;
  const sf::RefereeView second_half = view("Us", "Them", false);  // would make blue attack +x
  const sf::Opponent blue = sf::resolve_opponent(choice, &second_half);
  EXPECT_EQ(blue.color, TeamColor::blue);
  EXPECT_EQ(blue.attacks, AttackDirection::negative_x);
  EXPECT_EQ(blue.name, "Them");
}

TEST(ResolveOpponent, OurTeamsColourMakesTheOpponentTheOtherOne) {
  const sf::RefereeView referee = view("TIGERs Mannheim", "ER-Force");
  sf::OpponentChoice choice;
  choice.our_team = "tigers mannheim";
  const sf::Opponent vs_blue = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(vs_blue.color, TeamColor::blue);
  EXPECT_EQ(vs_blue.color_because, Because::referee);
  EXPECT_EQ(vs_blue.name, "ER-Force");
  EXPECT_EQ(vs_blue.unresolved, "");
  choice.our_team = " ER-Force ";
  const sf::Opponent vs_yellow = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(vs_yellow.color, TeamColor::yellow);
  EXPECT_EQ(vs_yellow.color_because, Because::referee);
  EXPECT_EQ(vs_yellow.name, "TIGERs Mannheim");
}

TEST(ResolveOpponent, TheOpponentsNamePicksItsColour) {
  const sf::RefereeView referee = view("TIGERs Mannheim", "ER-Force");
  sf::OpponentChoice choice;
  choice.opponent_team = "ER-FORCE";
  const sf::Opponent blue = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(blue.color, TeamColor::blue);
  EXPECT_EQ(blue.color_because, Because::referee);
  EXPECT_EQ(blue.name, "ER-Force");
  choice.opponent_team = "TIGERs Mannheim";
  const sf::Opponent yellow = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(yellow.color, TeamColor::yellow);
  EXPECT_EQ(yellow.color_because, Because::referee);
  EXPECT_EQ(yellow.name, "TIGERs Mannheim");
}

TEST(ResolveOpponent, ANameTheRefereeDoesNotGiveIsUnresolved) {
  const sf::RefereeView referee = view("TIGERs Mannheim", "ER-Force");
  sf::OpponentChoice choice;
  choice.opponent_team = "RoboTeam Twente";
  const sf::Opponent opponent = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(opponent.color, TeamColor::yellow);
  EXPECT_EQ(opponent.color_because, Because::default_setting);
  EXPECT_NE(opponent.unresolved.find("RoboTeam Twente"), std::string::npos) << opponent.unresolved;
  // Without a referee yet, the same.
  const sf::Opponent early = sf::resolve_opponent(choice, nullptr);
  EXPECT_EQ(early.color_because, Because::default_setting);
  EXPECT_NE(early.unresolved.find("RoboTeam Twente"), std::string::npos) << early.unresolved;
}

TEST(ResolveOpponent, BothTeamsWithTheSameNameAreUnresolved) {
  const sf::RefereeView referee = view("Mirror", "mirror ");
  sf::OpponentChoice choice;
  choice.our_team = "Mirror";
  const sf::Opponent opponent = sf::resolve_opponent(choice, &referee);
  EXPECT_EQ(opponent.color, TeamColor::yellow);
  EXPECT_EQ(opponent.color_because, Because::default_setting);
  EXPECT_NE(opponent.unresolved.find("Mirror"), std::string::npos) << opponent.unresolved;
}

TEST(ResolveOpponent, TheSideFollowsBlueTeamOnPositiveHalf) {
  struct Case {
    TeamColor color;
    bool blue_on_positive_half;
    AttackDirection expected;
  };
  // Blue defending +x attacks -x; yellow then defends -x and attacks +x.
  const Case cases[] = {
      {TeamColor::blue, true, AttackDirection::negative_x},
      {TeamColor::yellow, true, AttackDirection::positive_x},
      {TeamColor::blue, false, AttackDirection::positive_x},
      {TeamColor::yellow, false, AttackDirection::negative_x},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(sf::to_string(c.color)) + (c.blue_on_positive_half ? " +" : " -"));
    const sf::RefereeView referee = view("Y", "B", c.blue_on_positive_half);
    sf::OpponentChoice by_option;
    by_option.color = c.color;
    by_option.infer_attacks = true;
    const sf::Opponent opponent = sf::resolve_opponent(by_option, &referee);
    EXPECT_EQ(opponent.attacks, c.expected);
    EXPECT_EQ(opponent.attacks_because, Because::referee);
    EXPECT_EQ(opponent.name, c.color == TeamColor::yellow ? "Y" : "B");
    sf::OpponentChoice by_name;
    by_name.opponent_team = c.color == TeamColor::yellow ? "Y" : "B";
    EXPECT_EQ(sf::resolve_opponent(by_name, &referee).attacks, c.expected);
  }
}

TEST(MatchFollower, FollowsTheChangeOfEndsAndANewOpponentName) {
  sf::OpponentChoice choice;
  choice.our_team = "Us";
  sf::MatchFollower match(choice);
  EXPECT_EQ(match.opponent(), sf::resolve_opponent(choice, nullptr));
  EXPECT_FALSE(match.opponent().unresolved.empty());
  match.add_referee(payload(Referee::NORMAL_START, 1, "Us", "Them", true), 1.0);
  EXPECT_EQ(match.opponent().color, TeamColor::blue);
  EXPECT_EQ(match.opponent().name, "Them");
  EXPECT_EQ(match.opponent().attacks, AttackDirection::negative_x);
  EXPECT_EQ(match.opponent().unresolved, "");
  EXPECT_EQ(match.game_state(), sf::GameState::running);
  // Half time: the teams change ends.
  const sf::RefereeChange ends =
      match.add_referee(payload(Referee::STOP, 2, "Us", "Them", false), 2.0);
  EXPECT_TRUE(ends.sides);
  EXPECT_EQ(match.opponent().attacks, AttackDirection::positive_x);
  EXPECT_EQ(match.opponent().attacks_because, Because::referee);
  // A new name takes over once it has held for a second.
  EXPECT_FALSE(match.add_referee(payload(Referee::STOP, 2, "Us", "Them Again", false), 3.0).teams);
  EXPECT_EQ(match.opponent().name, "Them");
  const sf::RefereeChange renamed =
      match.add_referee(payload(Referee::STOP, 2, "Us", "Them Again", false), 4.1);
  EXPECT_TRUE(renamed.teams);
  EXPECT_FALSE(renamed.command);
  EXPECT_EQ(match.opponent().name, "Them Again");
  EXPECT_EQ(match.opponent().color, TeamColor::blue);
}

TEST(MatchFollower, LearningCountsOnlyRunningPlayUnlessAll) {
  sf::MatchFollower match;
  EXPECT_TRUE(match.learning(sf::LearnDuring::running));  // no referee: the state is unknown
  EXPECT_TRUE(match.learning(sf::LearnDuring::all));
  const struct {
    Referee::Command command;
    bool learning;
  } cases[] = {
      {Referee::HALT, false},
      {Referee::NORMAL_START, true},
      {Referee::STOP, false},
      {Referee::DIRECT_FREE_YELLOW, true},
      {Referee::BALL_PLACEMENT_BLUE, false},
      {Referee::FORCE_START, true},
      {Referee::PREPARE_KICKOFF_BLUE, false},
      {Referee::TIMEOUT_YELLOW, false},
  };
  std::uint32_t counter = 0;
  for (const auto& c : cases) {
    SCOPED_TRACE(Referee::Command_Name(c.command));
    ++counter;
    match.add_referee(payload(c.command, counter, "A", "B", std::nullopt), 0.1 * counter);
    EXPECT_EQ(match.learning(sf::LearnDuring::running), c.learning);
    EXPECT_TRUE(match.learning(sf::LearnDuring::all));
  }
}

TEST(MatchFollower, ResetReturnsToTheOpponentOfTheOptionsAlone) {
  sf::OpponentChoice choice;
  choice.opponent_team = "Them";
  choice.infer_attacks = true;
  sf::MatchFollower match(choice);
  const sf::Opponent before = match.opponent();
  EXPECT_EQ(before.attacks_because, Because::inferred);
  match.add_referee(payload(Referee::HALT, 1, "Us", "Them", true), 1.0);
  EXPECT_EQ(match.opponent().color, TeamColor::blue);
  EXPECT_EQ(match.opponent().attacks_because, Because::referee);
  EXPECT_FALSE(match.learning(sf::LearnDuring::running));
  match.reset();
  EXPECT_EQ(match.opponent(), before);
  EXPECT_EQ(match.game_state(), sf::GameState::unknown);
  EXPECT_FALSE(match.referee().heard());
  // The named opponent is not found again yet: nothing is learned of whoever plays meanwhile.
  EXPECT_FALSE(match.opponent_known());
  EXPECT_FALSE(match.learning(sf::LearnDuring::all));
  EXPECT_EQ(match.referee().counters().messages, 1u);
}

TEST(LearnDuring, ParsesWhatItPrintsAndRejectsTheRest) {
  for (const sf::LearnDuring l : {sf::LearnDuring::running, sf::LearnDuring::all}) {
    EXPECT_EQ(sf::parse_learn_during(sf::to_string(l)), l);
  }
  EXPECT_EQ(sf::to_string(sf::LearnDuring::running), "running");
  EXPECT_EQ(sf::to_string(sf::LearnDuring::all), "all");
  EXPECT_EQ(sf::parse_learn_during("sometimes"), std::nullopt);
  EXPECT_EQ(sf::parse_learn_during(""), std::nullopt);
}

}  // namespace
