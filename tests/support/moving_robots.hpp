#pragma once
// A vision feed of robots that really move, for the process tests of the motion model (the
// simulated producer's opponent jumps between formations every 2 s, which leaves it nothing to
// learn): frames at 60 Hz from one camera, six yellow robots (the opponent by default, attacking
// +x) and six blue ones, every robot driving a smooth path of its own whose speed swells and
// ebbs between about 0.1 and 2 m/s, all on a Division B field (9 x 6 m, one geometry packet
// first). Deterministic for a seed: the same seed gives the same packets.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::testing {

struct MovingRobots {
  std::uint64_t seed = 1;
  double seconds = 60.0;
  double start_time_s = 100.0;  // t_capture of the first frame
  double frame_rate_hz = 60.0;
};

// Where robot `index` (0-11: yellow 0-5, then blue) is at `t` seconds into the stream: a
// Lissajous path about a centre of its own, run at a speed that varies smoothly (the path's
// parameter is t - a sin(b t) / b, so the robot speeds up, slows down almost to a stop, turns).
inline Point moving_robot_position(std::uint64_t seed, int index, double t) {
  const double i = index;
  const double s = static_cast<double>(seed % 1000);
  const Point centre{-2800.0 + 1120.0 * (index % 6),
                     index < 6 ? -900.0 + 300.0 * (index % 3) : 900.0 - 300.0 * (index % 3)};
  const double amplitude_x = 700.0 + 100.0 * (index % 5);
  const double amplitude_y = 600.0 + 80.0 * (index % 4);
  const double rate = 0.45 + 0.07 * (index % 6);   // rad/s of the path's parameter
  const double swell = 0.25 + 0.05 * (index % 3);  // rad/s of the speed's swell
  const double parameter = t - 0.9 * std::sin(swell * t + 0.8 * i + s) / swell;
  return {centre.x + amplitude_x * std::sin(rate * parameter + 1.3 * i + 0.7 * s),
          centre.y + amplitude_y * std::sin(1.5 * rate * parameter + 0.4 * i + 1.1 * s)};
}

// The feed's packets in order: a geometry packet, then one detection packet per frame.
inline std::vector<SSL_WrapperPacket> moving_robots_packets(const MovingRobots& config) {
  std::vector<SSL_WrapperPacket> packets;
  packets.push_back(make_geometry_packet(FieldSize{9000.0, 6000.0}));
  const auto frames = static_cast<int>(std::lround(config.seconds * config.frame_rate_hz));
  for (int f = 0; f < frames; ++f) {
    const double t = f / config.frame_rate_hz;
    DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(f);
    spec.t_capture = config.start_time_s + t;
    for (int index = 0; index < 12; ++index) {
      const RobotDetection robot{static_cast<std::uint32_t>(index % 6),
                                 moving_robot_position(config.seed, index, t)};
      (index < 6 ? spec.yellow : spec.blue).push_back(robot);
    }
    packets.push_back(make_detection_packet(spec));
  }
  return packets;
}

// Writes `packets` as an official log (.log, or gzip with .log.gz), each received at its
// t_capture (the geometry packet with the first frame). An error message, empty on success.
inline std::string write_vision_log(const std::filesystem::path& path,
                                    const std::vector<SSL_WrapperPacket>& packets) {
  auto writer = LogWriter::create(path);
  if (!writer) return writer.error().message;
  double t = 0.0;  // the latest frame's t_capture; before the first, the first's
  for (const SSL_WrapperPacket& packet : packets) {
    if (packet.has_detection()) {
      t = packet.detection().t_capture();
      break;
    }
  }
  for (const SSL_WrapperPacket& packet : packets) {
    if (packet.has_detection()) t = packet.detection().t_capture();
    if (!writer->write_vision(packet, static_cast<std::int64_t>(std::llround(t * 1e9)))) {
      return writer->error();
    }
  }
  if (!writer->close()) return writer->error();
  return {};
}

// A minute of moving robots to train on (seed 1) and `test_seconds` of others (seed 2, starting
// at 1000 s on the data clock) to test on, written as logs at `train` and `test`: what a team's
// two recorded matches would be. An error message, empty on success.
inline std::string write_train_and_test_logs(const std::filesystem::path& train,
                                             const std::filesystem::path& test,
                                             double test_seconds) {
  std::string error = write_vision_log(train, moving_robots_packets({.seed = 1, .seconds = 60.0}));
  if (!error.empty()) return error;
  return write_vision_log(
      test, moving_robots_packets({.seed = 2, .seconds = test_seconds, .start_time_s = 1000.0}));
}

}  // namespace ssl_formation::testing
