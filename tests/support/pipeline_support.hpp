#pragma once
// What the process tests of the pipeline share: a listener that collects the predictor's
// FormationPrediction messages on a thread of its own, an end marker to know that nothing more is
// on its way, and a table's counts as a comparable list. Everything sends and joins on 127.0.0.1
// (the multicast layer's default), on groups of the test's own (new_group(), feed_groups.hpp).

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "child_process.hpp"
#include "formation_prediction.pb.h"
#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/net/proto_multicast.hpp"

namespace ssl_formation::testing {

// What a test sends to a group once everything it expects has arrived, to know without sleeping
// that nothing more is on the way: a socket hands datagrams over in the order they reached it, and
// on loopback a datagram reaches every joined socket while it is being sent. So once a listener
// has the marker, whatever was sent to the group before it (by a process that has stopped
// sending) has arrived too. Raw listeners compare datagrams with `end_marker`; the prediction
// listener sends it as a FormationPrediction's opponent_color.
inline const std::string end_marker = "sslf-test-end-marker";

// Sends `bytes` to `group` from 127.0.0.1, TTL 1.
inline bool send_to_group(const std::string& group, const std::string& bytes) {
  boost::asio::io_context io;
  net::MulticastSender sender(io, net::parse_multicast_endpoint(group).value());
  sender.open();
  return sender.send(std::as_bytes(std::span(bytes.data(), bytes.size())));
}

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
  explicit PredictionListener(const std::string& group) : group_(group) {
    receiver_ = std::make_unique<net::ProtoMulticastReceiver<proto::FormationPrediction>>(
        io_, net::parse_multicast_endpoint(group).value());
    receiver_->start([this](const proto::FormationPrediction& message, const net::udp::endpoint&) {
      std::lock_guard lock(mutex_);
      if (message.opponent_color() == end_marker) {
        ++markers_;
      } else {
        messages_.push_back(message);
      }
    });
    thread_ = std::thread([this] { io_.run(); });
  }
  ~PredictionListener() {
    io_.stop();
    thread_.join();
  }
  PredictionListener(const PredictionListener&) = delete;
  PredictionListener& operator=(const PredictionListener&) = delete;

  // How many predictions have arrived so far.
  std::size_t count() {
    std::lock_guard lock(mutex_);
    return messages_.size();
  }
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
  // Sends an end marker to the group and waits for it: then every prediction sent before it has
  // arrived. What has arrived, or nullopt if the marker did not come back within `timeout`.
  std::optional<std::vector<proto::FormationPrediction>> drain(std::chrono::milliseconds timeout) {
    std::size_t markers = 0;
    {
      std::lock_guard lock(mutex_);
      markers = markers_;
    }
    proto::FormationPrediction marker;
    marker.set_frame_number(0);
    marker.set_t_capture(0.0);
    marker.mutable_centroid_cell()->set_x(0);
    marker.mutable_centroid_cell()->set_y(0);
    marker.set_opponent_color(end_marker);
    if (!send_to_group(group_, marker.SerializeAsString())) return std::nullopt;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      {
        std::lock_guard lock(mutex_);
        if (markers_ > markers) return messages_;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return std::nullopt;
  }
  // The same, as the bytes on the wire (for exact comparisons with the library's messages).
  std::vector<std::string> wait_for_bytes(std::size_t n, std::chrono::milliseconds timeout) {
    std::vector<std::string> out;
    for (const auto& message : wait_for(n, timeout)) out.push_back(message.SerializeAsString());
    return out;
  }

 private:
  const std::string group_;
  boost::asio::io_context io_;
  std::unique_ptr<net::ProtoMulticastReceiver<proto::FormationPrediction>> receiver_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<proto::FormationPrediction> messages_;
  std::size_t markers_ = 0;
};

}  // namespace ssl_formation::testing
