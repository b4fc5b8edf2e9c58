// ssl-trainer --from-log on logs with the game controller's referee messages, as real match logs
// hold them: the opponent found by name and side through a change of colours, and learning only
// in running play. The trainer runs as a process on real files; the reference is the same
// trainer on the same robots given explicitly, or the same log learned in every state.

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "child_process.hpp"
#include "match_logs.hpp"
#include "motion_table_sums.hpp"
#include "moving_robots.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;

testing::RunResult train(const TempDir& dir, const std::filesystem::path& log,
                         const std::filesystem::path& table, std::vector<std::string> options,
                         const std::string& name) {
  std::vector<std::string> args{"--from-log", log.string(), "--table", table.string()};
  args.insert(args.end(), options.begin(), options.end());
  return testing::run_to_end(trainer_program, std::move(args), dir.path(), name, 60s);
}

std::vector<RobotDetection> team(double t, int first_index, bool mirrored) {
  std::vector<RobotDetection> robots;
  for (int i = 0; i < 6; ++i) {
    Point p = testing::moving_robot_position(3, first_index + i, t);
    if (mirrored) p = Point{-p.x, -p.y};
    robots.push_back({static_cast<std::uint32_t>(i), p});
  }
  return robots;
}

TEST(MatchTraining, RefereeNamesAndSidesTrainWhatTheSameRobotsGivenExplicitlyTrain) {
  TempDir dir;
  // 40 s a half, 10 s of half time without vision between. The scouted team plays blue
  // attacking +x in the first half, yellow attacking -x in the second (its robots' feed
  // positions turned about the centre); the other team is a decoy moving elsewhere.
  const auto half = [](double t) { return t < 40.0 ? 1 : t < 50.0 ? 0 : 2; };
  testing::MatchScript with_referee;
  with_referee.seconds = 90.0;
  with_referee.frame = [&](double t) -> std::optional<DetectionFrameSpec> {
    if (half(t) == 0) return std::nullopt;
    DetectionFrameSpec frame;
    const bool first = half(t) == 1;
    (first ? frame.blue : frame.yellow) = team(t, 0, !first);
    (first ? frame.yellow : frame.blue) = team(t, 6, false);
    return frame;
  };
  with_referee.referee = [&](double t) -> std::optional<testing::RefereeSpec> {
    testing::RefereeSpec spec;
    // blue's goal on -x all match: blue attacks +x, yellow -x.
    spec.blue_on_positive_half = false;
    if (half(t) == 1) {
      spec.yellow = "Decoy FC";
      spec.blue = "Scouted Team";
    } else {
      // The game controller's spelling may differ from the option's in case and spaces.
      spec.yellow = " scouted TEAM";
      spec.blue = "Decoy FC";
      spec.command = half(t) == 0 ? Referee::HALT : Referee::NORMAL_START;
      spec.command_counter = half(t) == 0 ? 2 : 3;
      spec.stage = half(t) == 0 ? Referee::NORMAL_HALF_TIME : Referee::NORMAL_SECOND_HALF;
    }
    return spec;
  };
  // The same robots pre-normalised: the scouted team yellow attacking +x all match, no referee.
  testing::MatchScript explicit_script;
  explicit_script.seconds = 90.0;
  explicit_script.frame = [&](double t) -> std::optional<DetectionFrameSpec> {
    if (half(t) == 0) return std::nullopt;
    DetectionFrameSpec frame;
    frame.yellow = team(t, 0, false);
    frame.blue = team(t, 6, false);
    return frame;
  };
  ASSERT_EQ(testing::write_match_log(dir / "referee.log", with_referee), "");
  ASSERT_EQ(testing::write_match_log(dir / "explicit.log", explicit_script), "");

  const auto by_name = train(dir, dir / "referee.log", dir / "by-name.table",
                             {"--opponent-team", "Scouted Team"}, "by-name");
  ASSERT_EQ(by_name.exit_code, 0) << by_name.err;
  const auto given = train(dir, dir / "explicit.log", dir / "given.table",
                           {"--opponent-color", "yellow", "--opponent-attacks", "+x"}, "given");
  ASSERT_EQ(given.exit_code, 0) << given.err;
  // The log line says who the opponent ended up as, and why.
  EXPECT_NE(by_name.err.find("opponent ' scouted TEAM' yellow (referee), attacks -x (referee)"),
            std::string::npos)
      << by_name.err;

  const auto a = load_table(dir / "by-name.table", Grid(3, 2));
  const auto b = load_table(dir / "given.table", Grid(3, 2));
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(b) << b.error().message;
  ASSERT_TRUE(a->motion && b->motion);
  EXPECT_GT(b->motion->instances(), 3000u);
  EXPECT_GT(b->table.transitions(), 10000u);
  EXPECT_EQ(testing::table_entries(a->table), testing::table_entries(b->table));
  EXPECT_EQ(a->metadata.samples, b->metadata.samples);
  EXPECT_TRUE(*a->motion == *b->motion);

  // Without the name, the referee's sides still apply but the colour stays the default yellow:
  // the decoy is learned in the first half, and the table differs.
  const auto unnamed = train(dir, dir / "referee.log", dir / "unnamed.table", {}, "unnamed");
  ASSERT_EQ(unnamed.exit_code, 0) << unnamed.err;
  const auto c = load_table(dir / "unnamed.table", Grid(3, 2));
  ASSERT_TRUE(c && c->motion);
  EXPECT_NE(testing::table_entries(c->table), testing::table_entries(b->table));
}

// Robot i's position: circling in its own half in running play, about a spot near the other
// goal while the game is stopped (somewhere running play never goes).
Point robot_position(int i, double t, bool running) {
  const double angle = 0.9 * t + 1.1 * i;
  const Point centre = running ? Point{-2600.0 + 250.0 * (i % 3), -2000.0 + 800.0 * i}
                               : Point{3750.0, -2000.0 + 800.0 * i};
  const double radius = running ? 500.0 : 150.0;
  return {centre.x + radius * std::cos(angle), centre.y + radius * std::sin(angle)};
}

TEST(MatchTraining, NothingIsLearnedDuringStopHaltOrBallPlacement) {
  TempDir dir;
  // The commands of 80 s of a match, with the game controller's command counter.
  struct Stretch {
    double until_s;
    Referee::Command command;
  };
  const std::vector<Stretch> stretches{
      {20.0, Referee::NORMAL_START}, {30.0, Referee::STOP}, {35.0, Referee::BALL_PLACEMENT_BLUE},
      {55.0, Referee::NORMAL_START}, {60.0, Referee::HALT}, {80.0, Referee::FORCE_START}};
  const auto stretch_at = [&](double t) {
    std::size_t i = 0;
    while (i + 1 < stretches.size() && t >= stretches[i].until_s) ++i;
    return i;
  };
  const auto running = [&](double t) {
    const Referee::Command c = stretches[stretch_at(t)].command;
    return c == Referee::NORMAL_START || c == Referee::FORCE_START;
  };
  testing::MatchScript script;
  script.seconds = 80.0;
  script.frame = [&](double t) -> std::optional<DetectionFrameSpec> {
    DetectionFrameSpec frame;
    for (int i = 0; i < 6; ++i) {
      frame.yellow.push_back({static_cast<std::uint32_t>(i), robot_position(i, t, running(t))});
    }
    return frame;
  };
  script.referee = [&](double t) -> std::optional<testing::RefereeSpec> {
    testing::RefereeSpec spec;
    spec.command = stretches[stretch_at(t)].command;
    spec.command_counter = static_cast<std::uint32_t>(stretch_at(t) + 1);
    spec.yellow = "Them";
    spec.blue = "Us";
    return spec;
  };
  ASSERT_EQ(testing::write_match_log(dir / "match.log", script), "");

  const auto in_play = train(dir, dir / "match.log", dir / "running.table",
                             {"--our-team", "us", "--learn-during", "running"}, "running");
  ASSERT_EQ(in_play.exit_code, 0) << in_play.err;
  const auto everything = train(dir, dir / "match.log", dir / "all.table",
                                {"--our-team", "us", "--learn-during", "all"}, "all");
  ASSERT_EQ(everything.exit_code, 0) << everything.err;

  // The stopped robots' cells: the 3x2 grid's third column, and the motion model's 0.5 m cells
  // about the spot they circle; running play never reaches either.
  std::set<int> stopped_cells;
  for (double t = 0.0; t < 80.0; t += 0.05) {
    for (int i = 0; i < 6; ++i) {
      stopped_cells.insert(MotionFeatures::cell(robot_position(i, t, false)));
      ASSERT_EQ(stopped_cells.count(MotionFeatures::cell(robot_position(i, t, true))), 0u);
    }
  }
  const StateCodec codec(Grid(3, 2));
  struct Counted {
    std::uint64_t transitions = 0;
    std::uint64_t stopped_transitions = 0;
    std::uint64_t stopped_rows = 0;
  };
  const auto count = [&](const std::filesystem::path& path) {
    const auto loaded = load_table(path, Grid(3, 2));
    EXPECT_TRUE(loaded && loaded->motion) << path;
    Counted counted;
    if (!loaded || !loaded->motion) return counted;
    loaded->table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count n) {
      counted.transitions += n;
      if (codec.decode(from).position.x == 2 || codec.decode(to).position.x == 2) {
        counted.stopped_transitions += n;
      }
    });
    for (const auto& [key, row] : loaded->motion->sorted_rows()) {
      const MotionKeyParts parts = decode_motion_key(key);
      if (parts.level == MotionLevel::robot && stopped_cells.count(parts.cell)) {
        ++counted.stopped_rows;
      }
    }
    return counted;
  };
  const Counted running_only = count(dir / "running.table");
  const Counted all_states = count(dir / "all.table");
  // Learned in every state, the stops are in the tables; in running play only, not at all, not
  // even the transition from the last instant of play into a stop.
  EXPECT_GT(all_states.stopped_transitions, 1000u);
  EXPECT_GT(all_states.stopped_rows, 10u);
  EXPECT_EQ(running_only.stopped_transitions, 0u);
  EXPECT_EQ(running_only.stopped_rows, 0u);
  // Running play itself is learned: 60 of the 80 s.
  EXPECT_GT(running_only.transitions, all_states.transitions / 2);
  // The log line says how much was set aside: 20 of the 80 s, about 1200 formations.
  const std::size_t at = in_play.err.find(" outside running play)");
  ASSERT_NE(at, std::string::npos) << in_play.err;
  const std::size_t open = in_play.err.rfind('(', at);
  EXPECT_NEAR(std::stod(in_play.err.substr(open + 1, at - open - 1)), 1200.0, 20.0) << in_play.err;
}

// 30 s of a match between two named teams, blue's goal on the +x side (yellow attacks +x): each
// team's robots move as testing::moving_robot_position's (yellow from index `yellow_index`, blue
// from `blue_index`, turned about the centre, since blue attacks -x).
std::string write_named_match(const std::filesystem::path& path, const std::string& yellow,
                              int yellow_index, const std::string& blue, int blue_index) {
  testing::MatchScript script;
  script.seconds = 30.0;
  script.frame = [=](double t) -> std::optional<DetectionFrameSpec> {
    DetectionFrameSpec frame;
    frame.yellow = team(t, yellow_index, false);
    frame.blue = team(t, blue_index, true);
    return frame;
  };
  script.referee = [=](double) -> std::optional<testing::RefereeSpec> {
    testing::RefereeSpec spec;
    spec.yellow = yellow;
    spec.blue = blue;
    spec.blue_on_positive_half = true;
    return spec;
  };
  return testing::write_match_log(path, script);
}

TEST(MatchTraining, ScoutingLearnsTheNamedTeamFromEveryLogItPlaysInOnEveryCore) {
  TempDir dir;
  // The scouted team plays yellow in one log and blue in another (moving the same way, as its
  // own team); a third log is of two other teams.
  ASSERT_EQ(write_named_match(dir / "1.log", "Scouted", 0, "Alpha", 6), "");
  ASSERT_EQ(write_named_match(dir / "2.log", "Beta", 6, "SCOUTED", 0), "");
  ASSERT_EQ(write_named_match(dir / "3.log", "Gamma", 0, "Delta", 6), "");
  const std::vector<std::string> logs{(dir / "1.log").string(), (dir / "2.log").string(),
                                      (dir / "3.log").string()};
  const auto scout = [&](const std::string& table_dir, std::vector<std::string> options,
                         const std::string& name) {
    std::vector<std::string> args{"--from-log"};
    args.insert(args.end(), logs.begin(), logs.end());
    args.insert(args.end(), {"--table-dir", (dir / table_dir).string()});
    args.insert(args.end(), options.begin(), options.end());
    return testing::run_to_end(trainer_program, std::move(args), dir.path(), name, 60s);
  };
  const auto both_cores = scout("two", {"--opponent-team", "scouted", "--jobs", "2"}, "two");
  ASSERT_EQ(both_cores.exit_code, 0) << both_cores.err;
  EXPECT_NE(both_cores.err.find("3.log: skipped, the referee names neither team the opponent "
                                "'scouted' (yellow 'Gamma', blue 'Delta')"),
            std::string::npos)
      << both_cores.err;
  EXPECT_NE(both_cores.err.find("opponent 'Scouted' yellow (referee), attacks +x (referee)"),
            std::string::npos)
      << both_cores.err;
  EXPECT_NE(both_cores.err.find("opponent 'SCOUTED' blue (referee), attacks -x (referee)"),
            std::string::npos)
      << both_cores.err;
  const auto one_core = scout("one", {"--opponent-team", "Scouted", "--jobs", "1"}, "one");
  ASSERT_EQ(one_core.exit_code, 0) << one_core.err;
  const auto every_team = scout("all", {"--opponent-team", "all"}, "all");
  ASSERT_EQ(every_team.exit_code, 0) << every_team.err;

  // The team's table: one file, the same on one core or two and among every team's.
  const auto two = load_table(dir / "two" / "scouted.bin", Grid(3, 2));
  const auto one = load_table(dir / "one" / "scouted.bin", Grid(3, 2));
  const auto all = load_table(dir / "all" / "scouted.bin", Grid(3, 2));
  ASSERT_TRUE(two && one && all);
  // One table (beside the trainer's lock file).
  EXPECT_EQ(std::count_if(std::filesystem::directory_iterator(dir / "two"),
                          std::filesystem::directory_iterator(),
                          [](const auto& entry) { return entry.path().extension() == ".bin"; }),
            1);
  EXPECT_EQ(testing::table_entries(two->table), testing::table_entries(one->table));
  EXPECT_TRUE(*two->motion == *one->motion);
  EXPECT_EQ(testing::table_entries(two->table), testing::table_entries(all->table));
  EXPECT_TRUE(*two->motion == *all->motion);
  // Both logs it played in, and nothing of the others: as training each log alone with the team
  // given by colour and side, then merging.
  const auto alone = [&](const std::string& log, const std::string& color,
                         const std::string& attacks, const std::string& table) {
    const auto run = train(dir, dir / log, dir / table,
                           {"--opponent-color", color, "--opponent-attacks", attacks}, table);
    EXPECT_EQ(run.exit_code, 0) << run.err;
  };
  alone("1.log", "yellow", "+x", "1.bin");
  alone("2.log", "blue", "-x", "2.bin");
  const auto merged =
      testing::run_to_end(trainer_program,
                          {"merge", (dir / "1.bin").string(), (dir / "2.bin").string(), "-o",
                           (dir / "merged.bin").string()},
                          dir.path(), "merge", 60s);
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  const auto reference = load_table(dir / "merged.bin", Grid(3, 2));
  ASSERT_TRUE(reference && reference->motion);
  EXPECT_EQ(testing::table_entries(two->table), testing::table_entries(reference->table));
  // Both saved tables pruned, each on its own evidence: the same at every level a pruning keeps
  // exactly.
  EXPECT_TRUE(testing::same_coarse_evidence(*two->motion, *reference->motion));
  EXPECT_EQ(two->metadata.samples, reference->metadata.samples);
  // Every named team of every log has its table.
  for (const char* team : {"alpha.bin", "beta.bin", "gamma.bin", "delta.bin"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "all" / team)) << team << every_team.err;
  }
}

TEST(MatchTraining, ScoutingKeepsATeamThatWasNamedAndThenNotInTheSameLog) {
  TempDir dir;
  // A day's recording: the scouted team's match for 15 s, then two other teams'.
  testing::MatchScript script;
  script.seconds = 30.0;
  script.frame = [](double t) -> std::optional<DetectionFrameSpec> {
    DetectionFrameSpec frame;
    frame.yellow = team(t, 0, false);
    frame.blue = team(t, 6, true);
    return frame;
  };
  script.referee = [](double t) -> std::optional<testing::RefereeSpec> {
    testing::RefereeSpec spec;
    spec.yellow = t < 15.0 ? "Scouted" : "Gamma";
    spec.blue = t < 15.0 ? "Alpha" : "Delta";
    spec.command_counter = t < 15.0 ? 1 : 2;
    spec.blue_on_positive_half = true;
    return spec;
  };
  ASSERT_EQ(testing::write_match_log(dir / "day.log", script), "");
  const auto run = testing::run_to_end(trainer_program,
                                       {"--from-log", (dir / "day.log").string(), "--opponent-team",
                                        "scouted", "--table-dir", (dir / "tables").string()},
                                       dir.path(), "day", 60s);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("the opponent was found, then no longer named"), std::string::npos)
      << run.err;
  const auto table = load_table(dir / "tables" / "scouted.bin", Grid(3, 2));
  ASSERT_TRUE(table && table->motion) << run.err;
  // About 15 s of play: learned, and nothing after the teams changed.
  EXPECT_GT(table->table.transitions(), 3000u);
  const auto half = train(dir, dir / "day.log", dir / "all.bin",
                          {"--opponent-color", "yellow", "--opponent-attacks", "+x"}, "all");
  ASSERT_EQ(half.exit_code, 0) << half.err;
  const auto whole = load_table(dir / "all.bin", Grid(3, 2));
  ASSERT_TRUE(whole);
  EXPECT_LT(table->table.transitions(), whole->table.transitions() * 6 / 10);
  EXPECT_GT(table->table.transitions(), whole->table.transitions() * 4 / 10);
}

}  // namespace
}  // namespace ssl_formation
