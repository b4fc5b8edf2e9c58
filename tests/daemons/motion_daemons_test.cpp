// The default model, the motion model, through the real programs on a log of robots that really
// move (moving_robots.hpp, 60 Hz frames): ssl-trainer --from-log writes a version-3 table equal
// to the library's training; ssl-predictor --from-log predicts a position and 0 < r50 < r90 for
// every robot; the daemon fed the same log by ssl-producer --replay multicasts exactly that CSV;
// and a daemon given the paper's version-1 table says so, keeps running and takes the version-3
// table written later at the same path.

#include <gtest/gtest.h>
#include <signal.h>

#include <array>
#include <cmath>
#include <iostream>
#include <set>

#include "child_process.hpp"
#include "motion_table_sums.hpp"
#include "moving_robots.hpp"
#include "pipeline_support.hpp"
#include "prediction_rows.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::read_text;
using testing::Readiness;
using testing::rows_of;
using testing::split;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

// The format version in a table file's header (bytes 8-11, little-endian).
std::uint32_t table_version(const std::filesystem::path& path) {
  const std::string bytes = read_text(path);
  if (bytes.size() < 12) return 0;
  std::uint32_t version = 0;
  for (int i = 0; i < 4; ++i) {
    version |= std::uint32_t{static_cast<unsigned char>(bytes[8 + static_cast<std::size_t>(i)])}
               << (8 * i);
  }
  return version;
}

double number(const std::string& text) { return std::stod(text); }

class MotionDaemons : public ::testing::Test {
 protected:
  // A minute of play to train on, and 20 s of another (another seed, later on the clock) to
  // predict; the test log starts well after the training log ends, so replaying one after the
  // other is a new stream, as a new match would be.
  static constexpr double test_seconds = 20.0;
  static constexpr int test_frames = 1200;  // at 60 Hz

  void SetUp() override {
    ASSERT_EQ(testing::write_vision_log(train_log,
                                        testing::moving_robots_packets(
                                            {.seed = 1, .seconds = 60.0, .start_time_s = 100.0})),
              "");
    ASSERT_EQ(testing::write_vision_log(
                  test_log, testing::moving_robots_packets(
                                {.seed = 2, .seconds = test_seconds, .start_time_s = 1000.0})),
              "");
    // The default model: no --model.
    const auto trained = testing::run_to_end(
        trainer_program, {"--from-log", train_log.string(), "--table", table.string()}, dir.path(),
        "train", 60s);
    ASSERT_EQ(trained.exit_code, 0) << trained.err;
  }

  // `ssl-predictor --from-log LOG --table TABLE --horizon 3` with the default model (LOG: the
  // test log unless given): the CSV's rows, after its header (checked).
  std::vector<std::string> predict_csv(const std::filesystem::path& table_path,
                                       const std::string& name) {
    return predict_csv(table_path, name, test_log);
  }
  std::vector<std::string> predict_csv(const std::filesystem::path& table_path,
                                       const std::string& name, const std::filesystem::path& log) {
    const auto csv_path = dir / (name + ".csv");
    const auto offline =
        testing::run_to_end(predictor_program,
                            {"--from-log", log.string(), "--table", table_path.string(),
                             "--horizon", "3", "--output", csv_path.string()},
                            dir.path(), name, 60s);
    EXPECT_EQ(offline.exit_code, 0) << offline.err;
    std::vector<std::string> lines = split(read_text(csv_path), '\n');
    if (lines.empty()) {
      ADD_FAILURE() << "no CSV";
      return lines;
    }
    EXPECT_EQ(lines.front(), testing::prediction_csv_header);
    lines.erase(lines.begin());
    return lines;
  }

  TempDir dir;
  const std::filesystem::path train_log = dir / "train.log.gz";
  const std::filesystem::path test_log = dir / "test.log";
  const std::filesystem::path table = dir / "table.bin";
};

TEST_F(MotionDaemons, TrainerWritesAMotionTableAndTheDaemonMulticastsTheCsvsPositionsAndRadii) {
  // The trainer's table: version 5, the library's training with the motion model on the same log
  // (frame sampling, --step 0.5, 3 steps ahead: the defaults) as it is saved (its rows that add
  // nothing folded), count for count.
  EXPECT_EQ(table_version(table), table_file_compact_motion_version);
  const auto loaded = load_table(table, Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  ASSERT_TRUE(loaded->motion != nullptr);
  EXPECT_EQ(loaded->metadata.step_s, 0.5);
  EXPECT_EQ(loaded->motion->config().step_s, 0.5);
  EXPECT_EQ(loaded->motion->config().horizons, 3);
  SamplerConfig sampler;
  sampler.sampling = Sampling::frame;
  sampler.step_s = 0.5;
  MotionConfig motion;
  motion.step_s = 0.5;
  motion.horizons = 3;
  Training library(sampler, TransitionTable(Grid(3, 2)), 0, MotionTable(motion));
  const auto read = read_vision_log(train_log);
  ASSERT_TRUE(read) << read.error().message;
  for (const auto& packet : read->packets) library.add(packet);
  ASSERT_NE(library.stored_table().motion, nullptr);
  EXPECT_GT(library.stored_table().motion->instances(), 5000u);
  EXPECT_GT(library.stored_table().motion->held_out(), 1000u);
  EXPECT_TRUE(*loaded->motion == testing::as_saved(*library.stored_table().motion));
  EXPECT_EQ(testing::table_entries(loaded->table),
            testing::table_entries(library.stored_table().table));
  EXPECT_EQ(loaded->metadata.samples, library.samples());

  // Its predictions: a position and 0 < r50 < r90 for every robot at every step.
  const std::vector<std::string> lines = predict_csv(table, "from-log");
  std::set<std::string> instants;
  for (const std::string& line : lines) {
    const std::vector<std::string> fields = split(line, ',');
    ASSERT_EQ(fields.size(), testing::prediction_columns) << line;
    instants.insert(fields[testing::column_t_capture]);
    ASSERT_EQ(fields[testing::column_model], "motion") << line;
    const double x = number(fields[testing::column_feed_x]);
    const double y = number(fields[testing::column_feed_y]);
    ASSERT_TRUE(std::isfinite(x) && std::isfinite(y)) << line;
    // On (or near) the field: the robots stay within 4.1 x 2.7 m of the centre.
    ASSERT_LT(std::abs(x), 6000.0) << line;
    ASSERT_LT(std::abs(y), 4500.0) << line;
    const double r50 = number(fields[testing::column_radius_50]);
    const double r90 = number(fields[testing::column_radius_90]);
    ASSERT_GT(r50, 0.0) << line;
    ASSERT_LT(r50, r90) << line;
    ASSERT_TRUE(std::isfinite(r90)) << line;
    const int step = std::stoi(fields[3]);
    ASSERT_EQ(number(fields[testing::column_horizon_s]), 0.5 * step) << line;
  }
  // Every frame sampled and predicted: 3 steps of the 6 opponent robots each.
  EXPECT_EQ(instants.size(), static_cast<std::size_t>(test_frames));
  EXPECT_EQ(lines.size(), instants.size() * 3u * 6u);
  // The further ahead, the wider the radii.
  std::array<double, 4> mean_r50{}, mean_r90{};
  for (const std::string& line : lines) {
    const std::vector<std::string> fields = split(line, ',');
    const auto step = static_cast<std::size_t>(std::stoi(fields[3]));
    mean_r50[step] += number(fields[testing::column_radius_50]) / (test_frames * 6.0);
    mean_r90[step] += number(fields[testing::column_radius_90]) / (test_frames * 6.0);
  }
  EXPECT_LT(mean_r90[1], mean_r90[2]);
  EXPECT_LT(mean_r90[2], mean_r90[3]);
  std::cout << "[ figures  ] motion table: instances=" << loaded->motion->instances()
            << " held_out=" << loaded->motion->held_out() << " rows=" << loaded->motion->rows()
            << "; mean radii (mm):";
  for (std::size_t step = 1; step <= 3; ++step) {
    std::cout << " +" << 0.5 * static_cast<double>(step) << " s r50=" << mean_r50[step]
              << " r90=" << mean_r90[step];
  }
  std::cout << "\n";

  // The daemon with the same table, fed the same log by a replay: exactly the CSV's predictions,
  // positions and radii included.
  const std::string vision = new_group();
  const std::string predictions = new_group();
  ChildProcess daemon(predictor_program,
                      {"--vision-address", vision, "--prediction-address", predictions, "--table",
                       table.string(), "--horizon", "3", "--quiet"},
                      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
  EXPECT_EQ(daemon.ready_fact("table_loaded"), "1");
  testing::PredictionListener listener(predictions);
  // 20 s of 60 Hz frames at 10x: 600 datagrams a second for 2 s.
  const auto replayed = testing::run_to_end(
      producer_program,
      {"--replay", test_log.string(), "--vision-address", vision, "--speed", "10"}, dir.path(),
      "replay", 30s);
  ASSERT_EQ(replayed.exit_code, 0) << replayed.err;
  listener.wait_for(instants.size(), 20s);
  const auto messages = listener.drain(5s);
  ASSERT_TRUE(messages.has_value());
  ASSERT_EQ(messages->size(), instants.size()) << daemon.stderr_text();
  for (const auto& message : *messages) {
    ASSERT_EQ(message.model(), "motion");
    ASSERT_EQ(message.steps_size(), 3);
    for (const auto& step : message.steps()) {
      ASSERT_EQ(step.horizon_seconds(), 0.5 * step.step());
      for (const auto& robot : step.robots()) {
        ASSERT_TRUE(robot.has_position() && robot.has_radius_50_mm() && robot.has_radius_90_mm())
            << message.DebugString();
      }
    }
  }
  const std::vector<std::string> multicast = rows_of(*messages);
  ASSERT_EQ(multicast.size(), lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) ASSERT_EQ(multicast[i], lines[i]) << "row " << i;

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(5s), 0) << daemon.stderr_text();
}

TEST_F(MotionDaemons, PredictorRefusesAVersionOneTableKeepsRunningAndTakesAVersionTwoOneLater) {
  // The paper's table of the same log: version 1, which serves --model paper only.
  const auto paper_table = dir / "paper.bin";
  const auto trained = testing::run_to_end(
      trainer_program,
      {"--from-log", train_log.string(), "--table", paper_table.string(), "--model", "paper"},
      dir.path(), "train-paper", 60s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  ASSERT_EQ(table_version(paper_table), table_file_version);
  // A short stretch of play to feed while the daemon has no table it can use.
  const auto short_log = dir / "short.log";
  ASSERT_EQ(testing::write_vision_log(
                short_log,
                testing::moving_robots_packets({.seed = 3, .seconds = 3.0, .start_time_s = 500.0})),
            "");
  const std::filesystem::path live = dir / "live.bin";
  std::filesystem::copy_file(paper_table, live);

  const std::string vision = new_group();
  const std::string predictions = new_group();
  ChildProcess daemon(predictor_program,
                      {"--vision-address", vision, "--prediction-address", predictions, "--table",
                       live.string(), "--horizon", "3", "--quiet", "--reload-interval", "0.05",
                       "--status-interval", "0.05", "--model", "motion"},
                      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
  // Told --model motion: one error line that names the file and the model the table serves.
  ASSERT_TRUE(daemon.wait_for_stderr("--model paper", 5s)) << daemon.stderr_text();
  {
    const std::string text = daemon.stderr_text();
    const std::size_t at = text.find("--model paper");
    const std::size_t line_start = text.rfind('\n', at) + 1;
    const std::string line = text.substr(line_start, text.find('\n', at) - line_start);
    EXPECT_NE(line.find("error"), std::string::npos) << line;
    EXPECT_NE(line.find(live.string()), std::string::npos) << line;
    EXPECT_NE(line.find("version-1"), std::string::npos) << line;
  }
  EXPECT_EQ(daemon.stderr_text().find("loaded table"), std::string::npos) << daemon.stderr_text();
  testing::PredictionListener listener(predictions);

  // Fed meanwhile: it samples every frame and predicts nothing.
  const auto first = testing::run_to_end(
      producer_program,
      {"--replay", short_log.string(), "--vision-address", vision, "--speed", "10"}, dir.path(),
      "replay-short", 30s);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_TRUE(testing::wait_for_status(daemon, "formations", 180, 10s)) << daemon.stderr_text();
  EXPECT_EQ(testing::last_status(daemon.stderr_text()).at("predictions"), 0u)
      << daemon.stderr_text();
  const auto nothing = listener.drain(5s);
  ASSERT_TRUE(nothing.has_value());
  EXPECT_TRUE(nothing->empty());
  EXPECT_TRUE(daemon.running());

  // The motion model's table written over it (atomically, as the trainer saves): taken, and the
  // test log then predicted exactly as --from-log predicts it with that table.
  std::filesystem::copy_file(table, dir / "live.bin.new");
  std::filesystem::rename(dir / "live.bin.new", live);
  ASSERT_TRUE(daemon.wait_for_stderr("loaded table " + live.string(), 5s)) << daemon.stderr_text();
  const auto second = testing::run_to_end(
      producer_program,
      {"--replay", test_log.string(), "--vision-address", vision, "--speed", "10"}, dir.path(),
      "replay-test", 30s);
  ASSERT_EQ(second.exit_code, 0) << second.err;
  listener.wait_for(test_frames, 20s);
  const auto messages = listener.drain(5s);
  ASSERT_TRUE(messages.has_value());
  ASSERT_EQ(messages->size(), static_cast<std::size_t>(test_frames)) << daemon.stderr_text();
  for (const auto& message : *messages) ASSERT_EQ(message.model(), "motion");
  const std::vector<std::string> multicast = rows_of(*messages);
  const std::vector<std::string> lines = predict_csv(table, "from-log");
  ASSERT_EQ(multicast.size(), lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) ASSERT_EQ(multicast[i], lines[i]) << "row " << i;

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(5s), 0) << daemon.stderr_text();
  EXPECT_EQ(testing::last_status(daemon.stderr_text()).at("predictions"),
            static_cast<std::uint64_t>(test_frames));
}

// Fed at the real pace (a frame every 16.7 ms), the daemon rehearses its last prediction shortly
// before each next frame is due, to warm its caches: it sends nothing more, and what it sends is
// still exactly what --from-log predicts.
TEST_F(MotionDaemons, WarmUpsBetweenFramesAtTheRealPaceSendNothingAndChangeNoPrediction) {
  const auto short_log = dir / "short.log";
  constexpr int frames = 180;  // 3 s at 60 Hz
  ASSERT_EQ(testing::write_vision_log(short_log,
                                      testing::moving_robots_packets(
                                          {.seed = 4, .seconds = 3.0, .start_time_s = 2000.0})),
            "");
  const std::string vision = new_group();
  const std::string predictions = new_group();
  ChildProcess daemon(
      predictor_program,
      {"--vision-address", vision, "--prediction-address", predictions, "--table", table.string(),
       "--horizon", "3", "--quiet", "--warm-up-lead", "2", "--status-interval", "0.1"},
      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
  testing::PredictionListener listener(predictions);
  const auto replayed = testing::run_to_end(
      producer_program, {"--replay", short_log.string(), "--vision-address", vision}, dir.path(),
      "replay", 30s);
  ASSERT_EQ(replayed.exit_code, 0) << replayed.err;
  listener.wait_for(frames, 20s);
  const auto messages = listener.drain(2s);
  ASSERT_TRUE(messages.has_value());
  ASSERT_EQ(messages->size(), static_cast<std::size_t>(frames)) << daemon.stderr_text();
  const std::vector<std::string> multicast = rows_of(*messages);
  const std::vector<std::string> lines = predict_csv(table, "from-log-short", short_log);
  ASSERT_EQ(multicast.size(), lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) ASSERT_EQ(multicast[i], lines[i]) << "row " << i;

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(5s), 0) << daemon.stderr_text();
  const auto status = testing::last_status(daemon.stderr_text());
  EXPECT_EQ(status.at("predictions"), static_cast<std::uint64_t>(frames));
  EXPECT_EQ(status.at("send_errors"), 0u);  // every prediction sent
  // Nearly every gap between two frames had its warm-up (a busy machine may let a frame come
  // first now and then).
  EXPECT_GT(status.at("warm_ups"), static_cast<std::uint64_t>(frames / 2)) << daemon.stderr_text();
}

}  // namespace
}  // namespace ssl_formation
