// Core costs: prediction, table increment, sampling. Run: build/benchmarks/core_benchmarks
// (scripts/bench.sh runs it with repetitions and prints medians).

#include <benchmark/benchmark.h>

#include <random>

#include "ssl_formation/predictor.hpp"
#include "ssl_formation/sampler.hpp"
#include "ssl_formation/transition_table.hpp"
#include "ssl_formation/vision_packet.hpp"

namespace sf = ssl_formation;

namespace {

// A table trained on random walks of `robots` robots, the way the sampler would count them:
// each robot moves to a neighbouring cell or stays, the centroid follows the mean.
struct TrainedModel {
  sf::TransitionTable table;
  std::vector<std::vector<sf::RobotStateById>> formations;  // test formations
};

TrainedModel train_random_walks(sf::Grid grid, int robots, int samples, unsigned seed) {
  TrainedModel model{sf::TransitionTable(grid), {}};
  const sf::FieldSize field;
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> step(-1, 1);
  std::uniform_real_distribution<double> x(-4500, 4500);
  std::uniform_real_distribution<double> y(-3000, 3000);
  const sf::StateCodec& codec = model.table.codec();
  std::vector<sf::Point> positions(static_cast<std::size_t>(robots));
  for (auto& p : positions) p = {x(random), y(random)};
  std::optional<sf::Formation> previous;
  const double cell_x = field.length_mm / grid.length();
  const double cell_y = field.width_mm / grid.width();
  for (int s = 0; s < samples; ++s) {
    for (sf::Point& p : positions) {
      p.x = std::clamp(p.x + step(random) * cell_x, -4499.0, 4499.0);
      p.y = std::clamp(p.y + step(random) * cell_y, -2999.0, 2999.0);
    }
    sf::Formation formation = sf::FormationSampler::formation_at(codec, field, positions,
                                                                 previous ? &*previous : nullptr);
    if (previous) {
      for (const auto& robot : formation.robots) {
        model.table.add(previous->find(robot.robot_id)->state, robot.state);
      }
    }
    if (s % 97 == 0) model.formations.push_back(sf::robot_states(formation));
    previous = std::move(formation);
  }
  return model;
}

void BM_Predict(benchmark::State& state) {
  const sf::Grid grid = state.range(0) == 0 ? sf::Grid(3, 2) : sf::Grid(12, 9);
  const int robots = static_cast<int>(state.range(1));
  const int horizon = static_cast<int>(state.range(2));
  static std::map<std::pair<int, int>, TrainedModel> cache;
  auto key = std::pair{static_cast<int>(state.range(0)), robots};
  if (!cache.count(key)) cache.emplace(key, train_random_walks(grid, robots, 200000, 42));
  const TrainedModel& model = cache.at(key);
  sf::Prediction prediction;
  std::size_t i = 0;
  for (auto _ : state) {
    sf::predict(model.table, model.formations[i++ % model.formations.size()], horizon, prediction);
    benchmark::DoNotOptimize(prediction.steps.back().confidence);
  }
  state.SetLabel(grid.to_string() + (model.table.is_dense() ? " dense" : " sparse"));
}
// Args: grid (0 = 3x2, 1 = 12x9), robots, horizon.
BENCHMARK(BM_Predict)
    ->ArgNames({"grid12x9", "robots", "horizon"})
    ->Args({0, 6, 1})
    ->Args({0, 6, 2})
    ->Args({0, 11, 1})
    ->Args({0, 11, 2})
    ->Args({1, 6, 1})
    ->Args({1, 6, 2})
    ->Args({1, 11, 1})
    ->Args({1, 11, 2});

void BM_TableIncrement(benchmark::State& state) {
  const sf::Grid grid = state.range(0) == 0 ? sf::Grid(3, 2) : sf::Grid(12, 9);
  sf::TransitionTable table(grid);
  const sf::StateCodec& codec = table.codec();
  std::mt19937 random(1);
  std::uniform_int_distribution<sf::StateIndex> cell(0, codec.cell_count() - 1);
  std::vector<std::pair<sf::StateIndex, sf::StateIndex>> transitions(4096);
  for (auto& [from, to] : transitions) {
    from = codec.compose(cell(random), cell(random), cell(random));
    to = codec.compose(cell(random), cell(random), codec.position_id(from));
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& [from, to] = transitions[i++ & 4095];
    benchmark::DoNotOptimize(table.add(from, to));
  }
  state.SetLabel(grid.to_string() + (table.is_dense() ? " dense" : " sparse"));
}
BENCHMARK(BM_TableIncrement)->ArgName("grid12x9")->Arg(0)->Arg(1);

// Sampling and state encoding per packet: 6 yellow + 6 blue robots, `cameras` cameras at 60 Hz,
// one formation every 2 s of data time. Items are opponent robots processed.
void BM_SamplerPerPacket(benchmark::State& state) {
  const int cameras = static_cast<int>(state.range(0));
  std::vector<SSL_WrapperPacket> packets;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> x(-4500, 4500);
  std::uniform_real_distribution<double> y(-3000, 3000);
  for (int frame = 0; frame < 600; ++frame) {
    for (int camera = 0; camera < cameras; ++camera) {
      sf::DetectionFrameSpec spec;
      spec.camera_id = static_cast<std::uint32_t>(camera);
      spec.frame_number = static_cast<std::uint32_t>(frame);
      spec.t_capture = frame / 60.0;
      for (std::uint32_t id = 0; id < 6; ++id) {
        if (static_cast<int>(id) % cameras != camera) continue;  // each robot seen by one camera
        spec.yellow.push_back({id, {x(random), y(random)}});
        spec.blue.push_back({id, {x(random), y(random)}});
      }
      packets.push_back(sf::make_detection_packet(spec));
    }
  }
  sf::SamplerConfig config;
  std::size_t samples = 0;
  sf::FormationSampler sampler(config, [&](const sf::FormationSample&) { ++samples; });
  std::size_t i = 0;
  double clock_offset = 0.0;
  for (auto _ : state) {
    SSL_WrapperPacket& packet = packets[i];
    // Keep the data clock moving forward across passes over the packet list.
    packet.mutable_detection()->set_t_capture(clock_offset + (i / cameras) / 60.0);
    sampler.add(packet);
    if (++i == packets.size()) {
      i = 0;
      clock_offset += 10.0;
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 6 / cameras);
  benchmark::DoNotOptimize(samples);
}
BENCHMARK(BM_SamplerPerPacket)->ArgName("cameras")->Arg(1)->Arg(4);

}  // namespace

BENCHMARK_MAIN();
