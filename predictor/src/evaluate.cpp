#include "ssl_formation/predictor/evaluate.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <fstream>

#include "ssl_formation/evaluation.hpp"
#include "ssl_formation/log_file.hpp"
#include "ssl_formation/prediction_pipeline.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/training.hpp"

namespace ssl_formation::evaluate {

namespace ev = ssl_formation::evaluation;

namespace {

// A stream of vision packets: a log file, or the simulated vision of a seed.
class PacketSource {
 public:
  static PacketSource from_log(const std::string& path) {
    PacketSource source;
    Result<LogVisionPackets> log = read_vision_log(path);
    if (!log) throw std::runtime_error(log.error().message);
    if (log->stopped_early) {
      // Everything before the damage is kept; a file with nothing before it is no data.
      if (log->packets.empty()) throw std::runtime_error(log->stopped_early->message);
      spdlog::warn("{}; using the {} packets before it", log->stopped_early->message,
                   log->packets.size());
    }
    source.packets_ = std::move(log->packets);
    return source;
  }
  static PacketSource simulated(std::uint64_t seed, int formations, double jitter_mm, int cameras) {
    PacketSource source;
    sim::SimulationConfig config;
    config.seed = seed;
    config.jitter_mm = jitter_mm;
    config.cameras = cameras;
    sim::SimulatedVision vision(config);
    for (int i = 0; i < formations; ++i) {
      for (auto& packet : vision.next().packets) source.packets_.push_back(std::move(packet));
    }
    return source;
  }
  const std::vector<SSL_WrapperPacket>& packets() const { return packets_; }
  // The first `fraction` of the packets and the rest: a time split of one log.
  std::pair<PacketSource, PacketSource> split(double fraction) const {
    const auto cut = static_cast<std::size_t>(fraction * static_cast<double>(packets_.size()));
    PacketSource head;
    PacketSource tail;
    head.packets_.assign(packets_.begin(), packets_.begin() + static_cast<std::ptrdiff_t>(cut));
    tail.packets_.assign(packets_.begin() + static_cast<std::ptrdiff_t>(cut), packets_.end());
    return {std::move(head), std::move(tail)};
  }

 private:
  std::vector<SSL_WrapperPacket> packets_;
};

TransitionTable train(const SamplerConfig& config, const PacketSource& source,
                      FieldSize* field = nullptr, std::uint64_t* samples = nullptr) {
  Training training(config, TransitionTable(config.grid));
  for (const auto& packet : source.packets()) training.add(packet);
  if (field) *field = training.sampler().field();
  if (samples) *samples = training.samples();
  return training.table();
}

// The test stream through the PredictionPipeline the predictor runs, predicting from `table`
// as far ahead as the evaluation looks.
std::vector<ev::PredictedTest> predict_stream(const SamplerConfig& config,
                                              std::shared_ptr<const StoredTable> table,
                                              const PacketSource& source, FieldSize* field) {
  std::vector<ev::PredictedTest> tests;
  PredictionConfig prediction;
  prediction.sampler = config;
  prediction.horizon = ev::HoldoutResult::max_horizon;
  PredictionPipeline pipeline(prediction, [&](const PredictedFormation& predicted) {
    tests.push_back({predicted.formation(), predicted.prediction});
  });
  pipeline.set_table(std::move(table));
  for (const auto& packet : source.packets()) pipeline.add(packet);
  *field = pipeline.sampler().field();
  return tests;
}

std::ofstream open_csv(const EvaluateOptions& options, const std::string& name) {
  const std::filesystem::path path = std::filesystem::path(options.output_dir) / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  spdlog::info("writing {}", path.string());
  return out;
}

// ---- paper
// ---------------------------------------------------------------------------------------

}  // namespace

int run_paper(const EvaluateOptions& options) {
  SamplerConfig config = options.model.sampler_config();
  const auto started = std::chrono::steady_clock::now();
  const PacketSource training_data =
      options.train_log.empty() ? PacketSource::simulated(options.seed, options.train_formations,
                                                          options.jitter_mm, options.cameras)
                                : PacketSource::from_log(options.train_log);
  FieldSize field = config.field;
  std::uint64_t training_samples = 0;
  const TransitionTable table = train(config, training_data, &field, &training_samples);

  std::vector<ev::PlayStates> plays;
  for (int p = 0; p < sim::play_count; ++p) {
    std::vector<std::vector<Point>> positions;
    for (int f = 0; f < sim::formations_per_play; ++f) {
      const auto& team = sim::play_formation(p, f);
      positions.emplace_back(team.begin(), team.end());
    }
    plays.push_back(ev::play_states(table.codec(), field, positions));
  }

  // The test formations: the paper's random formations, every robot anywhere, velocity 0.
  std::mt19937_64 random(options.test_seed);
  std::uniform_real_distribution<double> x(-field.length_mm / 2, field.length_mm / 2);
  std::uniform_real_distribution<double> y(-field.width_mm / 2, field.width_mm / 2);
  ev::PaperSummary summary;
  std::ofstream csv = open_csv(options, "paper-running-averages.csv");
  csv << "test,count_per_play,distance_per_play,count_per_formation,distance_per_formation,"
         "confidence_1,confidence_2\n";
  for (int t = 0; t < options.tests; ++t) {
    std::vector<FormationRobot> robots(sim::robots_per_team);
    for (std::size_t id = 0; id < robots.size(); ++id) {
      robots[id].robot_id = static_cast<std::uint32_t>(id);
      robots[id].position = Point{x(random), y(random)};
    }
    const Formation formation =
        FormationSampler::build_formation(table.codec(), field, robots, nullptr);
    ev::accumulate(summary, ev::run_paper_test(table, robot_states(formation), plays));
    csv << summary.tests << ',' << summary.count_per_play << ',' << summary.distance_per_play << ','
        << summary.count_per_formation << ',' << summary.distance_per_formation << ','
        << summary.mean_confidence[0] << ',' << summary.mean_confidence[1] << '\n';
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  std::printf(
      "Paper protocol (§6.1): trained on %llu formations (%zu packets, %llu transitions), "
      "%d tests, grid %s\n",
      static_cast<unsigned long long>(training_samples), training_data.packets().size(),
      static_cast<unsigned long long>(table.transitions()), summary.tests,
      config.grid.to_string().c_str());
  std::printf("%-28s %14s %14s %14s %14s\n", "", "per play", "paper", "per formation", "paper");
  std::printf("%-28s %14.4f %14.4f %14.4f %14.4f\n", "count similarity measure",
              summary.count_per_play, 16.6826, summary.count_per_formation, 5.5608);
  std::printf("%-28s %14.4f %14.4f %14.4f %14.4f\n", "distance similarity measure",
              summary.distance_per_play, 21.9680, summary.distance_per_formation, 7.3226);
  std::printf("average confidence: 1st predicted formation %.6f, 2nd %.6f\n",
              summary.mean_confidence[0], summary.mean_confidence[1]);
  std::printf("took %.2f s\n", seconds);
  return 0;
}

// ---- holdout
// ---------------------------------------------------------------------------------------

namespace {

std::pair<PacketSource, PacketSource> holdout_data(const EvaluateOptions& options) {
  if (options.split > 0.0) {
    if (options.train_log.empty()) throw app::UsageError("--split needs --train-log");
    return PacketSource::from_log(options.train_log).split(options.split);
  }
  PacketSource train_data = options.train_log.empty()
                                ? PacketSource::simulated(options.seed, options.train_formations,
                                                          options.jitter_mm, options.cameras)
                                : PacketSource::from_log(options.train_log);
  PacketSource test_data = options.test_log.empty()
                               ? PacketSource::simulated(options.test_seed, options.test_formations,
                                                         options.jitter_mm, options.cameras)
                               : PacketSource::from_log(options.test_log);
  return {std::move(train_data), std::move(test_data)};
}

struct GridReport {
  Grid grid{3, 2};
  ev::HoldoutResult result;
  std::size_t test_formations = 0;
  std::uint64_t transitions = 0;
  std::size_t memory_bytes = 0;
  double prediction_us = 0.0;  // mean two-step prediction time
};

GridReport holdout_for_grid(const SamplerConfig& config, const PacketSource& train_data,
                            const PacketSource& test_data) {
  GridReport report;
  report.grid = config.grid;
  const auto stored =
      std::make_shared<const StoredTable>(StoredTable{train(config, train_data), {}});
  const TransitionTable& table = stored->table;
  FieldSize field;
  const std::vector<ev::PredictedTest> test = predict_stream(config, stored, test_data, &field);
  report.result = ev::evaluate_holdout(table.codec(), test, field);
  report.test_formations = test.size();
  report.transitions = table.transitions();
  report.memory_bytes = table.memory_bytes();
  // Prediction time: two steps ahead from every test formation, as the predictor does live.
  Prediction prediction;
  std::vector<std::vector<RobotStateById>> inputs;
  for (const auto& t : test) inputs.push_back(robot_states(t.formation));
  const auto start = std::chrono::steady_clock::now();
  std::size_t runs = 0;
  for (int pass = 0; pass < 20 && !inputs.empty(); ++pass) {
    for (const auto& input : inputs) {
      predict(table, input, 2, prediction);
      ++runs;
    }
  }
  const double elapsed =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  report.prediction_us = runs ? elapsed / static_cast<double>(runs) : 0.0;
  return report;
}

void print_holdout(const GridReport& report) {
  std::printf("Held-out evaluation, grid %s: %zu test formations, table of %llu transitions\n",
              report.grid.to_string().c_str(), report.test_formations,
              static_cast<unsigned long long>(report.transitions));
  std::printf("%-8s %-18s %12s %12s %14s %10s\n", "horizon", "method", "exact state", "exact cell",
              "cells off/robot", "robots");
  for (int h = 0; h < ev::HoldoutResult::max_horizon; ++h) {
    for (std::size_t m = 0; m < ev::all_methods.size(); ++m) {
      const ev::Accuracy& a = report.result.accuracy[static_cast<std::size_t>(h)][m];
      std::printf("%-8d %-18s %11.2f%% %11.2f%% %14.3f %10llu\n", h + 1,
                  ev::to_string(ev::all_methods[m]), 100.0 * a.state_accuracy(),
                  100.0 * a.cell_accuracy(), a.mean_distance(),
                  static_cast<unsigned long long>(a.robots));
    }
  }
  for (int h = 0; h < ev::HoldoutResult::max_horizon; ++h) {
    const ev::Calibration& c = report.result.calibration[static_cast<std::size_t>(h)];
    std::printf(
        "confidence that the whole formation is right, horizon %d: Brier %.4f over %llu "
        "formations\n",
        h + 1, c.brier(), static_cast<unsigned long long>(c.n));
    std::printf("  %-12s %10s %16s %14s\n", "confidence", "formations", "mean confidence",
                "observed");
    for (int b = 0; b < ev::Calibration::bins; ++b) {
      const auto i = static_cast<std::size_t>(b);
      if (c.bin_count[i] == 0) continue;
      std::printf("  [%.1f, %.1f%c %10llu %16.4f %13.2f%%\n", b / 10.0, (b + 1) / 10.0,
                  b == 9 ? ']' : ')', static_cast<unsigned long long>(c.bin_count[i]),
                  c.bin_confidence[i] / double(c.bin_count[i]),
                  100.0 * double(c.bin_hits[i]) / double(c.bin_count[i]));
    }
  }
}

void write_holdout_csv(std::ofstream& accuracy, std::ofstream& reliability,
                       const GridReport& report) {
  for (int h = 0; h < ev::HoldoutResult::max_horizon; ++h) {
    for (std::size_t m = 0; m < ev::all_methods.size(); ++m) {
      const ev::Accuracy& a = report.result.accuracy[static_cast<std::size_t>(h)][m];
      accuracy << report.grid.to_string() << ',' << h + 1 << ','
               << ev::to_string(ev::all_methods[m]) << ',' << a.state_accuracy() << ','
               << a.cell_accuracy() << ',' << a.mean_distance() << ',' << a.robots << '\n';
    }
    const ev::Calibration& c = report.result.calibration[static_cast<std::size_t>(h)];
    for (int b = 0; b < ev::Calibration::bins; ++b) {
      const auto i = static_cast<std::size_t>(b);
      reliability << report.grid.to_string() << ',' << h + 1 << ',' << b << ',' << c.bin_count[i]
                  << ',' << (c.bin_count[i] ? c.bin_confidence[i] / double(c.bin_count[i]) : 0.0)
                  << ',' << (c.bin_count[i] ? double(c.bin_hits[i]) / double(c.bin_count[i]) : 0.0)
                  << ',' << c.brier() << '\n';
    }
  }
}

}  // namespace

int run_holdout(const EvaluateOptions& options, const std::vector<std::string>& grids) {
  const auto [train_data, test_data] = holdout_data(options);
  std::ofstream accuracy =
      open_csv(options, grids.size() > 1 ? "grid-sweep-accuracy.csv" : "holdout-accuracy.csv");
  accuracy << "grid,horizon,method,state_accuracy,cell_accuracy,mean_cell_distance,robots\n";
  std::ofstream reliability = open_csv(
      options, grids.size() > 1 ? "grid-sweep-reliability.csv" : "holdout-reliability.csv");
  reliability << "grid,horizon,bin,formations,mean_confidence,observed_frequency,brier\n";
  std::vector<GridReport> reports;
  for (const std::string& grid : grids) {
    app::ModelOptions model = options.model;
    model.grid = grid;
    reports.push_back(holdout_for_grid(model.sampler_config(), train_data, test_data));
    print_holdout(reports.back());
    write_holdout_csv(accuracy, reliability, reports.back());
    std::printf("\n");
  }
  if (grids.size() > 1) {
    std::ofstream sweep = open_csv(options, "grid-sweep.csv");
    sweep << "grid,states,transitions,table_memory_bytes,prediction_us,model_cell_accuracy_h1,"
             "persistence_cell_accuracy_h1,constant_velocity_cell_accuracy_h1,model_mean_distance_"
             "h1\n";
    std::printf("Grid sweep (horizon 1)\n%-6s %12s %12s %14s %14s %12s %12s %12s\n", "grid",
                "states", "transitions", "table memory", "predict 2 (us)", "model cell",
                "persist cell", "const-v cell");
    for (const GridReport& r : reports) {
      const auto& h1 = r.result.accuracy[0];
      const StateCodec codec(r.grid);
      std::printf("%-6s %12u %12llu %11.1f KiB %14.3f %11.2f%% %11.2f%% %11.2f%%\n",
                  r.grid.to_string().c_str(), codec.state_count(),
                  static_cast<unsigned long long>(r.transitions), r.memory_bytes / 1024.0,
                  r.prediction_us, 100 * h1[0].cell_accuracy(), 100 * h1[1].cell_accuracy(),
                  100 * h1[2].cell_accuracy());
      sweep << r.grid.to_string() << ',' << codec.state_count() << ',' << r.transitions << ','
            << r.memory_bytes << ',' << r.prediction_us << ',' << h1[0].cell_accuracy() << ','
            << h1[1].cell_accuracy() << ',' << h1[2].cell_accuracy() << ',' << h1[0].mean_distance()
            << '\n';
    }
  }
  return 0;
}

}  // namespace ssl_formation::evaluate
