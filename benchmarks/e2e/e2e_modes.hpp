#pragma once
// What e2e_bench's modes share (e2e_bench.cpp says what each mode does): the benchmark's own
// multicast groups, the clock and pacing helpers, and each mode's entry point.

// bounded in count and time.

#include <spdlog/spdlog.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "formation_prediction.pb.h"
#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace e2e {

namespace sf = ssl_formation;
namespace po = boost::program_options;
using Clock = std::chrono::steady_clock;

// Benchmark groups, apart from the defaults (10006, 10040) so a running demo does not interfere,
// and from the tests' 224.5.23.100-199.
inline constexpr const char* kVisionGroup = "224.5.23.210:10210";
inline constexpr const char* kPredictionGroup = "224.5.23.211:10211";
inline constexpr const char* kEchoInGroup = "224.5.23.212:10212";
inline constexpr const char* kEchoOutGroup = "224.5.23.213:10213";

inline std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// Sleeps until `spin_ns` before the deadline, then spins: sleeping alone wakes tens of
// microseconds late, spinning alone would take a whole core from the daemons under test. The
// send time is recorded after this returns, so lateness shifts the schedule, never a latency.
inline void wait_until(std::int64_t deadline_ns, std::int64_t spin_ns) {
  for (;;) {
    const std::int64_t now = now_ns();
    if (now >= deadline_ns) return;
    if (deadline_ns - now > spin_ns) {
      // steady_clock is CLOCK_MONOTONIC on Linux.
      const std::int64_t wake = deadline_ns - spin_ns;
      timespec until{static_cast<time_t>(wake / 1'000'000'000),
                     static_cast<long>(wake % 1'000'000'000)};
      ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
    }
  }
}

// The default timer slack (50 us) would make every sleep that late.
inline void tighten_timer_slack() { ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); }

inline std::span<const std::byte> bytes_of(const std::string& text) {
  return std::as_bytes(std::span(text.data(), text.size()));
}

inline sf::net::MulticastEndpoint group_option(const std::string& name, const std::string& text) {
  return sf::app::parse_group_option(name, text);
}

// Only one interface address, never "all": this program sends and joins on one interface.
inline sf::net::InterfaceChoice interface_option(const std::string& text) {
  return sf::app::parse_interface_option(text, false);
}

struct LatencyOptions {
  double rate = 60.0;
  double seconds = 10.0;
  std::size_t warmup = 10;
  std::string vision_address = kVisionGroup;
  std::string prediction_address = kPredictionGroup;
  std::string echo_in = kEchoInGroup;
  std::string echo_out = kEchoOutGroup;
  std::string interface = sf::app::default_interface;
  double step_s = 2.0;
  double start_time_s = 1000.0;
  std::uint64_t seed = 7;
  double spin_us = 30.0;
  double drain_s = 0.5;
  bool no_echo = false;
  bool no_predictor = false;
  // The table file the predictor follows, replaced during the run by a copy of replace_from
  // (of itself as it was at the start when empty); empty: never replaced.
  std::string replace_table;
  std::string replace_from;
  double replace_every_s = 2.0;
};

struct LoadOptions {
  double rate = 20000.0;  // packets per second
  double seconds = 5.0;
  int cameras = 4;
  double frame_dt_s = 2.0;  // data-clock advance per camera frame
  std::string vision_address = kVisionGroup;
  std::string interface = sf::app::default_interface;
  std::uint64_t seed = 11;
  double start_time_s = 1000.0;
};

// Nearest-rank percentile of a sorted sample.
inline double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return std::nan("");
  const auto rank =
      static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

// One detection packet per formation of a one-camera simulated feed, t_capture advancing by one
// step each, so every packet completes one sample and the predictor answers every packet.
inline std::vector<std::string> latency_packets(const LatencyOptions& o, std::size_t count) {
  sf::simulation::SimulationConfig simulation;
  simulation.seed = o.seed;
  simulation.step_s = o.step_s;
  simulation.start_time_s = o.start_time_s;
  simulation.cameras = 1;
  sf::simulation::SimulatedVision vision(simulation);
  std::vector<std::string> packets;
  packets.reserve(count);
  while (packets.size() < count) {
    for (SSL_WrapperPacket& packet : vision.next().packets) {
      if (!packet.has_detection()) continue;  // geometry: the default field is the same
      packet.mutable_detection()->set_frame_number(static_cast<std::uint32_t>(packets.size() + 1));
      packets.push_back(packet.SerializeAsString());
    }
  }
  return packets;
}

// The modes (e2e_bench.cpp: make-table and echo; latency_mode.cpp, pipeline_mode.cpp,
// load_mode.cpp).
int make_table(const std::string& path, std::uint64_t formations, std::uint64_t seed, double step_s,
               sf::ModelKind model);
int run_echo(const std::string& in, const std::string& out, const std::string& interface_text,
             double seconds, int receive_buffer);
int run_latency(const LatencyOptions& o);
int run_pipeline(const std::string& table_path, std::size_t count, double step_s,
                 std::uint64_t seed, double idle_s);
int run_load(const LoadOptions& o);

}  // namespace e2e
