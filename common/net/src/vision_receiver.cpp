#include "ssl_formation/net/vision_receiver.hpp"

#include <utility>

#include "ssl_formation/net/proto_multicast.hpp"

namespace ssl_formation::net {

VisionReceiver::VisionReceiver(boost::asio::io_context& io, MulticastEndpoint endpoint,
                               InterfaceChoice interface, int receive_buffer_bytes)
    : receiver_(io, endpoint, interface, receive_buffer_bytes) {
  // Room for the usual frame from the start, so the robots share a page with what comes next.
  frame_.detection.robots_yellow.reserve(16);
  frame_.detection.robots_blue.reserve(16);
}

void VisionReceiver::start(FrameHandler on_frame) {
  // The handler is replaced only once the socket is up: a start() that throws (already started,
  // cannot bind or join) leaves a running receiver's handler alone. No datagram can arrive in
  // between: they are handled inside io_context::run().
  receiver_.start([this](std::span<const std::byte> data, const udp::endpoint& from) {
    on_datagram(data, from);
  });
  on_frame_ = std::move(on_frame);
}

void VisionReceiver::on_datagram(std::span<const std::byte> data, const udp::endpoint& from) {
  switch (read_vision_datagram(data, frame_, packet_)) {
    case VisionDatagram::decoded_directly:
      direct_decodes_.fetch_add(1, std::memory_order_relaxed);
      break;
    case VisionDatagram::parsed_by_protobuf:
      break;
    case VisionDatagram::invalid:
      receiver_.count_parse_error();
      detail::log_parse_error(receiver_, packet_.GetTypeName(), data.size());
      return;
  }
  if (on_frame_) on_frame_(frame_, from);
}

}  // namespace ssl_formation::net
