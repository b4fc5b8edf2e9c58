// End-to-end tests of the three daemons: the real binaries as processes, real multicast sockets
// on 127.0.0.1 (each test on its own group and port), real table files. The simulated producer's
// opponent jumps between formations every 2 s of data time, the paper's scenario: the trainers and
// predictors fed by it run --model paper, and the library's references are the paper's model
// (motion_daemons_test.cpp runs the default motion model on robots that really move).

#include <gtest/gtest.h>
#include <signal.h>

#include <boost/asio/io_context.hpp>
#include <fstream>
#include <mutex>
#include <regex>
#include <thread>

#include "child_process.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

using testing::new_group;
using testing::PredictionListener;

// The table the library computes from the producer's stream for `seed`: the paper's model
// (SamplerConfig's defaults: step sampling every 2 s, no motion table).
TransitionTable reference_table(std::uint64_t seed, int count, int cameras = 1,
                                std::uint64_t* samples = nullptr) {
  simulation::SimulationConfig config;
  config.seed = seed;
  config.cameras = cameras;
  simulation::SimulatedVision vision(config);
  Training training(SamplerConfig{}, TransitionTable(Grid(3, 2)));
  for (int i = 0; i < count; ++i) {
    for (const auto& packet : vision.next().packets) training.add(packet);
  }
  if (samples) *samples = training.samples();
  return training.stored_table().table;
}

const auto entries = testing::table_entries;

std::vector<std::string> trainer_args(const std::string& group,
                                      const std::filesystem::path& table) {
  return {"--vision-address", group, "--table", table.string(), "--status-interval", "0.1",
          "--flush-interval", "60",  "--model", "paper"};
}

// Runs the producer to the end on `group`.
void produce(const TempDir& dir, const std::string& group, std::uint64_t seed, int count,
             std::vector<std::string> extra = {}) {
  std::vector<std::string> args{"--simulation", "paper", "--vision-address", group, "--seed",
                                std::to_string(seed), "--count", std::to_string(count), "--period",
                                "0.002", "--status-interval", "100",
                                // The paper's protocol: vision only, as reference_table() trains.
                                "--referee", "off"};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto result =
      testing::run_to_end(producer_program, args, dir.path(), "producer-" + std::to_string(seed));
  ASSERT_EQ(result.exit_code, 0) << result.err;
}

// Stops a trainer with SIGTERM once it has sampled `formations`, and checks it exits cleanly.
void stop_trainer_after(ChildProcess& trainer, int formations) {
  ASSERT_TRUE(
      testing::wait_for_status(trainer, "formations", static_cast<std::uint64_t>(formations), 10s))
      << trainer.stderr_text();
  trainer.signal(SIGTERM);
  const auto code = trainer.wait(5s);
  ASSERT_TRUE(code.has_value()) << "trainer did not exit on SIGTERM";
  EXPECT_EQ(*code, 0) << trainer.stderr_text();
}

TEST(Daemons, TrainerTableHoldsExactlyTheLibrarysTransitions) {
  TempDir dir;
  const std::string group = new_group();
  ChildProcess trainer(trainer_program, trainer_args(group, dir / "table.bin"), dir.path(),
                       "trainer", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  produce(dir, group, 11, 300);
  stop_trainer_after(trainer, 300);

  const auto loaded = load_table(dir / "table.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  std::uint64_t samples = 0;
  const TransitionTable expected = reference_table(11, 300, 1, &samples);
  EXPECT_GT(expected.transitions(), 1000u);
  EXPECT_EQ(entries(loaded->table), entries(expected));
  EXPECT_EQ(loaded->metadata.samples, samples);
}

TEST(Daemons, FourCameraFeedTrainsTheSameTableAsOneCamera) {
  TempDir dir;
  const std::string group = new_group();
  ChildProcess trainer(trainer_program, trainer_args(group, dir / "table.bin"), dir.path(),
                       "trainer", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  produce(dir, group, 21, 200, {"--cameras", "4", "--camera-overlap", "400"});
  stop_trainer_after(trainer, 200);
  const auto loaded = load_table(dir / "table.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(entries(loaded->table), entries(reference_table(21, 200, 1)));
}

TEST(Daemons, PredictionsOnTheWireEqualTheLibrarysPredictions) {
  TempDir dir;
  const std::filesystem::path table_path = dir / "table.bin";
  const TransitionTable table = reference_table(3, 2000);
  ASSERT_TRUE(save_table(table_path, table, TableMetadata{}));
  const std::string vision = new_group();
  const std::string predictions = new_group();
  ChildProcess predictor(
      predictor_program,
      {"--vision-address", vision, "--prediction-address", predictions, "--table",
       table_path.string(), "--horizon", "3", "--model", "paper", "--print-predictions"},
      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  ASSERT_EQ(predictor.ready_fact("table_loaded"), "1") << predictor.stderr_text();
  PredictionListener listener(predictions);
  produce(dir, vision, 4, 60);
  const auto received = listener.wait_for(60, 10s);
  ASSERT_EQ(received.size(), 60u);

  // The same stream through the library.
  simulation::SimulatedVision vision_stream(simulation::SimulationConfig{.seed = 4});
  std::vector<std::string> expected;
  PredictionConfig config;
  config.horizon = 3;
  config.model = ModelKind::paper;  // the daemon's --model
  config.sampler = sampler_config_for(ModelKind::paper);
  PredictionPipeline pipeline(config, [&](const PredictedFormation& predicted) {
    proto::FormationPrediction message;
    fill_prediction_message(predicted.formation(), predicted.prediction, predicted.context,
                            message);
    expected.push_back(message.SerializeAsString());
  });
  pipeline.set_table(std::make_shared<const StoredTable>(StoredTable{table, {}}));
  for (int i = 0; i < 60; ++i) {
    for (const auto& packet : vision_stream.next().packets) pipeline.add(packet);
  }
  ASSERT_EQ(expected.size(), 60u);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(received[i].SerializeAsString(), expected[i]) << "prediction " << i << ":\n"
                                                            << received[i].DebugString();
  }
  EXPECT_EQ(received[5].steps_size(), 3);
  // One readable line per prediction on stdout.
  ASSERT_TRUE(predictor.wait_for_stdout("t=118.00 frame=59", 5s));
  predictor.signal(SIGINT);
  EXPECT_EQ(predictor.wait(2s), 0);
}

TEST(Daemons, ProducerSendsNinetyPercentPlaysOverTenThousandCycles) {
  TempDir dir;
  // 10,000 cycles are about 25,000 formations; nobody needs to listen for the proportions.
  const auto result =
      testing::run_to_end(producer_program,
                          {"--simulation", "paper", "--referee", "off", "--vision-address",
                           new_group(), "--period", "0", "--count", "25000", "--seed", "99"},
                          dir.path(), "producer");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  std::smatch match;
  const std::regex summary(
      R"(done: formations=25000 .*from_plays=(\d+) \(([\d.]+)%\) random=(\d+) \(([\d.]+)%\))");
  ASSERT_TRUE(std::regex_search(result.err, match, summary)) << result.err;
  EXPECT_NEAR(std::stod(match[2]), 90.0, 2.0);
  EXPECT_NEAR(std::stod(match[4]), 10.0, 2.0);
}

TEST(Daemons, ProducerPacketsRoundTripThroughOurSchema) {
  TempDir dir;
  const std::string group = new_group();
  boost::asio::io_context io;
  net::MulticastReceiver receiver(io, net::parse_multicast_endpoint(group).value());
  std::mutex mutex;
  std::vector<std::string> datagrams;
  bool marker_back = false;
  receiver.start([&](std::span<const std::byte> data, const net::udp::endpoint&) {
    std::string bytes(reinterpret_cast<const char*>(data.data()), data.size());
    std::lock_guard lock(mutex);
    if (bytes == testing::end_marker) {
      marker_back = true;
    } else {
      datagrams.push_back(std::move(bytes));
    }
  });
  std::thread io_thread([&] { io.run_for(20s); });
  produce(dir, group, 8, 20, {"--cameras", "4", "--jitter-mm", "15", "--opponent-color", "blue"});
  // The producer has stopped: once our end marker is back, all it sent has arrived.
  ASSERT_TRUE(testing::send_to_group(group, testing::end_marker));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (std::lock_guard lock(mutex); marker_back) break;
    std::this_thread::sleep_for(2ms);
  }
  io.stop();
  io_thread.join();
  ASSERT_TRUE(marker_back);
  // 20 formations x 4 cameras, plus a geometry packet every 3 s of data time (10 of them).
  ASSERT_EQ(datagrams.size(), 90u);
  int detections = 0;
  int robots = 0;
  for (const std::string& bytes : datagrams) {
    SSL_WrapperPacket packet;
    ASSERT_TRUE(packet.ParseFromString(bytes));
    ASSERT_TRUE(packet.IsInitialized());
    EXPECT_EQ(packet.SerializeAsString(), bytes);
    if (packet.has_detection()) {
      ++detections;
      robots += packet.detection().robots_blue_size() + packet.detection().robots_yellow_size();
    }
  }
  EXPECT_EQ(detections, 80);
  EXPECT_GE(robots, 20 * 12);  // both teams, each robot at least once per formation
}

TEST(Daemons, TrainerSavesOnSigtermAndResumesItsCounts) {
  TempDir dir;
  const std::string group = new_group();
  const auto table_path = dir / "table.bin";
  std::uint64_t first_transitions = 0;
  {
    ChildProcess trainer(trainer_program, trainer_args(group, table_path), dir.path(), "trainer1",
                         Readiness::ready_file);
    ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
    produce(dir, group, 5, 100);
    stop_trainer_after(trainer, 100);
    const auto loaded = load_table(table_path, Grid(3, 2));
    ASSERT_TRUE(loaded) << loaded.error().message;
    first_transitions = loaded->table.transitions();
    EXPECT_EQ(entries(loaded->table), entries(reference_table(5, 100)));
  }
  {
    ChildProcess trainer(trainer_program, trainer_args(group, table_path), dir.path(), "trainer2",
                         Readiness::ready_file);
    ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
    // Ready means the table is open, and the trainer says it resumed it (the counts below show
    // that it really did).
    EXPECT_NE(trainer.stderr_text().find("resumed " + table_path.string()), std::string::npos)
        << trainer.stderr_text();
    produce(dir, group, 5, 100);
    stop_trainer_after(trainer, 100);
  }
  const auto loaded = load_table(table_path, Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(loaded->table.transitions(), 2 * first_transitions);
  EXPECT_EQ(loaded->metadata.samples, 200u);
}

TEST(Daemons, TrainerRefusesATableOfAnotherGridUnlessReset) {
  TempDir dir;
  const auto table_path = dir / "table.bin";
  ASSERT_TRUE(save_table(table_path, reference_table(1, 50), TableMetadata{}));
  const auto before = testing::run_to_end(
      trainer_program,
      {"--table", table_path.string(), "--grid", "6x4", "--vision-address", new_group()},
      dir.path(), "refused", 5s);
  EXPECT_EQ(before.exit_code, 1);
  EXPECT_NE(before.err.find("3x2"), std::string::npos) << before.err;
  EXPECT_NE(before.err.find("6x4"), std::string::npos) << before.err;
  EXPECT_NE(before.err.find("--reset"), std::string::npos) << before.err;
  ASSERT_TRUE(load_table(table_path, Grid(3, 2)));  // untouched

  const std::string group = new_group();
  ChildProcess trainer(trainer_program,
                       {"--table", table_path.string(), "--grid", "6x4", "--reset",
                        "--vision-address", group, "--status-interval", "0.1"},
                       dir.path(), "reset", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  trainer.signal(SIGTERM);
  EXPECT_EQ(trainer.wait(5s), 0);
  EXPECT_TRUE(load_table(table_path, Grid(6, 4)));
}

TEST(Daemons, PredictorWaitsForTheTableAndPicksUpReplacements) {
  TempDir dir;
  const auto table_path = dir / "table.bin";
  const std::string vision = new_group();
  const std::string predictions = new_group();
  ChildProcess predictor(predictor_program,
                         {"--vision-address", vision, "--prediction-address", predictions,
                          "--table", table_path.string(), "--reload-interval", "0.05", "--quiet",
                          "--status-interval", "0.05", "--model", "paper"},
                         dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  ASSERT_EQ(predictor.ready_fact("table_loaded"), "0") << predictor.stderr_text();
  PredictionListener listener(predictions);

  const TransitionTable first = reference_table(1, 100);
  ASSERT_TRUE(save_table(table_path, first, TableMetadata{}));
  ASSERT_TRUE(testing::wait_for_status(predictor, "table_reloads", 1, 5s))
      << predictor.stderr_text();
  produce(dir, vision, 2, 5);
  auto received = listener.wait_for(5, 5s);
  ASSERT_EQ(received.size(), 5u);
  EXPECT_EQ(received.back().table_transitions(), first.transitions());

  const TransitionTable second = reference_table(1, 400);
  ASSERT_NE(first.transitions(), second.transitions());
  ASSERT_TRUE(save_table(table_path, second, TableMetadata{}));  // atomic rename, as the trainer
  ASSERT_TRUE(testing::wait_for_status(predictor, "table_reloads", 2, 5s))
      << predictor.stderr_text();
  produce(dir, vision, 2, 5);
  received = listener.wait_for(10, 5s);
  ASSERT_EQ(received.size(), 10u);
  EXPECT_EQ(received.back().table_transitions(), second.transitions());
  EXPECT_TRUE(predictor.running());
}

TEST(Daemons, TwoPipelinesOnDifferentPortsDoNotInterfere) {
  TempDir dir;
  const std::string vision_a = new_group();
  const std::string vision_b = new_group();
  const std::string predictions_a = new_group();
  const std::string predictions_b = new_group();
  const TransitionTable table = reference_table(3, 500);
  ASSERT_TRUE(save_table(dir / "predict.bin", table, TableMetadata{}));
  ChildProcess trainer_a(trainer_program, trainer_args(vision_a, dir / "a.bin"), dir.path(),
                         "trainer-a", Readiness::ready_file);
  ChildProcess trainer_b(trainer_program, trainer_args(vision_b, dir / "b.bin"), dir.path(),
                         "trainer-b", Readiness::ready_file);
  ChildProcess predictor_a(
      predictor_program,
      {"--vision-address", vision_a, "--prediction-address", predictions_a, "--table",
       (dir / "predict.bin").string(), "--quiet", "--model", "paper"},
      dir.path(), "predictor-a", Readiness::ready_file);
  ChildProcess predictor_b(
      predictor_program,
      {"--vision-address", vision_b, "--prediction-address", predictions_b, "--table",
       (dir / "predict.bin").string(), "--quiet", "--model", "paper"},
      dir.path(), "predictor-b", Readiness::ready_file);
  for (ChildProcess* p : {&trainer_a, &trainer_b, &predictor_a, &predictor_b}) {
    ASSERT_TRUE(p->wait_until_ready(10s)) << p->stderr_text();
  }
  EXPECT_EQ(predictor_a.ready_fact("table_loaded"), "1");
  EXPECT_EQ(predictor_b.ready_fact("table_loaded"), "1");
  PredictionListener listen_a(predictions_a);
  PredictionListener listen_b(predictions_b);
  produce(dir, vision_a, 6, 40);
  stop_trainer_after(trainer_a, 40);
  EXPECT_EQ(listen_a.wait_for(40, 5s).size(), 40u);
  trainer_b.signal(SIGTERM);
  ASSERT_EQ(trainer_b.wait(5s), 0);
  predictor_b.signal(SIGTERM);
  ASSERT_EQ(predictor_b.wait(5s), 0);
  // All of pipeline a's predictions have arrived, and so, once an end marker sent after them
  // through each prediction group is back, has anything that went astray.
  const auto on_a = listen_a.drain(5s);
  const auto on_b = listen_b.drain(5s);
  ASSERT_TRUE(on_a.has_value() && on_b.has_value());
  EXPECT_EQ(on_a->size(), 40u);
  EXPECT_TRUE(on_b->empty());
  const auto a = load_table(dir / "a.bin", Grid(3, 2));
  const auto b = load_table(dir / "b.bin", Grid(3, 2));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(entries(a->table), entries(reference_table(6, 40)));
  EXPECT_EQ(b->table.transitions(), 0u);
  // Pipeline b's daemons received nothing at all (their last status lines, written as they exit).
  for (ChildProcess* p : {&trainer_b, &predictor_b}) {
    EXPECT_NE(p->stderr_text().find("status: no vision packets yet"), std::string::npos)
        << p->stderr_text();
    EXPECT_EQ(testing::last_status(p->stderr_text()).at("packets"), 0u) << p->stderr_text();
  }
}

TEST(Daemons, SharedOptionsHelpAndErrors) {
  TempDir dir;
  for (const auto& program : {producer_program, trainer_program, predictor_program}) {
    const auto help = testing::run_to_end(program, {"--help"}, dir.path(), "help", 5s);
    EXPECT_EQ(help.exit_code, 0) << program;
    for (const std::string option :
         {"--vision-address", "--interface arg (=127.0.0.1)", "--step", "--opponent-color arg (=",
          "--opponent-attacks arg (=", "--field-length arg (=9000)", "--field-width arg (=6000)"}) {
      EXPECT_NE(help.out.find(option), std::string::npos) << program << " lacks " << option;
    }
    const auto bad = testing::run_to_end(program, {"--no-such-option"}, dir.path(), "bad", 5s);
    EXPECT_EQ(bad.exit_code, 2) << program;
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
    const auto bad_value = testing::run_to_end(program, {"--vision-address", "10.1.2.3:10006"},
                                               dir.path(), "bad-value", 5s);
    EXPECT_EQ(bad_value.exit_code, 2) << program << bad_value.err;
  }
  for (const auto& program : {trainer_program, predictor_program}) {
    const auto help = testing::run_to_end(program, {"--help"}, dir.path(), "help", 5s);
    EXPECT_NE(help.out.find("--table arg (=formation-table.bin)"), std::string::npos);
    // The grid, the model and the step of the table when one is there.
    EXPECT_NE(help.out.find("--grid arg (=auto)"), std::string::npos) << program;
    // The opponent from the referee's names and sides unless given.
    EXPECT_NE(help.out.find("--opponent-color arg (=referee)"), std::string::npos) << program;
    EXPECT_NE(help.out.find("--opponent-attacks arg (=referee)"), std::string::npos) << program;
    EXPECT_NE(help.out.find("--our-team"), std::string::npos) << program;
    EXPECT_NE(help.out.find("--opponent-team"), std::string::npos) << program;
    // The table's model, else the motion model, on the sampling it needs.
    EXPECT_NE(help.out.find("--model arg (=auto)"), std::string::npos) << program;
    EXPECT_NE(help.out.find("--sampling arg (=auto)"), std::string::npos) << program;
    EXPECT_NE(help.out.find("--step arg (=auto)"), std::string::npos) << program;
    // Only the predictor predicts.
    EXPECT_EQ(help.out.find("--recalibration-half-life arg (=60)") != std::string::npos,
              program == predictor_program)
        << program;
    EXPECT_EQ(help.out.find("--prior-table FILE") != std::string::npos,
              program == predictor_program)
        << program;
  }
  // A prior that is not a table says so, naming the option, before anything starts.
  std::ofstream(dir.path() / "not-a-table.bin") << "hello";
  for (const std::string prior : {"missing.bin", "not-a-table.bin"}) {
    const auto bad_prior = testing::run_to_end(predictor_program, {"--prior-table", prior},
                                               dir.path(), "bad-prior", 5s);
    EXPECT_EQ(bad_prior.exit_code, 2) << bad_prior.err;
    EXPECT_NE(bad_prior.err.find("--prior-table: "), std::string::npos) << bad_prior.err;
    EXPECT_NE(bad_prior.err.find(prior), std::string::npos) << bad_prior.err;
  }
}

TEST(Daemons, EachDaemonStopsWithinOneSecondOfASignal) {
  TempDir dir;
  for (const int signal_number : {SIGINT, SIGTERM}) {
    const std::string group = new_group();
    std::vector<std::unique_ptr<ChildProcess>> daemons;
    daemons.push_back(std::make_unique<ChildProcess>(trainer_program,
                                                     trainer_args(group, dir / "t.bin"), dir.path(),
                                                     "trainer", Readiness::ready_file));
    daemons.push_back(std::make_unique<ChildProcess>(
        predictor_program,
        std::vector<std::string>{"--vision-address", group, "--table", (dir / "t.bin").string(),
                                 "--prediction-address", new_group(), "--status-interval", "0.1",
                                 "--model", "paper"},
        dir.path(), "predictor", Readiness::ready_file));
    daemons.push_back(std::make_unique<ChildProcess>(
        producer_program,
        std::vector<std::string>{"--simulation", "paper", "--referee", "off", "--vision-address",
                                 group, "--period", "0.05"},
        dir.path(), "producer", Readiness::ready_file));
    for (auto& d : daemons) {
      ASSERT_TRUE(d->wait_until_ready(10s)) << d->stderr_text();
    }
    EXPECT_EQ(daemons[2]->ready_fact("mode"), "simulation");
    // Stopped mid-stream: once the feed reaches the trainer and the predictor.
    for (auto& d : {daemons[0].get(), daemons[1].get()}) {
      ASSERT_TRUE(testing::wait_for_status(*d, "packets", 1, 10s)) << d->stderr_text();
    }
    for (auto& d : daemons) {
      const auto start = std::chrono::steady_clock::now();
      d->signal(signal_number);
      const auto code = d->wait(1s);
      EXPECT_TRUE(code.has_value()) << d->stderr_text();
      EXPECT_EQ(code.value_or(-1), 0);
      EXPECT_LT(std::chrono::steady_clock::now() - start, 1s);
    }
  }
}

}  // namespace
}  // namespace ssl_formation
