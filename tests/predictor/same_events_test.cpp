// One seam for match input: the same events give the same predictions, byte for byte, whoever
// carries them. A recorded match with its referee goes through ssl-predictor --from-log (the
// log read as it streams), a match kept in memory, the daemon driven in-process as the network
// would feed it, and the evaluation; every one of them writes the same CSV and multicasts the
// same datagrams.

#include <gtest/gtest.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <fstream>
#include <sstream>

#include "match_logs.hpp"
#include "moving_robots.hpp"
#include "recorded_output.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/evaluation/position_evaluation.hpp"
#include "ssl_formation/files/log_events.hpp"
#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/prediction_csv.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/predictor/predictor_daemon.hpp"
#include "ssl_formation/predictor/predictor_options.hpp"

namespace ssl_formation::predictor {
namespace {

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// 40 s of a match: blue (the opponent) moving, yellow standing; the referee stops the game for
// 5 s, places the ball for 5, restarts with a free kick and lets play run.
testing::MatchScript script() {
  testing::MatchScript match;
  match.seconds = 40.0;
  match.frame = [](double t) -> std::optional<DetectionFrameSpec> {
    DetectionFrameSpec spec;
    for (int i = 0; i < 6; ++i) {
      spec.yellow.push_back({static_cast<std::uint32_t>(i), Point{-3000.0, -2500.0 + 1000.0 * i}});
      spec.blue.push_back({static_cast<std::uint32_t>(i), testing::moving_robot_position(3, i, t)});
    }
    return spec;
  };
  match.referee = [](double t) -> std::optional<testing::RefereeSpec> {
    testing::RefereeSpec spec;
    spec.yellow = "Us";
    spec.blue = "Them";
    spec.blue_on_positive_half = false;
    spec.command = t < 10.0   ? Referee::NORMAL_START
                   : t < 15.0 ? Referee::STOP
                   : t < 20.0 ? Referee::BALL_PLACEMENT_BLUE
                              : Referee::DIRECT_FREE_BLUE;
    spec.command_counter = t < 10.0 ? 1 : t < 15.0 ? 2 : t < 20.0 ? 3 : 4;
    return spec;
  };
  return match;
}

TEST(SameEvents, FromLogMemoryTheDaemonAndTheEvaluationPredictTheSame) {
  testing::ScratchDir dir;
  const auto log = dir.path() / "match.log";
  ASSERT_EQ(testing::write_match_log(log, script()), "");
  Result<RecordedLog> recorded = read_recorded_log(log);
  ASSERT_TRUE(recorded) << recorded.error().message;
  const RecordedMatch& match = recorded->match;
  ASSERT_TRUE(match.has_referee());

  PredictorOptions options;
  options.model.our_team = "Us";
  options.table = (dir.path() / "t.bin").string();
  options.from_logs = {log.string()};
  options.output = (dir.path() / "from-log.csv").string();
  options.horizon = 3;
  const PredictionConfig config = prediction_config(options);
  {
    // A table of the first half, as the trainer would learn it.
    TrainingConfig training_config;
    training_config.sampler = config.sampler;
    training_config.rules = MatchRules{*config.opponent, LearnDuring::all};
    ModelSettings settings;
    settings.step_s = config.sampler.step_s;
    Training training(training_config, config.model, make_learner(config.model, settings));
    match.split(0.5).first.replay(training);
    // Saved as the trainer saves it, within the default budget (the evaluation scores that).
    StoredTable stored = training.stored_table();
    auto fit = fit_table_to_budget(stored.table, stored.metadata, *stored.motion, TableBudget{});
    ASSERT_TRUE(fit) << fit.error().message;
    stored.motion = std::make_shared<const MotionTable>(std::move(fit->pruned.table));
    ASSERT_TRUE(save_table(options.table, stored));
  }
  const auto table =
      std::make_shared<const StoredTable>(*load_table(options.table, config.sampler.grid));

  // ssl-predictor --from-log.
  ASSERT_EQ(run_from_log(options), 0);
  const std::string from_log = read(options.output);

  // The match in memory through a PredictionPipeline.
  std::string in_memory(prediction_csv_header());
  std::vector<std::string> encoded;
  {
    PredictionPipeline pipeline(config, [&](const PredictedFormation& p) {
      append_prediction_csv(p, in_memory);
      encode_prediction(p.formation(), p.prediction, p.context, encoded.emplace_back());
    });
    pipeline.set_table(table);
    match.replay(pipeline);
  }
  EXPECT_GT(encoded.size(), 2000u);
  EXPECT_EQ(in_memory, from_log);
  // The referee was followed: the messages say the game state they were made in.
  EXPECT_TRUE(std::any_of(encoded.begin(), encoded.end(), [](const std::string& bytes) {
    return bytes.find("ball_placement") != std::string::npos;
  }));

  // The daemon, fed the events as its sockets would hand them on.
  {
    boost::asio::io_context io;
    app::ManualClock clock;
    testing::RecordedOutput output;
    PredictorDaemon daemon(io, options, config, clock, output);
    daemon.start();
    match.replay(daemon);
    EXPECT_EQ(output.datagrams, encoded);
  }

  // The evaluation, testing on the same match.
  std::string evaluated(prediction_csv_header());
  evaluation::PositionEvaluationConfig evaluation;
  evaluation.sampler = config.sampler;
  evaluation.model = config.model;
  evaluation.steps = config.horizon;
  evaluation.rules = MatchRules{*config.opponent, LearnDuring::all};
  evaluation.on_model_prediction = [&](const PredictedFormation& p) {
    append_prediction_csv(p, evaluated);
  };
  const auto [train, test] = match.split(0.5);
  (void)evaluation::evaluate_positions(evaluation, {train}, {match});
  // The evaluation trains its own table of the same half and prunes it as the trainer saves it:
  // the same counts, the same predictions. (A plain comparison: gtest's diff of two megabytes
  // of CSV takes minutes.)
  EXPECT_TRUE(evaluated == from_log) << "the evaluation's CSV differs from ssl-predictor's";
}

}  // namespace
}  // namespace ssl_formation::predictor
