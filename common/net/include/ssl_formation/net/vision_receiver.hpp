#pragma once
// Receives SSL-Vision datagrams (SSL_WrapperPacket) and hands on what sampling reads, as a
// VisionFrame. Detection packets are decoded straight from the bytes (decode_detection_datagram);
// anything else (geometry, unusual or damaged packets) goes through protobuf's parser exactly as
// ProtoMulticastReceiver<SSL_WrapperPacket> would take it, so what counts as a parse error is
// protobuf's decision, never this class's.
//
//   net::VisionReceiver vision(io, group, iface);
//   vision.start([&](const VisionFrame& frame, const net::udp::endpoint& from) { ... });

#include <atomic>
#include <cstdint>
#include <functional>

#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::net {

class VisionReceiver {
 public:
  // frame is valid only during the call (it is reused for the next datagram).
  using FrameHandler = std::function<void(const VisionFrame& frame, const udp::endpoint& from)>;

  VisionReceiver(boost::asio::io_context& io, MulticastEndpoint endpoint,
                 InterfaceChoice interface = {},
                 int receive_buffer_bytes = kDefaultReceiveBufferBytes);

  // Opens, binds, joins and starts receiving; throws MulticastError on failure (see
  // MulticastReceiver::start()).
  void start(FrameHandler on_frame);
  void stop() { receiver_.stop(); }

  const ReceiverCounters& counters() const { return receiver_.counters(); }
  // Datagrams decoded without protobuf (the rest were parsed by protobuf or refused by it).
  std::uint64_t direct_decodes() const { return direct_decodes_.load(std::memory_order_relaxed); }

 private:
  void on_datagram(std::span<const std::byte> data, const udp::endpoint& from);

  FrameHandler on_frame_;
  VisionFrame frame_;         // reused: its robot vectors keep their capacity
  SSL_WrapperPacket packet_;  // for the datagrams protobuf parses
  std::atomic<std::uint64_t> direct_decodes_{0};
  // Declared last so it is destroyed (and stopped) first: no callback sees a dead member.
  MulticastReceiver receiver_;
};

}  // namespace ssl_formation::net
