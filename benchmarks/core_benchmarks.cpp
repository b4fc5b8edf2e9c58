// Core costs: prediction, table increment, sampling. Run: build/benchmarks/core_benchmarks
// (scripts/bench.sh runs it with repetitions and prints medians).

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <memory>
#include <random>

#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/motion_model/set_play_memory.hpp"
#include "ssl_formation/paper_model/predictor.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

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

// Rolling prediction, as the predictor runs it with --sampling frame: 11 robots moving smoothly,
// one camera at 60 Hz, a formation and a prediction `horizon` steps of 0.5 s ahead at every
// frame, from a table trained on the same kind of motion. Frames are VisionFrames (decoded), so
// the time is the pipeline's: sampling, the state history, prediction and the context.
void BM_RollingPrediction(benchmark::State& state) {
  const sf::Grid grid = state.range(0) == 0 ? sf::Grid(3, 2) : sf::Grid(12, 9);
  const int horizon = static_cast<int>(state.range(1));
  const bool motion = state.range(2) != 0;
  constexpr int robots = 11;
  constexpr double frame_s = 1.0 / 60.0;
  // Every robot circles its own spot; two minutes of frames.
  const auto frame_at = [&](int i, double offset_s) {
    sf::DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = offset_s + i * frame_s;
    const double t = i * frame_s;
    for (std::uint32_t id = 0; id < robots; ++id) {
      const double phase = 0.4 * t + id;
      spec.yellow.push_back(
          {id,
           {-4000.0 + 800.0 * id + 1200.0 * std::cos(phase), 2000.0 * std::sin(phase + 0.5 * id)}});
    }
    sf::VisionFrame frame;
    sf::to_vision_frame(sf::make_detection_packet(spec), frame);
    return frame;
  };
  sf::PredictionConfig config;
  config.sampler.grid = grid;
  config.sampler.step_s = 0.5;
  config.sampler.sampling = sf::Sampling::frame;
  config.horizon = horizon;
  config.model = motion ? sf::ModelKind::motion : sf::ModelKind::paper;
  std::optional<sf::MotionTable> motion_table;
  if (motion) {
    sf::MotionConfig motion_config;
    motion_config.step_s = config.sampler.step_s;
    motion_config.horizons = 3;
    motion_table.emplace(motion_config);
  }
  sf::Training training(config.sampler, sf::TransitionTable(grid), 0, std::move(motion_table));
  for (int i = 0; i < 120 * 60; ++i) training.add(frame_at(i, 0.0));
  std::vector<sf::VisionFrame> frames;
  for (int i = 0; i < 60 * 60; ++i) frames.push_back(frame_at(i, 0.0));

  std::uint64_t predictions = 0;
  sf::PredictionPipeline pipeline(
      config, [&](const sf::PredictedFormation& p) { predictions += p.prediction.steps.size(); });
  sf::TableMetadata metadata;
  metadata.step_s = config.sampler.step_s;
  metadata.field = training.sampler().field();
  pipeline.set_table(std::make_shared<const sf::StoredTable>(training.stored_table(metadata)));
  std::size_t i = 0;
  double offset_s = 1000.0;
  for (auto _ : state) {
    sf::VisionFrame& frame = frames[i];
    // Keep the data clock moving forward across passes over the frames.
    frame.detection.t_capture = offset_s + static_cast<double>(i) * frame_s;
    pipeline.add(frame);
    if (++i == frames.size()) {
      i = 0;
      offset_s += 100.0;
    }
  }
  state.SetLabel(std::string(motion ? "motion, " : "paper, ") + grid.to_string() + ", " +
                 std::to_string(training.table_summary().transitions) + " transitions");
  benchmark::DoNotOptimize(predictions);
}
// Args: grid (0 = 3x2, 1 = 12x9), horizon in steps, model (0 = paper, 1 = motion).
BENCHMARK(BM_RollingPrediction)
    ->ArgNames({"grid12x9", "horizon", "motion"})
    ->Args({0, 1, 0})
    ->Args({0, 3, 0})
    ->Args({1, 1, 0})
    ->Args({1, 3, 0})
    ->Args({1, 3, 1});

// A recall at a kick-off of the opponent's from a memory of `episodes` kick-offs (a full one
// holds SetPlayMemory::max_episodes), each 2 s prepared, 3 s taken and 1.5 s over, 11 robots
// at places that vary by 300 mm from run to run: what the predictor adds at each frame of a
// kick-off (only then).
void BM_SetPlayRecall(benchmark::State& state) {
  const auto episodes = static_cast<int>(state.range(0));
  std::mt19937 random(7);
  std::uniform_real_distribution<double> vary(-300.0, 300.0);
  sf::SetPlayMemory memory;
  for (int e = 0; e < episodes; ++e) {
    sf::SetPlayEpisode episode;
    std::array<sf::Point, 11> place{};
    for (std::size_t id = 0; id < place.size(); ++id) {
      place[id] = {-500.0 * static_cast<double>(id % 6) + vary(random),
                   -2500.0 + 500.0 * static_cast<double>(id) + vary(random)};
    }
    for (int i = 0; i < 65; ++i) {
      sf::SetPlaySnapshot s;
      s.offset_ms = 100 * i;
      s.stage = i < 20   ? sf::SetPlayStage::preparation
                : i < 50 ? sf::SetPlayStage::taken
                         : sf::SetPlayStage::over;
      s.since_command_ms = i < 20 ? 100 * i : 100 * (i - 20);
      for (std::size_t id = 0; id < place.size(); ++id) {
        s.seen |= 1U << id;
        const double run = i < 20 ? 0.0 : 40.0 * (i - 20);
        s.position[id] = {static_cast<std::int32_t>(place[id].x + run * (id % 3 == 0)),
                          static_cast<std::int32_t>(place[id].y)};
      }
      episode.snapshots.push_back(s);
    }
    memory.add(std::move(episode));
  }
  sf::Formation now;
  for (std::uint32_t id = 0; id < 11; ++id) {
    sf::FormationRobot robot;
    robot.robot_id = id;
    robot.position = {-500.0 * (id % 6), -2500.0 + 500.0 * id};
    now.robots.push_back(robot);
  }
  sf::SetPlayAdvice advice;
  double since_s = 0.0;
  for (auto _ : state) {
    memory.recall(now, sf::SetPlayStage::taken, since_s, 0.5, 3, advice);
    benchmark::DoNotOptimize(advice);
    since_s = since_s >= 2.9 ? 0.0 : since_s + 1.0 / 60.0;
  }
  state.SetLabel(std::to_string(memory.snapshots()) + " snapshots");
}
BENCHMARK(BM_SetPlayRecall)->ArgName("kickoffs")->Arg(8)->Arg(64)->Arg(512);

}  // namespace

BENCHMARK_MAIN();
