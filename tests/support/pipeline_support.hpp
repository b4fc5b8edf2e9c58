#pragma once
// What the process tests of the pipeline share: a fresh loopback group per test, a listener that
// collects the predictor's FormationPrediction messages on a thread of its own, and a table's
// counts as a comparable list. Everything joins on 127.0.0.1 (the multicast layer's default).

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "child_process.hpp"
#include "formation_prediction.pb.h"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/transition_table.hpp"

namespace ssl_formation::testing {

// "239.255.x.y:PORT" on a port nobody uses: tests that ctest runs in parallel never share traffic.
inline std::string new_group() { return unique_group(free_udp_port()); }

// Every nonzero count as (from, to, count), in order: two tables are equal iff these are.
using TableEntries = std::vector<std::tuple<StateIndex, StateIndex, TransitionTable::Count>>;
inline TableEntries table_entries(const TransitionTable& table) {
  TableEntries out;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count c) {
    out.emplace_back(from, to, c);
  });
  return out;
}

class PredictionListener {
 public:
  explicit PredictionListener(const std::string& group) {
    receiver_ = std::make_unique<net::ProtoMulticastReceiver<proto::FormationPrediction>>(
        io_, net::parse_multicast_endpoint(group).value());
    receiver_->start([this](const proto::FormationPrediction& message, const net::udp::endpoint&) {
      std::lock_guard lock(mutex_);
      messages_.push_back(message);
    });
    thread_ = std::thread([this] { io_.run(); });
  }
  ~PredictionListener() {
    io_.stop();
    thread_.join();
  }
  PredictionListener(const PredictionListener&) = delete;
  PredictionListener& operator=(const PredictionListener&) = delete;

  // What has arrived once there are `n` messages, or when `timeout` runs out.
  std::vector<proto::FormationPrediction> wait_for(std::size_t n,
                                                   std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      {
        std::lock_guard lock(mutex_);
        if (messages_.size() >= n) return messages_;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::lock_guard lock(mutex_);
    return messages_;
  }
  // The same, as the bytes on the wire (for exact comparisons with the library's messages).
  std::vector<std::string> wait_for_bytes(std::size_t n, std::chrono::milliseconds timeout) {
    std::vector<std::string> out;
    for (const auto& message : wait_for(n, timeout)) out.push_back(message.SerializeAsString());
    return out;
  }

 private:
  boost::asio::io_context io_;
  std::unique_ptr<net::ProtoMulticastReceiver<proto::FormationPrediction>> receiver_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<proto::FormationPrediction> messages_;
};

}  // namespace ssl_formation::testing
