#pragma once
// What the field view's process tests share: a free TCP port on loopback, the table the library
// computes from the simulated feed, and a multicast listener for the predictions.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "formation_prediction.pb.h"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::web_testing {

// `name` on the PATH, if it is there.
inline std::optional<std::filesystem::path> find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::filesystem::path candidate =
        std::filesystem::path(dirs.substr(start, end - start)) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return std::nullopt;
}

// Why the browser tests cannot run here (Chromium, node or playwright-core in `web_test_dir`
// missing), or nothing; sets `chromium` and `node`.
inline std::optional<std::string> missing_browser_tools(std::filesystem::path& chromium,
                                                        std::filesystem::path& node,
                                                        const std::filesystem::path& web_test_dir) {
  chromium = std::getenv("SSLF_CHROMIUM") ? std::getenv("SSLF_CHROMIUM") : "/usr/bin/chromium";
  if (::access(chromium.c_str(), X_OK) != 0) {
    return chromium.string() +
           " is missing: apt-get install chromium (Debian) to run the browser test";
  }
  const auto found = find_program("node");
  if (!found) return "node is missing: apt-get install nodejs (node 18 or newer)";
  node = *found;
  if (!std::filesystem::exists(web_test_dir / "node_modules" / "playwright-core" /
                               "package.json")) {
    return "playwright-core is missing: run npm ci --prefix " + web_test_dir.string();
  }
  return std::nullopt;
}

// A TCP port nothing listens on right now (the kernel picks it on 127.0.0.1).
inline std::uint16_t free_tcp_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  ::close(fd);
  return ntohs(address.sin_port);
}

// The table the library learns from `count` formations of the simulated producer with `seed`.
inline TransitionTable reference_table(std::uint64_t seed, int count) {
  simulation::SimulationConfig config;
  config.seed = seed;
  simulation::SimulatedVision vision(config);
  Training training(SamplerConfig{}, TransitionTable(Grid(3, 2)));
  for (int i = 0; i < count; ++i) {
    for (const auto& packet : vision.next().packets) training.add(packet);
  }
  return training.stored_table().table;
}

// The same table with its metadata as the trainer would save it: the formations it sampled.
struct ReferenceTable {
  TransitionTable table;
  TableMetadata metadata;
};
inline ReferenceTable reference_stored_table(std::uint64_t seed, int count) {
  simulation::SimulationConfig config;
  config.seed = seed;
  simulation::SimulatedVision vision(config);
  Training training(SamplerConfig{}, TransitionTable(Grid(3, 2)));
  for (int i = 0; i < count; ++i) {
    for (const auto& packet : vision.next().packets) training.add(packet);
  }
  TableMetadata metadata;
  metadata.field = training.sampler().field();
  metadata.step_s = training.sampler().config().step_s;
  metadata.samples = training.samples();
  return ReferenceTable{training.stored_table().table, metadata};
}

// How many datagrams the simulated producer with `seed` sends for `count` formations (geometry
// included), by default options.
inline std::uint64_t simulated_packet_count(std::uint64_t seed, int count) {
  simulation::SimulationConfig config;
  config.seed = seed;
  simulation::SimulatedVision vision(config);
  std::uint64_t packets = 0;
  for (int i = 0; i < count; ++i) packets += vision.next().packets.size();
  return packets;
}

// Records when each FormationPrediction arrives on a group, and when each vision detection frame
// arrives on the vision group (by frame number), on a thread of their own.
class PredictionArrivals {
 public:
  using Time = std::chrono::steady_clock::time_point;
  PredictionArrivals(const std::string& predictions, const std::string& vision) {
    receiver_ = std::make_unique<net::ProtoMulticastReceiver<proto::FormationPrediction>>(
        io_, net::parse_multicast_endpoint(predictions).value());
    receiver_->start([this](const proto::FormationPrediction& message, const net::udp::endpoint&) {
      std::lock_guard lock(mutex_);
      arrivals_.push_back(std::chrono::steady_clock::now());
      frames_.push_back(message.frame_number());
    });
    vision_ = std::make_unique<net::ProtoMulticastReceiver<SSL_WrapperPacket>>(
        io_, net::parse_multicast_endpoint(vision).value());
    vision_->start([this](const SSL_WrapperPacket& packet, const net::udp::endpoint&) {
      if (!packet.has_detection()) return;
      std::lock_guard lock(mutex_);
      vision_arrivals_[packet.detection().frame_number()] = std::chrono::steady_clock::now();
    });
    thread_ = std::thread([this] { io_.run(); });
  }
  // For each prediction, the time from the vision frame that completed it to the prediction.
  std::vector<std::chrono::steady_clock::duration> latencies() {
    std::lock_guard lock(mutex_);
    std::vector<std::chrono::steady_clock::duration> out;
    for (std::size_t i = 0; i < arrivals_.size(); ++i) {
      const auto seen = vision_arrivals_.find(frames_[i]);
      if (seen != vision_arrivals_.end()) out.push_back(arrivals_[i] - seen->second);
    }
    return out;
  }
  ~PredictionArrivals() {
    io_.stop();
    thread_.join();
  }
  std::vector<std::chrono::steady_clock::time_point> arrivals() {
    std::lock_guard lock(mutex_);
    return arrivals_;
  }
  std::size_t count() {
    std::lock_guard lock(mutex_);
    return arrivals_.size();
  }

 private:
  boost::asio::io_context io_;
  std::unique_ptr<net::ProtoMulticastReceiver<proto::FormationPrediction>> receiver_;
  std::unique_ptr<net::ProtoMulticastReceiver<SSL_WrapperPacket>> vision_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<Time> arrivals_;
  std::vector<std::uint32_t> frames_;
  std::map<std::uint32_t, Time> vision_arrivals_;
};

}  // namespace ssl_formation::web_testing
