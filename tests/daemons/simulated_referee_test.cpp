// ssl-producer's game controller, as processes on real files and loopback: the referee messages
// it writes into a log let ssl-trainer find the opponent by name and follow it through the
// change of ends, learning in running play only; sent live, they let ssl-predictor do the same
// while it predicts.

#include <gtest/gtest.h>

#include <map>

#include "child_process.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

// The simulated match of these tests: the opponent 'Away' plays blue and attacks -x in the
// first half, halves of 60 s of data time (30 formations).
std::vector<std::string> match_options(const std::string& seed) {
  return {"--seed",           seed,   "--our-team",         "Home", "--opponent-team", "Away",
          "--opponent-color", "blue", "--opponent-attacks", "-x",   "--half-length",   "60",
          "--cameras",        "2"};
}

void write_log(const TempDir& dir, const std::string& name, std::vector<std::string> options) {
  options.insert(options.begin(),
                 {"--simulation", "paper", "--write-log", (dir / name).string(), "--count", "400"});
  const auto written = testing::run_to_end(producer_program, options, dir.path(), "write-" + name);
  ASSERT_EQ(written.exit_code, 0) << written.err;
}

TransitionTable train(const TempDir& dir, const std::string& log, const std::string& table,
                      std::vector<std::string> options, std::string* err = nullptr) {
  options.insert(options.begin(), {"--from-log", (dir / log).string(), "--table",
                                   (dir / table).string(), "--model", "paper"});
  const auto trained = testing::run_to_end(trainer_program, options, dir.path(), "train-" + table);
  EXPECT_EQ(trained.exit_code, 0) << trained.err;
  if (err) *err = trained.err;
  auto loaded = load_table(dir / table, Grid(3, 2));
  EXPECT_TRUE(loaded) << loaded.error().message;
  return loaded ? std::move(loaded->table) : TransitionTable(Grid(3, 2));
}

TEST(SimulatedReferee, AWrittenMatchTrainsTheNamedOpponentThroughTheChangeOfEndsInRunningPlay) {
  TempDir dir;
  std::vector<std::string> refereed = match_options("3");
  write_log(dir, "match.log", refereed);
  std::vector<std::string> vision_only = refereed;
  vision_only.insert(vision_only.end(), {"--referee", "off"});
  write_log(dir, "vision.log", vision_only);

  // One referee message before each formation's vision, every one of them a valid message
  // naming both teams; the ends change at each half time.
  auto reader = LogReader::open(dir / "match.log");
  ASSERT_TRUE(reader) << reader.error().message;
  RefereeFollower follower;
  LogMessage message;
  int referee_messages = 0;
  int changes_of_ends = 0;
  while (reader->next(message)) {
    if (message.type != static_cast<std::int32_t>(LogMessageType::referee)) continue;
    ++referee_messages;
    const RefereeChange change = follower.add(message.payload, message.receive_time_ns * 1e-9);
    if (change.sides && referee_messages > 1) ++changes_of_ends;
    ASSERT_EQ(follower.view().blue_name, "Away");
    ASSERT_EQ(follower.view().yellow_name, "Home");
  }
  ASSERT_TRUE(reader->error().empty()) << reader->error();
  EXPECT_EQ(referee_messages, 400);
  EXPECT_EQ(follower.counters().undecodable + follower.counters().unknown_command, 0u);
  // 800 s of matches of two 60 s halves and 20 s breaks: a change of ends at each half time
  // and each new match, nine or so.
  EXPECT_GE(changes_of_ends, 8);

  // Found by name, followed through every change of ends; what is counted outside running play.
  std::string err;
  const TransitionTable refereed_table =
      train(dir, "match.log", "refereed.bin",
            {"--opponent-team", " away ", "--learn-during", "running"}, &err);
  EXPECT_NE(err.find("opponent 'Away' blue (referee), attacks "), std::string::npos) << err;
  EXPECT_NE(err.find("; 0 changes of colour, " + std::to_string(changes_of_ends) +
                     " changes of ends; 400 formations ("),
            std::string::npos)
      << err;

  // The same formations without a referee, the opponent given, everything learned. Each state
  // the refereed training moved a robot into, it moved it into there too, as often or more: the
  // refereed training counts part of the same moves (a robot's state after a move is its cell
  // now and before, whichever chain it is in). Had a half been read from the wrong end, its
  // mirrored states would be counted too often.
  const TransitionTable everything =
      train(dir, "vision.log", "everything.bin",
            {"--opponent-color", "blue", "--opponent-attacks", "-x", "--learn-during", "all"});
  std::map<StateIndex, std::uint64_t> into_everything;
  std::map<StateIndex, std::uint64_t> into_refereed;
  for (const auto& [from, to, count] : testing::table_entries(everything)) {
    into_everything[to] += count;
  }
  for (const auto& [from, to, count] : testing::table_entries(refereed_table)) {
    into_refereed[to] += count;
  }
  for (const auto& [to, count] : into_refereed) {
    EXPECT_LE(count, into_everything[to]) << "moves into state " << to;
  }
  // Kick-offs, stoppages and the half-time breaks (20 s after each 60 s half) are left out, and
  // the first move under each new command: 40% of the match or so.
  EXPECT_LT(refereed_table.transitions(), everything.transitions() * 80 / 100);
  EXPECT_GT(refereed_table.transitions(), everything.transitions() * 45 / 100);
}

TEST(SimulatedReferee, ThePredictorFollowsTheLiveSimulationsRefereeThroughHalfTime) {
  TempDir dir;
  write_log(dir, "train.log", match_options("4"));
  train(dir, "train.log", "t.bin", {"--our-team", "Home"});

  const std::string vision = new_group();
  const std::string referee = new_group();
  const std::string predictions = new_group();
  ChildProcess predictor(
      predictor_program,
      {"--vision-address", vision, "--referee-address", referee, "--prediction-address",
       predictions, "--table", (dir / "t.bin").string(), "--model", "paper", "--our-team", "home",
       "--quiet", "--status-interval", "0.2"},
      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  testing::PredictionListener listener(predictions);
  std::vector<std::string> live = match_options("5");
  live.insert(live.end(),
              {"--simulation", "paper", "--vision-address", vision, "--referee-address", referee,
               "--count", "100", "--period", "0.02", "--status-interval", "100"});
  const auto produced = testing::run_to_end(producer_program, live, dir.path(), "producer");
  ASSERT_EQ(produced.exit_code, 0) << produced.err;
  EXPECT_EQ(testing::last_status(produced.err, "done:").at("referee_sent"), 100u) << produced.err;

  const auto messages = listener.drain(5s);
  ASSERT_TRUE(messages.has_value());
  // 100 formations: a first half, half time, a second half and the next match's start.
  ASSERT_GT(messages->size(), 90u) << predictor.stderr_text();
  std::map<std::string, int> states;
  int running = 0;
  int keeper_at_own_goal = 0;
  int keeper_on_plus_x = 0;
  int keeper_on_minus_x = 0;
  for (const auto& prediction : *messages) {
    ASSERT_EQ(prediction.opponent_color(), "blue");
    ++states[prediction.game_state()];
    const auto state = parse_game_state(prediction.game_state());
    ASSERT_TRUE(state.has_value()) << prediction.game_state();
    // Around a change of command the two sockets may hand over vision before the referee's
    // message; running play is away from the changes of ends.
    if (!is_running_play(*state)) continue;
    for (const auto& robot : prediction.robots()) {
      if (robot.robot_id() != 0) continue;
      ++running;
      // Column 0 is the opponent's own goal side, whichever end it defends in the feed.
      if (robot.position_cell().x() == 0) ++keeper_at_own_goal;
      (robot.position().x() > 0 ? keeper_on_plus_x : keeper_on_minus_x) += 1;
    }
  }
  EXPECT_GT(states["running"] + states["free_kick"], 50) << predictor.stderr_text();
  EXPECT_GT(states["kickoff_preparation"] + states["stop"] + states["halt"], 5);
  // The keeper keeps its goal in the plays (90% of formations), and stands anywhere in the
  // random ones: read from the wrong end, half the match would put it in column 2.
  EXPECT_GT(keeper_at_own_goal, running * 85 / 100) << keeper_at_own_goal << " of " << running;
  EXPECT_GT(keeper_on_plus_x, running / 4) << "the first half: its goal on +x";
  EXPECT_GT(keeper_on_minus_x, running / 4) << "the second half: its goal on -x";
  const std::string log = predictor.stderr_text();
  EXPECT_NE(log.find("opponent: 'Away' blue (referee), attacks -x (referee)"), std::string::npos)
      << log;
  EXPECT_NE(log.find("opponent: 'Away' blue (referee), attacks +x (referee)"), std::string::npos)
      << log;
}

TEST(SimulatedReferee, TheGameControllersOptionsShowTheirDefaultsAndBadOnesAreUsageErrors) {
  TempDir dir;
  const auto help = testing::run_to_end(producer_program, {"--help"}, dir.path(), "help");
  EXPECT_EQ(help.exit_code, 0);
  for (const std::string option :
       {"--referee arg (=on)", "--our-team arg (=ssl-formation)",
        "--opponent-team arg (=Simulated Opponent)", "--half-length arg (=300)",
        "--referee-address arg (=224.5.23.1:10003)"}) {
    EXPECT_NE(help.out.find(option), std::string::npos) << "ssl-producer lacks " << option;
  }
  const std::string log = (dir / "x.log").string();
  for (const auto& [options, complaint] :
       std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--half-length", "0"}, "--half-length must be a positive number of seconds"},
           {{"--our-team", "Rival", "--opponent-team", " rival"}, "must differ"},
           {{"--opponent-team", "  "}, "must not be empty"},
           {{"--referee", "maybe"}, "referee"}}) {
    std::vector<std::string> args{"--write-log", log, "--count", "3"};
    args.insert(args.end(), options.begin(), options.end());
    const auto refused = testing::run_to_end(producer_program, args, dir.path(), "refused");
    EXPECT_EQ(refused.exit_code, 2) << refused.err;
    EXPECT_NE(refused.err.find(complaint), std::string::npos) << refused.err;
    EXPECT_FALSE(std::filesystem::exists(log)) << "nothing written for a usage error";
  }
}

}  // namespace
}  // namespace ssl_formation
