#pragma once
// Byte-level UDP multicast (docs/architecture.md, "On the wire"): endpoint and interface
// parsing, a receiver and a sender on Boost.Asio's io_context. The typed protobuf layer lives in
// proto_multicast.hpp, on top of this one (like Thunderbots' ProtoUdpListener<T> over
// UdpListener).
//
// Threading: everything runs on the one thread that runs the io_context (the daemon's main
// thread); handlers run there. Only the counters may be read from other threads.
//
// Life cycle: constructors only store the configuration. MulticastReceiver::start() and
// MulticastSender::open() create the socket and throw MulticastError (a std::runtime_error) with
// a message that says what failed, with group, port and interface, and the likely cause.
// Nothing here starts a thread. As with every Asio I/O object, destroy receivers and senders
// before their io_context (declare the io_context first).
//
// Typical use in a daemon:
//
//   auto group = net::parse_multicast_endpoint(text_from_options);   // "224.5.23.2:10006"
//   if (!group) throw std::runtime_error("--vision-address: " + group.error().message);
//   auto iface = net::parse_interface(interface_text, /*allow_all=*/true).value();  // "127.0.0.1"
//   net::MulticastReceiver receiver(io, *group, iface);
//   receiver.start([](std::span<const std::byte> data, const net::udp::endpoint& from) { ... });
//   io.run();

#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address_v4.hpp>
#include <boost/asio/ip/udp.hpp>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ssl_formation/base/result.hpp"

namespace ssl_formation::net {

using udp = boost::asio::ip::udp;
using boost::asio::ip::address_v4;

// The largest payload of one UDP datagram over IPv4 (65,535 - 20 IP header - 8 UDP header).
// Receive buffers have this size, so every datagram is read whole.
inline constexpr std::size_t kMaxUdpPayload = 65507;

// Default SO_RCVBUF request: 4 MiB holds several seconds of an 8-camera SSL-Vision feed.
inline constexpr int kDefaultReceiveBufferBytes = 4 << 20;

// Default multicast TTL: 1 keeps packets on the local link.
inline constexpr int kDefaultMulticastTtl = 1;

// Thrown by MulticastReceiver::start() and MulticastSender::open() when a socket cannot be set
// up. what() names the operation, the group, the port, the interface and the likely cause.
class MulticastError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An IPv4 multicast group and a UDP port, written "224.5.23.2:10006".
struct MulticastEndpoint {
  address_v4 group;
  std::uint16_t port = 0;

  std::string to_string() const;  // "224.5.23.2:10006"
  friend bool operator==(const MulticastEndpoint&, const MulticastEndpoint&) = default;
};
std::ostream& operator<<(std::ostream& out, const MulticastEndpoint& endpoint);

// Parses "GROUP:PORT". GROUP must be an IPv4 multicast address (224.0.0.0/4) in dotted decimal,
// PORT a decimal number in 1..65535. The error is a sentence naming the text and what is wrong
// with it.
Result<MulticastEndpoint> parse_multicast_endpoint(std::string_view text);

// The interface to join on or send from: one IPv4 address of this machine, or (receivers only)
// every IPv4 interface of the machine. The default is the loopback address: nothing leaves the
// machine unless asked.
struct InterfaceChoice {
  bool all = false;
  address_v4 address = address_v4::loopback();

  std::string to_string() const;  // "127.0.0.1" or "all"
  friend bool operator==(const InterfaceChoice&, const InterfaceChoice&) = default;
};
std::ostream& operator<<(std::ostream& out, const InterfaceChoice& choice);

// Parses "all" (only if allow_all) or an IPv4 address in dotted decimal. Multicast and broadcast
// addresses are rejected (they are never the address of an interface). Whether the address
// belongs to this machine is checked by the kernel at start()/open(), with a clear error.
Result<InterfaceChoice> parse_interface(std::string_view text, bool allow_all);

// One IPv4 address of one network interface, as getifaddrs() reports it.
struct InterfaceAddress {
  std::string name;  // "lo", "eth0"
  address_v4 address;
  bool up = false;
  bool loopback = false;
  bool multicast = false;  // IFF_MULTICAST (Linux lets you join on "lo" without it)
};

// The IPv4 addresses of this machine's interfaces (getifaddrs), or why they cannot be listed.
Result<std::vector<InterfaceAddress>> ipv4_interfaces();

// Receive counters. Written on the io_context thread, readable from any thread (relaxed atomics:
// each value is exact, but a snapshot of several is not taken at one instant).
struct ReceiverCounters {
  std::atomic<std::uint64_t> datagrams{0};       // datagrams received (any content)
  std::atomic<std::uint64_t> bytes{0};           // their payload bytes
  std::atomic<std::uint64_t> receive_errors{0};  // failed waits and recvmsg() calls
  std::atomic<std::uint64_t> parse_errors{0};    // datagrams a typed layer could not decode
  // Datagrams the kernel dropped because the socket's receive buffer was full, as reported by
  // SO_RXQ_OVFL (Linux): the kernel's cumulative count, updated with each datagram that does
  // arrive (so drops show up with the next datagram delivered after them). Stays 0 where
  // SO_RXQ_OVFL is unavailable: see MulticastReceiver::kernel_drops_supported().
  std::atomic<std::uint64_t> kernel_drops{0};
};

// A datagram's bytes as the text view protobuf's parsers and the log writer take.
inline std::string_view as_text(std::span<const std::byte> data) {
  return {reinterpret_cast<const char*>(data.data()), data.size()};
}

// Receives whole datagrams sent to one multicast group and port.
//
// start() opens a UDP socket with SO_REUSEADDR (several processes can share the port), sets
// SO_RCVBUF to the requested size (0 keeps the kernel default), enables SO_RXQ_OVFL, binds to
// GROUP:PORT (binding to the group address means datagrams for other groups on the same port are
// not delivered) and joins the group on the chosen interface, or on every IPv4 interface for
// "all" (interfaces that refuse are logged and skipped; it fails only if none accepts).
//
// The receive loop waits for readability (socket.async_wait) and then reads with non-blocking
// recvmsg() until the socket is empty, so each datagram arrives whole (buffer kMaxUdpPayload) and
// the kernel's drop count comes along in a control message. The wait is re-armed after every
// readiness event, every error (which is counted and logged, rate-limited) and even when the
// callback throws, so the loop never silently stops; only stop() ends it.
class MulticastReceiver {
 public:
  // data is valid only during the call; from is the sender's address and port.
  using DatagramHandler =
      std::function<void(std::span<const std::byte> data, const udp::endpoint& from)>;

  MulticastReceiver(boost::asio::io_context& io, MulticastEndpoint endpoint,
                    InterfaceChoice interface = {},
                    int receive_buffer_bytes = kDefaultReceiveBufferBytes);
  ~MulticastReceiver();  // stop()s, which cannot throw
  MulticastReceiver(const MulticastReceiver&) = delete;
  MulticastReceiver& operator=(const MulticastReceiver&) = delete;

  // Opens, binds and joins, then starts the receive loop; handlers run on the io_context thread.
  // Throws MulticastError if a step fails (the socket is closed again), std::logic_error if
  // already started. May be called again after stop().
  void start(DatagramHandler on_datagram);

  // Ends the loop and closes the socket (leaving the group). The callback is not called after
  // stop() returns, even for datagrams already read. Safe to call from inside the callback, and
  // more than once. Never throws (only error_code calls), so the destructor can call it.
  void stop() noexcept;

  bool running() const;
  const MulticastEndpoint& endpoint() const;

  // The addresses the group was joined on (after start()).
  std::vector<address_v4> joined_interfaces() const;

  // The receive buffer (SO_RCVBUF) in effect after start() (0 before), as Asio reports it: the
  // size the kernel accepted, which on Linux is the request capped at net.core.rmem_max (the
  // kernel then doubles it for bookkeeping and Asio halves the doubled value it reads back). A
  // warning is logged when this is below the request.
  int granted_receive_buffer() const;

  // Whether SO_RXQ_OVFL could be enabled, so counters().kernel_drops is meaningful.
  bool kernel_drops_supported() const;

  const ReceiverCounters& counters() const;

  // For layers on top (the typed receiver): count a datagram whose content could not be decoded.
  void count_parse_error();

 private:
  struct State;
  std::shared_ptr<State> state_;  // shared with pending handlers, so destruction is safe
};

// Sends datagrams to one multicast group and port from one interface.
//
// open() sets IP_MULTICAST_IF to the interface (ip::multicast::outbound_interface), the multicast
// TTL (ip::multicast::hops, default 1: the packets stay on the local link) and enables multicast
// loopback, so listeners on this machine receive what it sends.
class MulticastSender {
 public:
  MulticastSender(boost::asio::io_context& io, MulticastEndpoint endpoint,
                  address_v4 interface = address_v4::loopback(), int ttl = kDefaultMulticastTtl);
  MulticastSender(const MulticastSender&) = delete;
  MulticastSender& operator=(const MulticastSender&) = delete;

  // Opens and configures the socket. Throws MulticastError naming the group, port, interface and
  // likely cause if a step fails (e.g. the interface is not an address of this machine).
  void open();
  bool is_open() const;

  // Sends one datagram synchronously (send_to; UDP does not wait for the receiver). Returns false
  // and counts a send error (logged, rate-limited) if the socket is not open or the send fails.
  bool send(std::span<const std::byte> data);

  const MulticastEndpoint& endpoint() const { return endpoint_; }
  int ttl() const { return ttl_; }

  std::uint64_t sent() const { return sent_.load(std::memory_order_relaxed); }
  std::uint64_t send_errors() const { return send_errors_.load(std::memory_order_relaxed); }

 private:
  udp::socket socket_;
  MulticastEndpoint endpoint_;
  udp::endpoint destination_;
  address_v4 interface_;
  int ttl_;
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> send_errors_{0};
};

}  // namespace ssl_formation::net
