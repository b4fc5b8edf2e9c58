// ssl-evaluate paper: the paper's own protocol on its simulated opponent.
#include "evaluate_internal.hpp"

namespace ssl_formation::evaluate {

using namespace detail;

int run_paper(const EvaluateOptions& options) {
  // The paper's protocol is the paper's model on step sampling, whatever --model says.
  app::ModelOptions paper = options.model;
  paper.model = "paper";
  SamplerConfig config = paper.sampler_config();
  const auto started = std::chrono::steady_clock::now();
  // The paper's protocol trains one table, on the logs one after the other (each its own
  // stream) or on the paper's simulated opponent.
  Streams training_data;
  if (options.train_logs.empty()) {
    training_data.push_back(
        in_memory(paper_simulation(options, options.seed, options.train_formations)));
  } else {
    for (const std::string& log : options.train_logs) {
      training_data.push_back(LogFile(log).stream());
    }
  }
  Training training(config, TransitionTable(config.grid));
  VisionCount counted(training);
  for (const ev::EventStream& stream : training_data) {
    counted.start_new_stream();
    stream(counted);
  }
  const std::size_t packets = counted.packets();
  const FieldSize field = training.sampler().field();
  const std::uint64_t training_samples = training.samples();
  const StoredTable stored = training.stored_table();
  const TransitionTable& table = stored.table;

  std::vector<ev::PlayStates> plays;
  for (int p = 0; p < simulation::play_count; ++p) {
    std::vector<std::vector<Point>> positions;
    for (int f = 0; f < simulation::formations_per_play; ++f) {
      const auto& team = simulation::play_formation(p, f);
      positions.emplace_back(team.begin(), team.end());
    }
    plays.push_back(ev::play_states(table.codec(), field, positions));
  }

  // The test formations: the paper's random formations, every robot anywhere, velocity 0.
  std::mt19937_64 random(options.test_seed);
  std::uniform_real_distribution<double> x(-field.length_mm / 2, field.length_mm / 2);
  std::uniform_real_distribution<double> y(-field.width_mm / 2, field.width_mm / 2);
  ev::PaperSummary summary;
  CsvFile csv(options, "paper-running-averages.csv");
  csv << "test,count_per_play,distance_per_play,count_per_formation,distance_per_formation,"
         "confidence_1,confidence_2\n";
  for (int t = 0; t < options.tests; ++t) {
    std::vector<FormationRobot> robots(simulation::robots_per_team);
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
      static_cast<unsigned long long>(training_samples), packets,
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

}  // namespace ssl_formation::evaluate
