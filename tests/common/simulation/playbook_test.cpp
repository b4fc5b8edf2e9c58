#include "ssl_formation/simulation/playbook.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "scratch_dir.hpp"

namespace ssl_formation::simulation {
namespace {

Playbook parsed(std::string_view text) {
  auto playbook = parse_playbook(text, "test.txt");
  EXPECT_TRUE(playbook) << (playbook ? "" : playbook.error().message);
  return playbook ? std::move(*playbook) : Playbook{};
}

// The error of a playbook that should be refused.
std::string refusal(std::string_view text) {
  auto playbook = parse_playbook(text, "plays.txt");
  EXPECT_FALSE(playbook) << "accepted:\n" << text;
  return playbook ? std::string() : playbook.error().message;
}

TEST(Playbook, AFileGivesItsPlaysStepsBallsAndTargets) {
  const Playbook book = parsed(R"(# a comment line
playbook "Test book"

play "attack down the left" weight 2.5   # a comment after words
  restart kickoff
  step 2.5 ball 3
    1 -0.5 -0.3
    3  0.1  0.6
  step 1 ball goal
    3 0.8 0.0

play short
  step 0.5
)");
  EXPECT_EQ(book.name, "Test book");
  ASSERT_EQ(book.plays.size(), 2u);
  const Play& left = book.plays[0];
  EXPECT_EQ(left.name, "attack down the left");
  EXPECT_DOUBLE_EQ(left.weight, 2.5);
  EXPECT_EQ(left.restart, PlayRestart::kickoff);
  EXPECT_EQ(left.line, 4);
  ASSERT_EQ(left.steps.size(), 2u);
  EXPECT_DOUBLE_EQ(left.steps[0].hold_s, 2.5);
  EXPECT_EQ(left.steps[0].ball_robot, 3u);
  EXPECT_FALSE(left.steps[0].shot);
  ASSERT_EQ(left.steps[0].targets.size(), 2u);
  EXPECT_EQ(left.steps[0].targets[0].robot_id, 1u);
  EXPECT_EQ(left.steps[0].targets[0].position, (Point{-0.5, -0.3}));
  EXPECT_EQ(left.steps[0].targets[1].position, (Point{0.1, 0.6}));
  EXPECT_TRUE(left.steps[1].shot);
  EXPECT_FALSE(left.steps[1].ball_robot.has_value());
  const Play& short_play = book.plays[1];
  EXPECT_EQ(short_play.name, "short");
  EXPECT_DOUBLE_EQ(short_play.weight, 1.0);
  EXPECT_EQ(short_play.restart, PlayRestart::any);
  EXPECT_TRUE(short_play.steps[0].targets.empty());
}

TEST(Playbook, AnErrorNamesTheFileTheLineAndWhatIsWrong) {
  const std::string head = "playbook \"x\"\nplay a\n  step 2\n";  // lines 1 to 3
  const std::vector<std::pair<std::string, std::string>> cases{
      {head + "    11 0.1 0.1\n", "plays.txt:4: robot 11: ids go from 1 to 10 (0 keeps goal)"},
      {head + "    0 0.1 0.1\n", "plays.txt:4: robot 0 keeps goal"},
      {head + "    3 1.5 0.1\n", "plays.txt:4: robot 3 at 1.5 0.1: off the field"},
      {head + "    3 0.1\n", "plays.txt:4: expected: ROBOT X Y"},
      {head + "    3 0.1 zero\n", "plays.txt:4: robot 3: '0.1 zero' is not two numbers"},
      {head + "    3 0.1 0.1\n    3 0.2 0.2\n", "plays.txt:5: robot 3 twice in one step"},
      {head + "  step 0\n", "plays.txt:4: step '0': the seconds to hold it must be more than 0"},
      {head + "  step 2 ball 12\n", "plays.txt:4: ball '12': expected a robot id from 1 to 10"},
      {head + "  step 2 ball 0\n", "plays.txt:4: ball '0': expected a robot id from 1 to 10"},
      {"play a\nplaybook \"y\"\n", "plays.txt:2: 'playbook' names the playbook once, first"},
      {head + "  restart kickoff\n", "plays.txt:4: 'restart' comes before the play's first step"},
      {head + "  restart corner\n", "plays.txt:4: 'restart' comes before"},
      {"play a\n  restart corner\n", "plays.txt:2: restart 'corner': expected kickoff"},
      {head + "pass 3\n", "plays.txt:4: unknown word 'pass'"},
      {head + "play \"b\n", "plays.txt:4: a name in quotes has no closing quote"},
      {head + "play a\n  step 1\n",
       "plays.txt:4: a second play named 'a' (the first is on line 2)"},
      {head + "play b weight -1\n", "plays.txt:4: weight '-1': expected a positive number"},
      {head + "play b\nplay c\n  step 1\n", "plays.txt:5: play 'b' (line 4) has no steps"},
      {"  step 1\n", "plays.txt:1: 'step' belongs to a play"},
      {"play a\n    1 0 0\n", "plays.txt:2: a robot's target belongs to a step"},
      {head + "playbook \"y\"\n", "plays.txt:4: 'playbook' names the playbook once, first"},
      {"# nothing\n\n", "plays.txt: no plays"},
      {"play a\n", "plays.txt:1: play 'a' (line 1) has no steps"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string error = refusal(text);
    EXPECT_EQ(error.rfind(expected, 0), 0u)
        << "got:      " << error << "\nexpected: " << expected << "...\nfor:\n"
        << text;
  }
}

TEST(Playbook, TheBuiltInPlaybooksParseAndEachHasAKickOffAFreeKickAndARetreat) {
  const std::vector<std::string> names = builtin_playbook_names();
  ASSERT_EQ(names, (std::vector<std::string>{"wings", "centre"}));
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const auto text = builtin_playbook_text(name);
    ASSERT_TRUE(text.has_value());
    const Playbook book = parsed(*text);
    EXPECT_EQ(book.name, name);
    std::set<PlayRestart> restarts;
    std::set<std::uint32_t> robots;
    bool retreat = false;
    bool shot = false;
    for (const Play& play : book.plays) {
      restarts.insert(play.restart);
      retreat = retreat || play.name == "retreat";
      for (const PlayStep& step : play.steps) {
        shot = shot || step.shot;
        for (const PlayTarget& target : step.targets) robots.insert(target.robot_id);
      }
    }
    EXPECT_EQ(restarts.size(), 3u) << "plays after kick-offs, after free kicks and in open play";
    EXPECT_TRUE(retreat);
    EXPECT_TRUE(shot);
    EXPECT_EQ(robots.size(), 10u) << "every field player of Division A has a part";
  }
  EXPECT_FALSE(builtin_playbook_text("no such playbook").has_value());
}

TEST(Playbook, LoadingAFileReadsItAndAMissingFileIsNamed) {
  const testing::ScratchDir dir;
  const auto path = (dir.path() / "mine.txt").string();
  std::ofstream(path) << "play a\n  step 1 ball 2\n    2 0.5 0.5\n";
  const auto book = load_playbook(path);
  ASSERT_TRUE(book) << book.error().message;
  EXPECT_EQ(book->plays.at(0).steps.at(0).ball_robot, 2u);
  std::ofstream(path) << "play a\n  step 1 ball 2\n    2 0.5 5\n";
  const auto bad = load_playbook(path);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message.rfind(path + ":3: robot 2 at 0.5 5: off the field", 0), 0u)
      << bad.error().message;
  const auto missing = load_playbook((dir.path() / "none.txt").string());
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("none.txt: cannot open the playbook"), std::string::npos);
}

}  // namespace
}  // namespace ssl_formation::simulation
