#include "ssl_formation/evaluate/evaluate.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <fstream>

#include "ssl_formation/evaluation/evaluation.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/evaluation/position_evaluation.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/files/real_log_shape.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/pipeline/training.hpp"

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
  // Several logs one after the other (for the paper protocol, which trains one table).
  static PacketSource from_logs(const std::vector<std::string>& paths) {
    PacketSource source;
    for (const std::string& path : paths) {
      PacketSource one = from_log(path);
      source.packets_.insert(source.packets_.end(), std::make_move_iterator(one.packets_.begin()),
                             std::make_move_iterator(one.packets_.end()));
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
  // The paper's protocol is the paper's model on step sampling, whatever --model says.
  app::ModelOptions paper = options.model;
  paper.model = "paper";
  SamplerConfig config = paper.sampler_config();
  const auto started = std::chrono::steady_clock::now();
  const PacketSource training_data =
      options.train_logs.empty() ? PacketSource::simulated(options.seed, options.train_formations,
                                                           options.jitter_mm, options.cameras)
                                 : PacketSource::from_logs(options.train_logs);
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

using Streams = std::vector<std::vector<SSL_WrapperPacket>>;

// The training and test streams the options describe: logs (each its own stream, split in
// time with --split) or the simulated vision of two seeds.
std::pair<Streams, Streams> holdout_streams(const EvaluateOptions& options) {
  Streams train;
  Streams test;
  if (options.split > 0.0) {
    if (options.train_logs.empty()) throw app::UsageError("--split needs --train-log");
    for (const std::string& log : options.train_logs) {
      auto [head, tail] = PacketSource::from_log(log).split(options.split);
      train.push_back(head.packets());
      test.push_back(tail.packets());
    }
  } else {
    for (const std::string& log : options.train_logs) {
      train.push_back(PacketSource::from_log(log).packets());
    }
    if (train.empty()) {
      train.push_back(PacketSource::simulated(options.seed, options.train_formations,
                                              options.jitter_mm, options.cameras)
                          .packets());
    }
  }
  for (const std::string& log : options.test_logs) {
    test.push_back(PacketSource::from_log(log).packets());
  }
  if (test.empty()) {
    test.push_back(PacketSource::simulated(options.test_seed, options.test_formations,
                                           options.jitter_mm, options.cameras)
                       .packets());
  }
  return {std::move(train), std::move(test)};
}

// One configuration's evaluation: its horizons, from `steps` steps of `step_s`.
struct Section {
  double step_s = 0.0;
  ev::PositionEvaluation evaluation;
};

struct GridReport {
  Grid grid{3, 2};
  std::vector<Section> sections;  // one per --horizons entry, then the chains of --step
  double prediction_us = 0.0;     // mean two-step prediction time of the chains' table
};

// Two-step predictions from the test formations, timed, as the predictor does live.
double time_predictions(const TransitionTable& table, const Streams& test,
                        const SamplerConfig& config) {
  std::vector<std::vector<RobotStateById>> inputs;
  FormationSampler sampler(config, [&](const FormationSample& sample) {
    if (inputs.size() < 5000) inputs.push_back(robot_states(sample.formation));
  });
  for (const auto& stream : test) {
    sampler.start_new_stream();
    for (const auto& packet : stream) sampler.add(packet);
  }
  Prediction prediction;
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
  return runs ? elapsed / static_cast<double>(runs) : 0.0;
}

GridReport holdout_for_grid(const EvaluateOptions& options, const std::string& grid,
                            const Streams& train, const Streams& test) {
  app::ModelOptions model = options.model;
  model.grid = grid;
  const SamplerConfig base = model.sampler_config();
  GridReport report;
  report.grid = base.grid;
  const auto evaluate = [&](double step_s, int steps) {
    ev::PositionEvaluationConfig config;
    config.sampler = base;
    config.sampler.step_s = step_s;
    config.steps = steps;
    config.velocity_window_s = options.velocity_window_s;
    config.model = model.parsed_model();
    config.recalibration = app::recalibration_settings(options.recalibration_half_life_s);
    report.sections.push_back({step_s, ev::evaluate_positions(config, train, test)});
  };
  for (const double horizon_s : options.horizons) evaluate(horizon_s, 1);
  evaluate(base.step_s, options.chain_steps);
  report.prediction_us =
      time_predictions(report.sections.back().evaluation.table->table, test, base);
  return report;
}

const char* quantity_name(bool robot) { return robot ? "robot" : "formation"; }

void print_holdout(const GridReport& report, const SamplerConfig& base) {
  const ev::PositionEvaluation& chains = report.sections.back().evaluation;
  std::printf(
      "Held-out evaluation, grid %s, %s sampling: %llu test formations; the chains' table: %llu "
      "transitions from %llu formations\n",
      report.grid.to_string().c_str(), std::string(to_string(base.sampling)).c_str(),
      static_cast<unsigned long long>(chains.test_formations),
      static_cast<unsigned long long>(chains.transitions),
      static_cast<unsigned long long>(chains.train_formations));
  std::printf("%9s %5s %-25s %11s %11s %9s %9s %9s %9s %9s\n", "horizon", "steps", "method",
              "exact state", "exact cell", "cells off", "mean mm", "median mm", "p90 mm", "robots");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.horizons.size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.horizons[h];
      for (std::size_t m = 0; m < ev::all_position_methods.size(); ++m) {
        const ev::Accuracy& a = score.cells[m];
        std::printf("%7.2f s %5zu %-25s %10.2f%% %10.2f%% %9.3f %9.1f %9.1f %9.1f %9llu\n",
                    score.horizon_s, h + 1,
                    std::string(ev::to_string(ev::all_position_methods[m])).c_str(),
                    100.0 * a.state_accuracy(), 100.0 * a.cell_accuracy(), a.mean_distance(),
                    score.error[m].mean(), score.error[m].median(), score.error[m].percentile(90),
                    static_cast<unsigned long long>(a.robots));
      }
    }
  }
  std::printf("Calibration of the model's probabilities (10 equal bins):\n");
  std::printf("%9s %5s %-10s %9s %9s %12s\n", "horizon", "steps", "quantity", "Brier", "ECE",
              "predictions");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.horizons.size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.horizons[h];
      for (const bool robot : {true, false}) {
        const ev::Calibration& c = robot ? score.robot : score.formation;
        std::printf("%7.2f s %5zu %-10s %9.4f %9.4f %12llu\n", score.horizon_s, h + 1,
                    quantity_name(robot), c.brier(), ev::expected_calibration_error(c),
                    static_cast<unsigned long long>(c.n));
      }
    }
  }
  if (report.sections.front().evaluation.horizons.front().radii.robots == 0) return;
  std::printf("The model's radii: how often the robot was within them (aim: 50%% and 90%%):\n");
  std::printf("%9s %5s %12s %12s %12s\n", "horizon", "steps", "within r50", "within r90", "robots");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.horizons.size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.horizons[h];
      std::printf("%7.2f s %5zu %11.1f%% %11.1f%% %12llu\n", score.horizon_s, h + 1,
                  100.0 * score.radii.share50(), 100.0 * score.radii.share90(),
                  static_cast<unsigned long long>(score.radii.robots));
    }
  }
}

void write_holdout_csv(std::ofstream& accuracy, std::ofstream& calibration,
                       std::ofstream& reliability, const GridReport& report) {
  const std::string grid = report.grid.to_string();
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.horizons.size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.horizons[h];
      for (std::size_t m = 0; m < ev::all_position_methods.size(); ++m) {
        const ev::Accuracy& a = score.cells[m];
        accuracy << grid << ',' << h + 1 << ',' << score.horizon_s << ','
                 << ev::to_string(ev::all_position_methods[m]) << ',' << a.state_accuracy() << ','
                 << a.cell_accuracy() << ',' << a.mean_distance() << ',' << score.error[m].mean()
                 << ',' << score.error[m].median() << ',' << score.error[m].percentile(90) << ','
                 << a.robots << '\n';
      }
      for (const bool robot : {true, false}) {
        const ev::Calibration& c = robot ? score.robot : score.formation;
        calibration << grid << ',' << h + 1 << ',' << score.horizon_s << ",model,"
                    << quantity_name(robot) << ',' << c.brier() << ','
                    << ev::expected_calibration_error(c) << ',' << c.n << ','
                    << score.radii.share50() << ',' << score.radii.share90() << '\n';
        for (std::size_t b = 0; b < c.bin_count.size(); ++b) {
          const auto n = static_cast<double>(c.bin_count[b]);
          reliability << grid << ',' << h + 1 << ',' << score.horizon_s << ','
                      << quantity_name(robot) << ',' << b << ',' << c.bin_count[b] << ','
                      << (n > 0 ? c.bin_confidence[b] / n : 0.0) << ','
                      << (n > 0 ? static_cast<double>(c.bin_hits[b]) / n : 0.0) << '\n';
        }
      }
    }
  }
}

}  // namespace

std::vector<double> parse_horizons(const std::string& text) {
  std::vector<double> horizons;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    double value = 0.0;
    const auto [rest, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || error != std::errc() || rest != item.data() + item.size() ||
        !(value > 0.0) || value > 600.0) {
      throw app::UsageError(
          "--horizons takes positive seconds separated by commas (e.g. "
          "0.2,0.5,1,2), not '" +
          text + "'");
    }
    horizons.push_back(value);
    begin = end + 1;
  }
  return horizons;
}

int run_holdout(const EvaluateOptions& options, const std::vector<std::string>& grids) {
  if (options.chain_steps < 1 || options.chain_steps > 10) {
    throw app::UsageError("--chain-steps must be 1 to 10");
  }
  if (!(options.velocity_window_s > 0.0)) {
    throw app::UsageError("--velocity-window must be a positive number of seconds");
  }
  const SamplerConfig base = options.model.sampler_config();
  const auto [train, test] = holdout_streams(options);
  const std::string prefix = grids.size() > 1 ? "grid-sweep-" : "holdout-";
  std::ofstream accuracy = open_csv(options, prefix + "accuracy.csv");
  accuracy << "grid,horizon_steps,horizon_s,method,state_accuracy,cell_accuracy,"
              "mean_cell_distance,mean_error_mm,median_error_mm,p90_error_mm,robots\n";
  std::ofstream calibration = open_csv(options, prefix + "calibration.csv");
  calibration << "grid,horizon_steps,horizon_s,method,quantity,brier,ece,predictions,"
                 "within_radius_50,within_radius_90\n";
  std::ofstream reliability = open_csv(options, prefix + "reliability.csv");
  reliability << "grid,horizon_steps,horizon_s,quantity,bin,count,mean_confidence,"
                 "observed_frequency\n";
  std::vector<GridReport> reports;
  for (const std::string& grid : grids) {
    reports.push_back(holdout_for_grid(options, grid, train, test));
    print_holdout(reports.back(), base);
    write_holdout_csv(accuracy, calibration, reliability, reports.back());
    std::printf("\n");
  }
  if (grids.size() > 1) {
    std::ofstream sweep = open_csv(options, "grid-sweep.csv");
    sweep << "grid,states,transitions,table_memory_bytes,prediction_us,model_cell_accuracy_h1,"
             "persistence_cell_accuracy_h1,constant_velocity_cell_accuracy_h1,"
             "damped_constant_velocity_cell_accuracy_h1,model_mean_error_mm_h1\n";
    std::printf("Grid sweep (one step of --step)\n%-6s %12s %12s %14s %14s %12s %12s %12s\n",
                "grid", "states", "transitions", "table memory", "predict 2 (us)", "model cell",
                "persist cell", "const-v cell");
    for (const GridReport& r : reports) {
      const ev::PositionEvaluation& chains = r.sections.back().evaluation;
      const ev::HorizonScore& h1 = chains.horizons.front();
      const StateCodec codec(r.grid);
      std::printf("%-6s %12u %12llu %11.1f KiB %14.3f %11.2f%% %11.2f%% %11.2f%%\n",
                  r.grid.to_string().c_str(), codec.state_count(),
                  static_cast<unsigned long long>(chains.transitions),
                  static_cast<double>(chains.table_memory_bytes) / 1024.0, r.prediction_us,
                  100 * h1.cells[0].cell_accuracy(), 100 * h1.cells[1].cell_accuracy(),
                  100 * h1.cells[2].cell_accuracy());
      sweep << r.grid.to_string() << ',' << codec.state_count() << ',' << chains.transitions << ','
            << chains.table_memory_bytes << ',' << r.prediction_us << ','
            << h1.cells[0].cell_accuracy() << ',' << h1.cells[1].cell_accuracy() << ','
            << h1.cells[2].cell_accuracy() << ',' << h1.cells[3].cell_accuracy() << ','
            << h1.error[0].mean() << '\n';
    }
  }
  return 0;
}

// ---- as-real-log

int run_as_real_log(const EvaluateOptions& options) {
  if (options.from_log.empty() || options.write_log.empty()) {
    throw app::UsageError("as-real-log needs --from-log FILE and --write-log FILE");
  }
  std::optional<RealLogMess> mess = parse_real_log_mess(options.mess);
  if (!mess) {
    throw app::UsageError("--mess must be none, all or a comma-separated list of " +
                          std::string(real_log_mess_names) + ", not '" + options.mess + "'");
  }
  mess->seed = options.seed;
  const Result<RealLogCounts> counts =
      write_as_real_log(options.from_log, options.write_log, *mess);
  if (!counts) {
    spdlog::error("{}", counts.error().message);
    return 1;
  }
  std::printf(
      "%s: %llu vision packets over %.1f s rewritten as %llu half-field packets (camera "
      "id 0, no geometry), mess: %s, %llu ghost detections\n",
      options.write_log.c_str(), static_cast<unsigned long long>(counts->packets_read),
      counts->recording_s, static_cast<unsigned long long>(counts->packets_written),
      options.mess.c_str(), static_cast<unsigned long long>(counts->ghost_detections));
  return 0;
}

}  // namespace ssl_formation::evaluate
