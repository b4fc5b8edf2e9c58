// ssl-predictor --from-log: logs through the same pipeline as the daemon, predictions as CSV.
// The main check: the daemon, fed the same log by ssl-producer --replay, multicasts exactly the
// predictions --from-log writes, line for line and number for number. These logs are the simulated
// producer's (formations jumping every 2 s, the paper's scenario), so the trainer and the
// predictor run --model paper; motion_daemons_test.cpp does the same for the default motion model
// on a log of moving robots.

#include <gtest/gtest.h>
#include <signal.h>

#include <set>

#include "child_process.hpp"
#include "pipeline_support.hpp"
#include "prediction_rows.hpp"

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

using testing::read_text;
using testing::rows_of;
using testing::split;

class PredictFromLog : public ::testing::Test {
 protected:
  void SetUp() override {
    // Two cameras with overlap and noise, geometry inside: training on one seed, testing on
    // another, as a team would with two recorded matches.
    for (const auto& [name, seed, count] :
         {std::tuple{"train.log.gz", "1", "400"}, std::tuple{"test.log", "9", "60"}}) {
      const auto written = testing::run_to_end(
          producer_program,
          {"--simulation", "paper", "--referee", "off", "--write-log", (dir / name).string(),
           "--count", count, "--seed", seed, "--cameras", "2", "--jitter-mm", "10"},
          dir.path(), std::string("write-") + name, 30s);
      ASSERT_EQ(written.exit_code, 0) << written.err;
    }
    const auto trained = testing::run_to_end(trainer_program,
                                             {"--from-log", (dir / "train.log.gz").string(),
                                              "--table", table.string(), "--model", "paper"},
                                             dir.path(), "train", 30s);
    ASSERT_EQ(trained.exit_code, 0) << trained.err;
  }

  // `ssl-predictor ARGS --model paper` run to its end.
  testing::RunResult predict(std::vector<std::string> args, const std::string& name) const {
    args.push_back("--model");
    args.push_back("paper");
    return testing::run_to_end(predictor_program, std::move(args), dir.path(), name);
  }

  TempDir dir;
  std::filesystem::path table = dir / "table.bin";
};

TEST_F(PredictFromLog, TheDaemonFedTheSameLogByReplayMulticastsExactlyTheCsv) {
  const auto csv_path = dir / "predictions.csv";
  const auto offline =
      testing::run_to_end(predictor_program,
                          {"--from-log", (dir / "test.log").string(), "--table", table.string(),
                           "--horizon", "3", "--output", csv_path.string(), "--model", "paper"},
                          dir.path(), "from-log", 30s);
  ASSERT_EQ(offline.exit_code, 0) << offline.err;
  std::vector<std::string> lines = split(read_text(csv_path), '\n');
  ASSERT_GT(lines.size(), 1u);
  EXPECT_EQ(lines.front(),
            "t_capture,frame,robot_id,step,horizon_s,state_index,predicted_cell_x,"
            "predicted_cell_y,predicted_x_mm,predicted_y_mm,probability,unseen,centroid_cell_x,"
            "centroid_cell_y,centroid_probability,formation_probability,confidence,model,"
            "predicted_feed_x_mm,predicted_feed_y_mm,radius_50_mm,radius_90_mm,grid,step_s");
  EXPECT_EQ(lines.front(), testing::prediction_csv_header);
  lines.erase(lines.begin());
  std::set<std::string> instants;
  for (const std::string& line : lines) {
    const std::vector<std::string> fields = split(line, ',');
    ASSERT_EQ(fields.size(), 24u) << line;
    instants.insert(fields.front());
    // The paper's model: its cell centre (columns 9-10) again, and no radii.
    EXPECT_EQ(fields[17], "paper") << line;
    EXPECT_EQ(fields[18], fields[8]) << line;
    EXPECT_EQ(fields[19], fields[9]) << line;
    EXPECT_EQ(fields[20], "0") << line;
    EXPECT_EQ(fields[21], "0") << line;
  }
  // 60 formations on two cameras: every one sampled and predicted, 3 steps of 6 robots each.
  ASSERT_EQ(instants.size(), 60u);
  EXPECT_EQ(lines.size(), 60u * 3u * 6u);

  const std::string vision = new_group();
  const std::string predictions = new_group();
  ChildProcess daemon(predictor_program,
                      {"--vision-address", vision, "--prediction-address", predictions, "--table",
                       table.string(), "--horizon", "3", "--quiet", "--model", "paper"},
                      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
  EXPECT_EQ(daemon.ready_fact("table_loaded"), "1");
  testing::PredictionListener listener(predictions);
  const auto replayed = testing::run_to_end(
      producer_program,
      {"--replay", (dir / "test.log").string(), "--vision-address", vision, "--speed", "50"},
      dir.path(), "replay", 30s);
  ASSERT_EQ(replayed.exit_code, 0) << replayed.err;
  const auto messages = listener.wait_for(instants.size(), 20s);
  ASSERT_EQ(messages.size(), instants.size()) << daemon.stderr_text();

  const std::vector<std::string> multicast = rows_of(messages);
  ASSERT_EQ(multicast.size(), lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) ASSERT_EQ(multicast[i], lines[i]) << "row " << i;

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(5s), 0) << daemon.stderr_text();
  // No prediction beyond those: the daemon stopped with exactly as many as the CSV holds.
  EXPECT_EQ(listener.wait_for(instants.size() + 1, 0ms).size(), instants.size());
}

TEST_F(PredictFromLog, WritesToStandardOutputAndKeepsEachFileItsOwnStream) {
  const auto one =
      predict({"--from-log", (dir / "test.log").string(), "--table", table.string()}, "stdout-one");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto twice = predict({"--from-log", (dir / "test.log").string(),
                              (dir / "test.log").string(), "--table", table.string()},
                             "stdout-twice");
  ASSERT_EQ(twice.exit_code, 0) << twice.err;
  // The second file starts a stream of its own, so its predictions are exactly the first's.
  const std::vector<std::string> single = split(one.out, '\n');
  const std::vector<std::string> both = split(twice.out, '\n');
  ASSERT_EQ(both.size(), 2 * single.size() - 1);  // one header
  for (std::size_t i = 1; i < single.size(); ++i) {
    ASSERT_EQ(both[i], single[i]);
    ASSERT_EQ(both[single.size() - 1 + i], single[i]);
  }
}

// The grid, the step and the model of a table need not be given again: the predictor takes them
// from the table and says so; given otherwise, the refusal names the option that fixes it.
TEST_F(PredictFromLog, TakesTheTablesGridStepAndModelUnlessTold) {
  const auto grid_table = dir / "g6x4.bin";
  const auto trained =
      testing::run_to_end(trainer_program,
                          {"--from-log", (dir / "train.log.gz").string(), "--table",
                           grid_table.string(), "--model", "paper", "--grid", "6x4"},
                          dir.path(), "train-6x4", 30s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  const auto taken = testing::run_to_end(
      predictor_program,
      {"--from-log", (dir / "test.log").string(), "--table", grid_table.string()}, dir.path(),
      "taken");
  EXPECT_EQ(taken.exit_code, 0) << taken.err;
  EXPECT_NE(taken.err.find("--grid 6x4, --model paper, --step 2 from the table"), std::string::npos)
      << taken.err;
  const auto told = predict(
      {"--from-log", (dir / "test.log").string(), "--table", grid_table.string(), "--grid", "3x2"},
      "told-otherwise");
  EXPECT_EQ(told.exit_code, 1);
  EXPECT_NE(told.err.find("give --grid 6x4"), std::string::npos) << told.err;
}

TEST_F(PredictFromLog, SaysWhatIsWrongAndUsesWhatItCan) {
  const auto no_table =
      predict({"--from-log", (dir / "test.log").string(), "--table", (dir / "none.bin").string()},
              "no-table");
  EXPECT_EQ(no_table.exit_code, 1);
  EXPECT_NE(no_table.err.find("none.bin"), std::string::npos) << no_table.err;
  EXPECT_EQ(no_table.out, "");

  const auto other_grid = predict(
      {"--from-log", (dir / "test.log").string(), "--table", table.string(), "--grid", "6x4"},
      "other-grid");
  EXPECT_EQ(other_grid.exit_code, 1);
  EXPECT_NE(other_grid.err.find("6x4"), std::string::npos) << other_grid.err;

  // A missing log among good ones: on standard output the good ones are predicted, and the exit
  // status says it.
  const auto partial = predict({"--from-log", (dir / "missing.log").string(),
                                (dir / "test.log").string(), "--table", table.string()},
                               "partial");
  EXPECT_EQ(partial.exit_code, 1);
  EXPECT_NE(partial.err.find("missing.log"), std::string::npos) << partial.err;
  EXPECT_EQ(split(partial.out, '\n').size(), 1u + 60u * 2u * 6u);
  // Into a file, a failed run leaves the file of an earlier run as it was: a missing log, and a
  // file that is not a log.
  const auto csv_path = dir / "good.csv";
  const auto good = predict({"--from-log", (dir / "test.log").string(), "--table", table.string(),
                             "-o", csv_path.string()},
                            "good");
  ASSERT_EQ(good.exit_code, 0) << good.err;
  const std::string good_csv = read_text(csv_path);
  ASSERT_EQ(split(good_csv, '\n').size(), 1u + 60u * 2u * 6u);
  for (const auto& input : {dir / "missing.log", table}) {
    const auto failed = predict({"--from-log", input.string(), "--table", table.string(), "-o",
                                 csv_path.string(), "--overwrite"},
                                "failed-into-file");
    EXPECT_EQ(failed.exit_code, 1) << failed.err;
    EXPECT_NE(failed.err.find("left as it was"), std::string::npos) << failed.err;
    EXPECT_EQ(read_text(csv_path), good_csv) << input;
  }
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << "left behind: " << entry;
  }

  const auto bad_horizon = predict(
      {"--from-log", (dir / "test.log").string(), "--table", table.string(), "--horizon", "0"},
      "bad-horizon");
  EXPECT_EQ(bad_horizon.exit_code, 2);

  // The paper's table (version 1) without --model: the paper's model, said once.
  const auto table_model = testing::run_to_end(
      predictor_program, {"--from-log", (dir / "test.log").string(), "--table", table.string()},
      dir.path(), "table-model");
  EXPECT_EQ(table_model.exit_code, 0) << table_model.err;
  EXPECT_NE(table_model.err.find("--model paper"), std::string::npos) << table_model.err;
  EXPECT_NE(table_model.out.find(",paper,"), std::string::npos);
  // Told --model motion: it says which model the table serves.
  const auto wrong_model = testing::run_to_end(
      predictor_program,
      {"--from-log", (dir / "test.log").string(), "--table", table.string(), "--model", "motion"},
      dir.path(), "wrong-model");
  EXPECT_EQ(wrong_model.exit_code, 1);
  EXPECT_NE(wrong_model.err.find("version-1"), std::string::npos) << wrong_model.err;
  EXPECT_NE(wrong_model.err.find("--model paper"), std::string::npos) << wrong_model.err;
  EXPECT_EQ(wrong_model.out, "");
}

// --model paper is the paper's protocol as it was: its sampling (auto: step) and --sampling step
// give the same table file (version 1) and the same predictions, byte for byte, as the code before
// rolling sampling made of the same log (tests/data/README.md; the CSV's first 17 columns, the 5
// appended since say "paper", the cell centre again and radii 0; the grid and step appended
// after those are checked apart).
TEST(StepSampling, ReproducesTheTableAndPredictionsOfBeforeByteForByte) {
  TempDir dir;
  const std::filesystem::path data = SSLF_TEST_DATA_DIR;
  const auto log = data / "step-golden.log.gz";
  for (const std::vector<std::string>& sampling :
       {std::vector<std::string>{"--model", "paper"},
        std::vector<std::string>{"--model", "paper", "--sampling", "step"}}) {
    SCOPED_TRACE(sampling.size() == 2 ? "--model paper" : "--model paper --sampling step");
    const auto table = dir / "table.bin";
    std::filesystem::remove(table);
    std::vector<std::string> train{"--from-log",   log.string(), "--table",
                                   table.string(), "--grid",     "6x4"};
    train.insert(train.end(), sampling.begin(), sampling.end());
    const auto trained = testing::run_to_end(trainer_program, train, dir.path(), "train", 30s);
    ASSERT_EQ(trained.exit_code, 0) << trained.err;
    EXPECT_EQ(read_text(table), read_text(data / "step-golden-6x4.bin"));

    std::vector<std::string> predict{"--from-log", log.string(),
                                     "--table",    (data / "step-golden-6x4.bin").string(),
                                     "--grid",     "6x4"};
    predict.insert(predict.end(), sampling.begin(), sampling.end());
    const auto predicted =
        testing::run_to_end(predictor_program, predict, dir.path(), "predict", 30s);
    ASSERT_EQ(predicted.exit_code, 0) << predicted.err;
    // The golden file is of before the grid and step_s columns: each line holds them at its
    // end, and is the golden line without them.
    std::string before_columns;
    for (const std::string& line : split(predicted.out, '\n')) {
      const std::size_t step_at = line.rfind(',');
      const std::size_t grid_at = line.rfind(',', step_at - 1);
      ASSERT_NE(grid_at, std::string::npos) << line;
      const std::string appended = line.substr(grid_at);
      EXPECT_TRUE(appended == ",grid,step_s" || appended == ",6x4,2") << line;
      before_columns += line.substr(0, grid_at) + '\n';
    }
    EXPECT_EQ(before_columns, read_text(data / "step-golden-6x4.csv"));
  }
  // The motion model learns from every frame: step sampling is a usage error for it (the
  // default model), in both programs, and writes nothing.
  for (const auto& program : {trainer_program, predictor_program}) {
    const auto refused = testing::run_to_end(program,
                                             {"--from-log", log.string(), "--table",
                                              (dir / "refused.bin").string(), "--sampling", "step"},
                                             dir.path(), "refused", 30s);
    EXPECT_EQ(refused.exit_code, 2) << program << refused.err;
    EXPECT_NE(refused.err.find("--model paper"), std::string::npos) << refused.err;
    EXPECT_EQ(refused.out, "");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "refused.bin"));
}

}  // namespace
}  // namespace ssl_formation
