#pragma once
// Four robots driving circles, for the unit tests of what learns from movement (the motion
// model's training, its table files, merging).
#include <cmath>
#include <cstdint>
#include <vector>

#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::testing {

// Four yellow robots driving circles, one frame every 1/30 s for `seconds` from `t0`; `seed`
// sets each robot's radius, direction and phase.
inline std::vector<SSL_WrapperPacket> circling_stream(double t0, double seconds, int seed) {
  std::vector<SSL_WrapperPacket> packets;
  const int frames = static_cast<int>(seconds * 30.0);
  for (int f = 0; f < frames; ++f) {
    const double t = t0 + f / 30.0;
    DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(f);
    spec.t_capture = t;
    for (std::uint32_t id = 0; id < 4; ++id) {
      const double radius = 600.0 + 300.0 * id + 100.0 * seed;
      const double omega = (0.6 + 0.25 * id) * (seed % 2 == 0 ? 1.0 : -1.0);
      const double phase = 0.7 * id + 1.3 * seed + omega * (t - t0);
      const Point centre{-2500.0 + 1600.0 * id, (id % 2 == 0 ? -1000.0 : 1000.0)};
      spec.yellow.push_back(
          {id, {centre.x + radius * std::cos(phase), centre.y + radius * std::sin(phase)}});
    }
    packets.push_back(make_detection_packet(spec));
  }
  return packets;
}

}  // namespace ssl_formation::testing
