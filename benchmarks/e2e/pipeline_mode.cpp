// e2e_bench pipeline: ssl-predictor's work for one packet, in this process (e2e_bench.cpp).
#include "e2e_modes.hpp"

namespace e2e {

int run_pipeline(const std::string& table_path, std::size_t count, double step_s,
                 std::uint64_t seed, double idle_s) {
  auto loaded = sf::load_table(table_path);
  if (!loaded) {
    std::cerr << "e2e_bench pipeline: " << loaded.error().message << '\n';
    return 1;
  }
  sf::StoredTable& stored = *loaded;
  LatencyOptions o;
  o.step_s = step_s;
  o.seed = seed;
  const std::vector<std::string> packets = latency_packets(o, 2 * count);

  // The predictor's per-packet path: net::VisionReceiver's decode, then the PredictionPipeline
  // and the encoding the daemon runs, with their buffers reused the same way.
  // The model the table serves (a version-3 table: the motion model, the daemon's default), at
  // the table's own step; `step_s` is the data-clock time between packets.
  sf::PredictionConfig config;
  config.sampler.grid = stored.table.grid();
  config.sampler.step_s = stored.metadata.step_s;
  config.model = stored.motion ? sf::ModelKind::motion : sf::ModelKind::paper;
  config.sampler.sampling = stored.motion ? sf::Sampling::frame : sf::Sampling::step;
  std::string encoded;
  encoded.reserve(2048);
  std::uint64_t predictions = 0;
  // Stage times of the current packet: decode, sample and predict, encode.
  std::array<std::int64_t, 4> marks{};
  sf::PredictionPipeline pipeline(config, [&](const sf::PredictedFormation& predicted) {
    marks[2] = now_ns();
    sf::encode_prediction(predicted.formation(), predicted.prediction, predicted.context, encoded);
    marks[3] = now_ns();
    ++predictions;
  });
  pipeline.set_table(std::make_shared<const sf::StoredTable>(std::move(stored)));
  // As net::VisionReceiver: detection packets decoded straight from the bytes, anything else
  // by protobuf.
  sf::VisionFrame frame;
  SSL_WrapperPacket parsed;
  std::array<std::vector<double>, 3> idle_stages;
  const auto one = [&](const std::string& bytes) {
    marks = {};
    marks[0] = now_ns();
    if (sf::read_vision_datagram(bytes_of(bytes), frame, parsed) != sf::VisionDatagram::invalid) {
      marks[1] = now_ns();
      pipeline.add(frame);
    }
    return static_cast<double>(now_ns() - marks[0]) / 1000.0;
  };
  // First every packet after sleeping as a daemon does between packets at 60 packets/s (its
  // caches and TLB go cold meanwhile: the machine runs other work), then as many back to back.
  std::vector<double> warm, idle;
  for (std::size_t i = 0; i < count; ++i) {
    std::this_thread::sleep_for(std::chrono::duration<double>(idle_s));
    idle.push_back(one(packets[i]));
    if (marks[3] != 0) {
      for (std::size_t k = 0; k < idle_stages.size(); ++k) {
        idle_stages[k].push_back(static_cast<double>(marks[k + 1] - marks[k]) / 1000.0);
      }
    }
  }
  for (std::size_t i = count; i < 2 * count; ++i) warm.push_back(one(packets[i]));
  std::sort(warm.begin(), warm.end());
  std::sort(idle.begin(), idle.end());
  std::printf(
      "pipeline packets=%zu predictions=%llu message_bytes=%zu warm_p50_us=%.2f warm_p99_us=%.2f "
      "idle_p50_us=%.2f idle_p99_us=%.2f idle_ms=%.1f\n",
      count, static_cast<unsigned long long>(predictions), encoded.size(), percentile(warm, 50),
      percentile(warm, 99), percentile(idle, 50), percentile(idle, 99), idle_s * 1000.0);
  const char* names[] = {"decode", "sample+predict", "encode"};
  std::printf("pipeline stage medians after idling (us):");
  for (std::size_t k = 0; k < idle_stages.size(); ++k) {
    std::sort(idle_stages[k].begin(), idle_stages[k].end());
    std::printf(" %s=%.2f", names[k], percentile(idle_stages[k], 50));
  }
  std::printf("\n");
  return 0;
}

}  // namespace e2e
