// Offline training throughput against its floor, a bare loop that only reads and parses the same
// log. Frames are SSL-Vision detection frames of 6 yellow + 6 blue robots and a ball at 60 Hz.
// Run: build/benchmarks/log_benchmarks (scripts/bench.sh prints the ratio).

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <random>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/files/real_log_shape.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace sf = ssl_formation;

namespace {

constexpr int frames_in_log = 200000;

// Writes the benchmark log once per process (plain and gzip), in the temp folder.
const std::filesystem::path& log_path(bool gzip) {
  static const auto base =
      std::filesystem::temp_directory_path() / ("sslf-bench-" + std::to_string(::getpid()));
  static const std::filesystem::path plain = base.string() + ".log";
  static const std::filesystem::path compressed = base.string() + ".log.gz";
  static const bool written = [] {
    std::mt19937 random(5);
    std::normal_distribution<double> step(0.0, 15.0);
    std::vector<sf::Point> yellow(6);
    std::vector<sf::Point> blue(6);
    for (int i = 0; i < 6; ++i) {
      yellow[static_cast<std::size_t>(i)] = {-3000.0 + 1000 * i, -1000.0};
      blue[static_cast<std::size_t>(i)] = {-3000.0 + 1000 * i, 1000.0};
    }
    for (const auto& path : {plain, compressed}) {
      auto writer = sf::LogWriter::create(path);
      if (!writer) throw std::runtime_error(writer.error().message);
      std::mt19937 frame_random(6);
      for (int frame = 0; frame < frames_in_log; ++frame) {
        sf::DetectionFrameSpec spec;
        spec.frame_number = static_cast<std::uint32_t>(frame);
        spec.t_capture = 1700000000.0 + frame / 60.0;
        for (std::uint32_t id = 0; id < 6; ++id) {
          auto& y = yellow[id];
          auto& b = blue[id];
          y = {std::clamp(y.x + step(frame_random), -4500.0, 4500.0),
               std::clamp(y.y + step(frame_random), -3000.0, 3000.0)};
          b = {std::clamp(b.x + step(frame_random), -4500.0, 4500.0),
               std::clamp(b.y + step(frame_random), -3000.0, 3000.0)};
          spec.yellow.push_back({id, y});
          spec.blue.push_back({id, b});
        }
        spec.balls.push_back({0.0, 0.0});
        if (frame % 180 == 0) {
          SSL_WrapperPacket packet = sf::make_detection_packet(spec);
          sf::fill_geometry(*packet.mutable_geometry(), sf::FieldSize{9000, 6000});
          writer->write_vision(packet, static_cast<std::int64_t>(spec.t_capture * 1e9));
        } else {
          writer->write_vision(sf::make_detection_packet(spec),
                               static_cast<std::int64_t>(spec.t_capture * 1e9));
        }
      }
      if (!writer->close()) throw std::runtime_error(writer->error());
    }
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove(plain, ignored);
      std::filesystem::remove(compressed, ignored);
    });
    return true;
  }();
  (void)written;
  return gzip ? compressed : plain;
}

std::uint32_t frame_number_of(const sf::VisionFrame& frame) { return frame.detection.frame_number; }
std::uint32_t frame_number_of(const SSL_WrapperPacket& packet) {
  return packet.detection().frame_number();
}

// The isal argument of the reading benchmarks: a .log.gz inflated by zlib (0) or ISA-L (1).
sf::Inflater inflater_of(std::int64_t isal) {
  return isal ? sf::Inflater::isal : sf::Inflater::zlib;
}

// Reads every vision packet of `path`, nothing else; bytes are the log's uncompressed ones. The
// label is `name` and, for a .log.gz, the inflater.
template <typename Frame>
void read_vision(benchmark::State& state, const std::filesystem::path& path, sf::Inflater inflater,
                 const std::string& name) {
  std::int64_t frames = 0;
  std::int64_t bytes = 0;
  Frame frame;
  for (auto _ : state) {
    auto reader = sf::LogReader::open(path, inflater).value();  // throws with the reason
    while (reader.next_vision(frame)) {
      benchmark::DoNotOptimize(frame_number_of(frame));
      ++frames;
    }
    bytes += static_cast<std::int64_t>(reader.offset());
  }
  state.SetItemsProcessed(frames);
  state.SetBytesProcessed(bytes);
  if (path.extension() != ".gz") {
    state.SetLabel(name);
  } else {
    state.SetLabel(name +
                   (inflater == sf::Inflater::isal ? ", ISA-L's inflate" : ", zlib's inflate"));
  }
}

// The floor: read every vision packet, nothing else. Into a VisionFrame (BM_ReadAndParse) as
// offline training reads it (detection frames decoded straight from the bytes), or into an
// SSL_WrapperPacket (BM_ReadAndParseProtobuf): protobuf's full parse, what offline training read
// through before the direct decoder. range(0): .log or .log.gz; range(1): the inflater.
template <typename Frame>
void BM_Read(benchmark::State& state) {
  const bool gzip = state.range(0) != 0;
  read_vision<Frame>(state, log_path(gzip), inflater_of(state.range(1)), gzip ? ".log.gz" : ".log");
}

// Offline training: the same reading feeding the Training the live trainer uses; range(1) chooses
// the sampling (0: a formation every 2 s, the paper's; 1: a formation at every frame, each
// counting the transition from 0.5 s earlier; 2: the same plus the motion model's rows for 3
// horizons, what `ssl-trainer --from-log` does by default).
void BM_OfflineTraining(benchmark::State& state) {
  const auto& path = log_path(state.range(0) != 0);
  const bool rolling = state.range(1) != 0;
  const bool motion = state.range(1) == 2;
  std::int64_t frames = 0;
  sf::VisionFrame frame;
  std::uint64_t transitions = 0;  // kept so the training cannot be optimised away
  for (auto _ : state) {
    sf::SamplerConfig config;
    config.step_s = rolling ? 0.5 : 2.0;
    config.sampling = rolling ? sf::Sampling::frame : sf::Sampling::step;
    std::optional<sf::MotionTable> motion_table;
    if (motion) {
      sf::MotionConfig motion_config;
      motion_config.step_s = config.step_s;
      motion_config.horizons = 3;
      motion_table.emplace(motion_config);
    }
    sf::Training training(config, sf::TransitionTable(config.grid), 0, std::move(motion_table));
    auto reader = sf::LogReader::open(path).value();  // throws with the reason
    while (reader.next_vision(frame)) {
      training.add(frame);
      ++frames;
    }
    transitions = training.table_summary().transitions;
  }
  state.SetItemsProcessed(frames);
  benchmark::DoNotOptimize(transitions);
  state.SetLabel(std::string(state.range(0) ? ".log.gz" : ".log") +
                 (motion    ? ", frame sampling + motion model"
                  : rolling ? ", frame sampling"
                            : ", step sampling"));
}
BENCHMARK(BM_OfflineTraining)
    ->ArgNames({"gzip", "frame"})
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({0, 2})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond);  // CPU time: one core

// Offline training as `ssl-trainer --from-log` runs it by default (frame sampling, the motion
// model's 3 horizons of 0.5 s) on a recorded match given by SSLF_BENCH_RECORDING (an
// uncompressed .log; scripts/bench.sh passes the shared grSim recording A). A real feed spreads
// a team over several cameras, so a frame holds fewer robots than the synthetic log's one camera.
void BM_OfflineTrainingRecorded(benchmark::State& state, const std::filesystem::path& path) {
  std::int64_t frames = 0;
  sf::VisionFrame frame;
  std::uint64_t instances = 0;  // kept so the training cannot be optimised away
  for (auto _ : state) {
    sf::SamplerConfig config;
    config.step_s = 0.5;
    config.sampling = sf::Sampling::frame;
    sf::MotionConfig motion_config;
    motion_config.step_s = config.step_s;
    motion_config.horizons = 3;
    sf::Training training(config, sf::TransitionTable(config.grid), 0,
                          sf::MotionTable(motion_config));
    auto reader = sf::LogReader::open(path).value();  // throws with the reason
    while (reader.next_vision(frame)) {
      training.add(frame);
      ++frames;
    }
    instances = training.table_summary().motion->instances;
  }
  state.SetItemsProcessed(frames);
  // The log's length, for figures per frame from counts over the whole run
  // (scripts/bench-instructions.sh divides callgrind's instruction count by it).
  state.counters["frames_per_pass"] =
      static_cast<double>(frames) / static_cast<double>(state.iterations());
  benchmark::DoNotOptimize(instances);
  state.SetLabel(path.filename().string() + ", frame sampling + motion model");
}

// The recording reshaped as recorded Division A matches come (docs/simulation.md,
// common/files/include/ssl_formation/files/real_log_shape.hpp): every packet with camera id 0, 90
// packets a second, each holding the robots of one half of the field. Each such packet completes an
// instant with every opponent robot, so this is the costliest shape per packet. Written once per
// process, when first asked for, in the temp folder.
const std::filesystem::path& one_camera_halves_log(const std::filesystem::path& recording) {
  static const std::filesystem::path out =
      std::filesystem::temp_directory_path() /
      ("sslf-bench-halves-" + std::to_string(::getpid()) + ".log");
  static const bool written = [&] {
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove(out, ignored);
    });
    sf::write_as_real_log(recording, out, sf::RealLogMess{}).value();  // throws with the reason
    return true;
  }();
  (void)written;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  // A .log.gz with both inflaters in one run, where the build has ISA-L.
  const std::int64_t inflaters = sf::isal_available() ? 2 : 1;
  for (const auto& [name, read] :
       {std::pair{"BM_ReadAndParse", &BM_Read<sf::VisionFrame>},
        std::pair{"BM_ReadAndParseProtobuf", &BM_Read<SSL_WrapperPacket>}}) {
    auto* benchmark = benchmark::RegisterBenchmark(name, read)->ArgNames({"gzip", "isal"});
    benchmark->Args({0, 0});
    for (std::int64_t isal = 0; isal < inflaters; ++isal) benchmark->Args({1, isal});
    benchmark->Unit(benchmark::kMillisecond);  // CPU time: one core
  }
  if (const char* recording = std::getenv("SSLF_BENCH_RECORDING")) {
    // The floor on the recording, with each inflater when it is a .log.gz.
    auto* benchmark = benchmark::RegisterBenchmark(
        "BM_ReadRecorded", [path = std::filesystem::path(recording)](benchmark::State& state) {
          read_vision<sf::VisionFrame>(state, path, inflater_of(state.range(0)),
                                       path.filename().string());
        });
    benchmark->ArgName("isal");
    const bool gzip = std::filesystem::path(recording).extension() == ".gz";
    for (std::int64_t isal = 0; isal < (gzip ? inflaters : 1); ++isal) benchmark->Arg(isal);
    benchmark->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark("BM_OfflineTrainingRecorded", BM_OfflineTrainingRecorded,
                                 std::filesystem::path(recording))
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(
        "BM_OfflineTrainingRecordedAsOneCameraHalves",
        [path = std::filesystem::path(recording)](benchmark::State& state) {
          BM_OfflineTrainingRecorded(state, one_camera_halves_log(path));
        })
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
