// Writes the seed corpus of the fuzz targets (tests/fuzz/corpus/{sampler,log,table}/): a few
// real grSim packets from tests/data, small simulated streams (clean and hostile), small logs
// (plain, gzip, indexed) and dense and sparse table files. Built only with SSLF_FUZZ=ON.
//
//   make_corpus GRSIM_LOG OUTPUT_DIR
//
// The corpus is committed; rerun this only to change it, and keep it small (< 300 KB).

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "fuzz_paths.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/files/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace fs = std::filesystem;
using namespace ssl_formation;

namespace {

// A sampler input: the config selector, then length-prefixed packets (fuzz_paths.hpp).
class SamplerInput {
 public:
  explicit SamplerInput(std::uint8_t selector) { bytes_.push_back(static_cast<char>(selector)); }
  void add(const SSL_WrapperPacket& packet) { add_raw(packet.SerializePartialAsString()); }
  void add_raw(const std::string& packet) {
    const std::size_t n = std::min<std::size_t>(packet.size(), 0xFFFE);
    bytes_.push_back(static_cast<char>(n & 0xff));
    bytes_.push_back(static_cast<char>(n >> 8));
    bytes_.append(packet, 0, n);
  }
  void new_stream() { bytes_.append("\xff\xff", 2); }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

void write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::vector<RobotDetection> team(int n, double t, double x0, std::uint32_t first_id) {
  std::vector<RobotDetection> robots;
  for (int i = 0; i < n; ++i) {
    RobotDetection r;
    r.robot_id = first_id + static_cast<std::uint32_t>(i);
    r.position = Point{x0 + 400.0 * t * (i % 2 == 0 ? 1 : -1) + 300.0 * i, -2000.0 + 900.0 * i};
    robots.push_back(r);
  }
  return robots;
}

// Two cameras splitting the field at x = 0, `robots` per team moving along x.
std::vector<SSL_WrapperPacket> simulated_stream(double duration_s, double frame_s, int robots) {
  std::vector<SSL_WrapperPacket> packets{make_geometry_packet(FieldSize{9000, 6000})};
  std::uint32_t frame = 0;
  for (double t = 0.0; t <= duration_s + 1e-9; t += frame_s) {
    for (std::uint32_t camera = 0; camera < 2; ++camera) {
      DetectionFrameSpec spec;
      spec.camera_id = camera;
      spec.frame_number = frame++;
      spec.t_capture = 100.0 + t;
      const double x0 = camera == 0 ? -3000.0 : 1000.0;
      spec.yellow = team(robots, t, x0, camera * 4);
      spec.blue = team(robots, t, -x0, camera * 4);
      spec.balls = {Point{10.0 * t, 0.0}};
      packets.push_back(make_detection_packet(spec));
    }
  }
  return packets;
}

void write_sampler_corpus(const fs::path& dir, const std::vector<SSL_WrapperPacket>& grsim) {
  // Real grSim packets, one per file: a detection and the one with geometry.
  for (const auto& packet : grsim) {
    if (packet.has_geometry()) {
      SamplerInput one(0x02);
      one.add(packet);
      write(dir / "grsim-geometry-packet", one.bytes());
      break;
    }
  }
  SamplerInput single(0x00);
  single.add(grsim.front());
  write(dir / "grsim-detection-packet", single.bytes());

  // Real grSim stream: every packet of the first 0.5 s of simulator time whose camera is 0 or 1,
  // 12x9 grid at a 0.1 s step, so samples and transitions come out.
  SamplerInput stream(0x22);
  const double t0 = grsim.front().detection().t_capture();
  for (const auto& packet : grsim) {
    if (!packet.has_detection()) continue;
    if (packet.detection().t_capture() > t0 + 0.5) break;
    if (packet.detection().camera_id() > 1) continue;
    SSL_WrapperPacket detection_only = packet;
    detection_only.clear_geometry();
    stream.add(detection_only);
  }
  write(dir / "grsim-stream-12x9-0.1s", stream.bytes());

  // Simulated: 3x2 at 2 s over 10 s, 3 robots per team per camera.
  SamplerInput sim(0x00);
  for (const auto& packet : simulated_stream(10.0, 0.5, 3)) sim.add(packet);
  write(dir / "sim-3x2-2s", sim.bytes());

  // Simulated: blue attacking -x, 1/60 s step, 16x16, geometry ignored.
  SamplerInput fast(0x40 | 0x10 | 0x08 | 0x04 | 0x03);
  for (const auto& packet : simulated_stream(0.2, 1.0 / 60.0, 2)) fast.add(packet);
  write(dir / "sim-16x16-60hz-blue-minus-x", fast.bytes());

  // Hostile: everything the sampler must refuse or survive, between valid frames.
  SamplerInput hostile(0x21);
  const auto frame = [](std::uint32_t camera, double t, std::vector<RobotDetection> yellow) {
    DetectionFrameSpec spec;
    spec.camera_id = camera;
    spec.frame_number = static_cast<std::uint32_t>(t * 60);
    spec.t_capture = t;
    spec.yellow = std::move(yellow);
    return make_detection_packet(spec);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  hostile.add(frame(0, 1.0, team(3, 0, 0, 0)));
  hostile.add(
      frame(0, 1.2, {{1, {0, 0}, 0, 0.5F}, {1, {100, 0}, 0, 0.9F}, {2, {nan, 0}, 0, 0.9F}}));
  hostile.add(
      frame(0, 1.3, {{3, {2e5, 0}, 0, 0.9F}, {5000, {0, 0}, 0, 0.9F}, {4, {0, inf}, 0, 0.9F}}));
  hostile.add(frame(64, 1.4, team(3, 0, 0, 0)));
  hostile.add(frame(0, nan, team(3, 0, 0, 0)));
  hostile.add(frame(1, 1.5, team(33, 0, 0, 0)));
  hostile.add(frame(0, 1.6, team(3, 1, 0, 0)));
  hostile.add(frame(0, 1.05, team(3, 1, 0, 0)));  // late
  hostile.add(frame(0, 0.1, team(3, 1, 0, 0)));   // clock reset
  hostile.add(frame(0, 0.3, team(3, 1, 0, 0)));
  hostile.add(make_geometry_packet(FieldSize{12000, 9000}));
  hostile.add(make_geometry_packet(FieldSize{-1, 0}));
  hostile.add(frame(0, 0.45, team(3, 2, 0, 0)));
  hostile.new_stream();
  hostile.add(frame(0, 1e15, team(3, 2, 0, 0)));
  hostile.add(frame(0, -1e15, team(3, 2, 0, 0)));
  hostile.add(frame(0, 1e15 + 0.5, team(3, 2, 0, 0)));
  hostile.add_raw("\x0a\x02\x08");  // truncated
  SSL_WrapperPacket missing_required;
  missing_required.mutable_detection()->set_camera_id(0);
  hostile.add(missing_required);
  write(dir / "sim-hostile-1x1-0.1s", hostile.bytes());
}

void write_log_corpus(const fs::path& dir, const std::vector<SSL_WrapperPacket>& grsim) {
  const auto write_log = [&](const fs::path& path, bool indexed) {
    auto writer = LogWriter::create(path);
    if (!writer) throw std::runtime_error(writer.error().message);
    std::int64_t t = 1'000'000'000;
    for (std::size_t i = 0; i < 4; ++i) writer->write_vision(grsim[i], t += 16'000'000);
    for (const auto& packet : simulated_stream(1.0, 0.5, 2))
      writer->write_vision(packet, t += 1'000'000);
    writer->write(3, t, std::string("\x08\x01\x10\x02", 4));  // a referee message (not parsed)
    // A legacy (2010) packet: today's detection decodes; then one without a frame number.
    DetectionFrameSpec spec;
    spec.t_capture = 5.0;
    spec.yellow = team(2, 0, 0, 0);
    writer->write(2, t, make_detection_packet(spec).SerializeAsString());
    SSL_WrapperPacket unusable;
    unusable.mutable_detection()->set_camera_id(1);
    writer->write(2, t, unusable.SerializePartialAsString());
    writer->write(4, t, "\x0a\x05garbage");  // does not parse
    writer->write(0, t, "");
    writer->write(5, t, "tracker");
    writer->write(42, t, "unknown type");
    if (!writer->close(indexed)) throw std::runtime_error(writer->error());
  };
  write_log(dir / "mixed.log", false);
  write_log(dir / "mixed-indexed.log", true);
  write_log(dir / "mixed.log.gz", false);
  write(dir / "header-only.log", std::string("SSL_LOG_FILE\0\0\0\1", 16));
  std::string cut = fuzz::read_bytes(dir / "mixed.log");
  write(dir / "truncated.log", cut.substr(0, cut.size() / 2));
}

void save(const fs::path& path, const TransitionTable& table, std::uint64_t samples) {
  const auto result = save_table(path, table, TableMetadata{FieldSize{}, 2.0, samples});
  if (!result) throw std::runtime_error(result.error().message);
}

void write_table_corpus(const fs::path& dir, const std::vector<SSL_WrapperPacket>& grsim) {
  TransitionTable one(Grid(1, 1), TableStorage::dense);
  one.add(0, 0, 7);
  save(dir / "dense-1x1.sslft", one, 8);

  TransitionTable two(Grid(2, 1), TableStorage::dense);
  two.add(0, 3, 2);
  two.add(5, 1);
  two.add(7, 7, TransitionTable::max_count);
  save(dir / "dense-2x1.sslft", two, 4);

  // Trained tables: the simulated stream on dense 2x2 and sparse 3x2, grSim on sparse 12x9.
  const auto train = [](const SamplerConfig& config, TransitionTable table,
                        const std::vector<SSL_WrapperPacket>& packets) {
    Training training(config, std::move(table));
    for (const auto& packet : packets) training.add(packet);
    return TransitionTable(training.table());
  };
  SamplerConfig config;
  config.step_s = 0.5;
  const auto sim = simulated_stream(10.0, 0.25, 3);
  config.grid = Grid(2, 2);
  save(dir / "dense-2x2.sslft",
       train(config, TransitionTable(config.grid, TableStorage::dense), sim), 20);
  config.grid = Grid(3, 2);
  save(dir / "sparse-3x2.sslft",
       train(config, TransitionTable(config.grid, TableStorage::sparse), sim), 20);
  config.grid = Grid(12, 9);
  config.step_s = 0.2;
  save(dir / "sparse-12x9-grsim.sslft", train(config, TransitionTable(config.grid), grsim), 50);
  save(dir / "sparse-4x4-empty.sslft", TransitionTable(Grid(4, 4), TableStorage::sparse), 0);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s GRSIM_LOG OUTPUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const auto read = read_vision_log(argv[1]);
    if (!read) {
      std::fprintf(stderr, "cannot read %s: %s\n", argv[1], read.error().message.c_str());
      return 1;
    }
    const LogVisionPackets& log = *read;
    if (log.stopped_early || log.packets.size() < 8) {
      std::fprintf(stderr, "cannot read %s: %s\n", argv[1],
                   log.stopped_early ? log.stopped_early->message.c_str() : "too few packets");
      return 1;
    }
    const fs::path out = argv[2];
    for (const char* target : {"sampler", "log", "table"}) fs::create_directories(out / target);
    write_sampler_corpus(out / "sampler", log.packets);
    write_log_corpus(out / "log", log.packets);
    write_table_corpus(out / "table", log.packets);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_corpus: %s\n", e.what());
    return 1;
  }
  return 0;
}
