#pragma once
// Typed protobuf layer over the byte-level multicast receiver and sender (multicast.hpp), like
// Thunderbots' ProtoUdpListener<T> over UdpListener.
//
//   net::ProtoMulticastReceiver<SSL_WrapperPacket> vision(io, group, iface);
//   vision.start([&](const SSL_WrapperPacket& packet, const net::udp::endpoint& from) { ... });
//
//   net::ProtoMulticastSender<FormationPrediction> out(io, group, iface.address, ttl);
//   out.open();
//   out.send(prediction);
//
// A datagram that does not decode (ParseFromArray fails: garbage, truncation, a missing proto2
// `required` field) is counted in counters().parse_errors, logged (rate-limited) and skipped; the
// receive loop goes on. Checking that a decoded packet makes sense (NaN coordinates, absurd ids)
// is the caller's job.

#include <google/protobuf/message_lite.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "ssl_formation/net/multicast.hpp"

namespace ssl_formation::net {

namespace detail {
// Logging helpers, out of line so this header does not pull in spdlog.
void log_parse_error(const MulticastReceiver& receiver, const std::string& type_name,
                     std::size_t size);
void log_encode_error(const MulticastSender& sender, const std::string& type_name, std::size_t size,
                      std::uint64_t errors);
}  // namespace detail

// Receives datagrams like MulticastReceiver and decodes each into a Message.
template <class Message>
class ProtoMulticastReceiver {
  static_assert(std::is_base_of_v<google::protobuf::MessageLite, Message>,
                "Message must be a generated protobuf message");

 public:
  // message is valid only during the call (it is reused for the next datagram).
  using MessageHandler = std::function<void(const Message& message, const udp::endpoint& from)>;

  ProtoMulticastReceiver(boost::asio::io_context& io, MulticastEndpoint endpoint,
                         InterfaceChoice interface = {},
                         int receive_buffer_bytes = kDefaultReceiveBufferBytes)
      : receiver_(io, endpoint, interface, receive_buffer_bytes) {}

  // Opens, binds, joins and starts receiving; throws MulticastError on failure (see
  // MulticastReceiver::start()).
  void start(MessageHandler on_message) {
    on_message_ = std::move(on_message);
    receiver_.start([this](std::span<const std::byte> data, const udp::endpoint& from) {
      on_datagram(data, from);
    });
  }

  const ReceiverCounters& counters() const { return receiver_.counters(); }

 private:
  void on_datagram(std::span<const std::byte> data, const udp::endpoint& from) {
    // data.size() <= kMaxUdpPayload, so it fits in an int. ParsePartialFromArray plus
    // IsInitialized() is ParseFromArray without protobuf's own unthrottled error log per packet.
    if (!message_.ParsePartialFromArray(data.data(), static_cast<int>(data.size())) ||
        !message_.IsInitialized()) {
      receiver_.count_parse_error();
      detail::log_parse_error(receiver_, message_.GetTypeName(), data.size());
      return;
    }
    if (on_message_) on_message_(message_, from);
  }

  MessageHandler on_message_;
  Message message_;  // reused, so repeated fields keep their allocations between datagrams
  // Declared last so it is destroyed (and stopped) first: no callback sees a dead member.
  MulticastReceiver receiver_;
};

// Serialises Messages into a reused buffer and sends each as one datagram.
template <class Message>
class ProtoMulticastSender {
  static_assert(std::is_base_of_v<google::protobuf::MessageLite, Message>,
                "Message must be a generated protobuf message");

 public:
  ProtoMulticastSender(boost::asio::io_context& io, MulticastEndpoint endpoint,
                       address_v4 interface = address_v4::loopback(),
                       int ttl = kDefaultMulticastTtl)
      : sender_(io, endpoint, interface, ttl) {}

  // Throws MulticastError on failure (see MulticastSender::open()).
  void open() { sender_.open(); }

  // Returns false if the message cannot be encoded (a proto2 `required` field is missing, or it
  // is larger than one datagram: counted in encode_errors()) or the send fails (send_errors()).
  bool send(const Message& message) {
    const std::size_t size = message.ByteSizeLong();
    bool encoded = false;
    // IsInitialized() first: SerializeToArray only checks `required` fields in debug builds,
    // and there it aborts.
    if (size <= kMaxUdpPayload && message.IsInitialized()) {
      buffer_.resize(size);
      encoded = message.SerializeToArray(buffer_.data(), static_cast<int>(size));
    }
    if (!encoded) {
      const auto errors = encode_errors_.fetch_add(1, std::memory_order_relaxed) + 1;
      detail::log_encode_error(sender_, message.GetTypeName(), size, errors);
      return false;
    }
    return sender_.send(std::span<const std::byte>(buffer_.data(), size));
  }

  std::uint64_t sent() const { return sender_.sent(); }
  std::uint64_t send_errors() const { return sender_.send_errors(); }
  std::uint64_t encode_errors() const { return encode_errors_.load(std::memory_order_relaxed); }

 private:
  MulticastSender sender_;
  std::vector<std::byte> buffer_;  // reused: grows to the largest message, never shrinks
  std::atomic<std::uint64_t> encode_errors_{0};
};

}  // namespace ssl_formation::net
