#include "ssl_formation/net/multicast.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/types.h>

#include <algorithm>
#include <boost/asio/buffer.hpp>
#include <boost/asio/ip/multicast.hpp>
#include <boost/asio/socket_base.hpp>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <exception>
#include <ostream>
#include <system_error>
#include <utility>

namespace ssl_formation::net {

namespace {

using boost::system::error_code;

// Errors that can repeat at packet rate are logged for the first few and then every 1000th.
bool worth_logging(std::uint64_t count) { return count <= 10 || count % 1000 == 0; }

// At most this many datagrams are read per readiness event before other handlers get a turn;
// the re-armed wait fires again at once if more are queued.
constexpr int kMaxDatagramsPerWake = 256;

std::string quoted(std::string_view text) { return "'" + std::string(text) + "'"; }

std::optional<address_v4> parse_ipv4(std::string_view text) {
  error_code ec;
  const address_v4 address = boost::asio::ip::make_address_v4(std::string(text), ec);
  if (ec) return std::nullopt;
  return address;
}

// Likely cause of a failed join, as advice for the user.
std::string join_advice(int error, const address_v4& interface) {
  switch (error) {
    case ENODEV:
    case EADDRNOTAVAIL:
      return "; is " + interface.to_string() +
             " an address of this machine? try --interface all or --interface 127.0.0.1";
    case ENOBUFS:
      return "; too many multicast memberships on this machine (see sysctl "
             "net.ipv4.igmp_max_memberships)";
    case EINVAL:
      return "; the group or interface address is not valid for a join";
    default:
      return "";
  }
}

std::string bind_advice(int error, std::uint16_t port) {
  switch (error) {
    case EADDRINUSE:
      return "; another program holds port " + std::to_string(port) +
             " without SO_REUSEADDR (find it with: ss -ulpn 'sport = :" + std::to_string(port) +
             "')";
    case EACCES:
      return "; ports below 1024 need privileges, choose another port";
    case EADDRNOTAVAIL:
      return "; this system does not allow binding to the multicast group address";
    default:
      return "";
  }
}

// The interface part of getifaddrs' name: "eth0:1" (an address label) belongs to "eth0".
std::string device_of(const std::string& name) { return name.substr(0, name.find(':')); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Parsing

std::string MulticastEndpoint::to_string() const {
  return group.to_string() + ":" + std::to_string(port);
}

std::ostream& operator<<(std::ostream& out, const MulticastEndpoint& endpoint) {
  return out << endpoint.to_string();
}

Result<MulticastEndpoint> parse_multicast_endpoint(std::string_view text) {
  const auto fail = [&](const std::string& why) {
    return ssl_formation::fail(quoted(text) + ": " + why);
  };
  const auto colon = text.rfind(':');
  if (colon == std::string_view::npos) {
    return fail("no port; expected GROUP:PORT, e.g. 224.5.23.2:10006");
  }
  const std::string_view group_text = text.substr(0, colon);
  const std::string_view port_text = text.substr(colon + 1);
  const auto group = parse_ipv4(group_text);
  if (!group) {
    return fail(quoted(group_text) +
                " is not an IPv4 address; expected GROUP:PORT, e.g. 224.5.23.2:10006");
  }
  if (!group->is_multicast()) {
    return fail(group->to_string() +
                " is not an IPv4 multicast address (224.0.0.0 to 239.255.255.255)");
  }
  unsigned long port = 0;
  const char* const first = port_text.data();
  const char* const last = port_text.data() + port_text.size();
  const auto [end, ec] = std::from_chars(first, last, port);
  if (port_text.empty() || ec == std::errc::invalid_argument || end != last) {
    return fail("port " + quoted(port_text) + " is not a number");
  }
  if (ec == std::errc::result_out_of_range || port < 1 || port > 65535) {
    return fail("port " + std::string(port_text) + " is not in 1..65535");
  }
  return MulticastEndpoint{*group, static_cast<std::uint16_t>(port)};
}

std::string InterfaceChoice::to_string() const { return all ? "all" : address.to_string(); }

std::ostream& operator<<(std::ostream& out, const InterfaceChoice& choice) {
  return out << choice.to_string();
}

Result<InterfaceChoice> parse_interface(std::string_view text, bool allow_all) {
  const auto fail = [&](const std::string& why) {
    return ssl_formation::fail("interface " + quoted(text) + ": " + why);
  };
  if (text == "all") {
    if (!allow_all) return fail("'all' is only accepted for receiving; give one IPv4 address");
    return InterfaceChoice{true, address_v4::any()};
  }
  const auto address = parse_ipv4(text);
  if (!address) {
    return fail(std::string("expected the IPv4 address of a network interface, e.g. 127.0.0.1") +
                (allow_all ? ", or 'all'" : ""));
  }
  if (address->is_multicast() || *address == address_v4::broadcast()) {
    return fail(address->to_string() + " cannot be the address of an interface");
  }
  return InterfaceChoice{false, *address};
}

Result<std::vector<InterfaceAddress>> ipv4_interfaces() {
  std::vector<InterfaceAddress> result;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0)
    return fail(std::string("getifaddrs failed: ") + std::strerror(errno));
  for (const ifaddrs* entry = list; entry != nullptr; entry = entry->ifa_next) {
    if (entry->ifa_addr == nullptr || entry->ifa_addr->sa_family != AF_INET) continue;
    sockaddr_in address{};
    std::memcpy(&address, entry->ifa_addr, sizeof address);
    InterfaceAddress item;
    item.name = entry->ifa_name ? entry->ifa_name : "";
    item.address = address_v4(ntohl(address.sin_addr.s_addr));
    item.up = (entry->ifa_flags & IFF_UP) != 0;
    item.loopback = (entry->ifa_flags & IFF_LOOPBACK) != 0;
    item.multicast = (entry->ifa_flags & IFF_MULTICAST) != 0;
    result.push_back(std::move(item));
  }
  ::freeifaddrs(list);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Receiver

struct MulticastReceiver::State {
  State(boost::asio::io_context& io, MulticastEndpoint endpoint_, InterfaceChoice interface_,
        int requested)
      : socket(io),
        endpoint(endpoint_),
        interface(interface_),
        requested_buffer(requested),
        buffer(kMaxUdpPayload) {}

  std::string describe() const {
    return endpoint.to_string() + " on interface " + interface.to_string();
  }

  udp::socket socket;
  MulticastEndpoint endpoint;
  InterfaceChoice interface;
  int requested_buffer;
  int granted_buffer = 0;
  bool drops_supported = false;
  std::vector<address_v4> joined;
  // Replaced by start(); a wake keeps its own copy, so stop()/start() from inside the callback
  // never destroys the function that is running.
  std::shared_ptr<const DatagramHandler> handler;
  bool running = false;
  std::uint64_t generation = 0;  // bumped by start() and stop(): stale handlers see a mismatch
  ReceiverCounters counters;
  std::vector<std::byte> buffer;  // one whole datagram (kMaxUdpPayload)

  static void arm(const std::shared_ptr<State>& self);
  static void rearm(const std::shared_ptr<State>& self, std::uint64_t generation);
  static void on_readable(const std::shared_ptr<State>& self, std::uint64_t generation,
                          const error_code& ec);
  void drain(std::uint64_t generation);
  void join(const address_v4& on);
  void join_all();
  [[noreturn]] void fail(const std::string& message);
};

void MulticastReceiver::State::fail(const std::string& message) {
  error_code ignored;
  socket.close(ignored);
  joined.clear();
  throw MulticastError(message);
}

void MulticastReceiver::State::arm(const std::shared_ptr<State>& self) {
  self->socket.async_wait(udp::socket::wait_read,
                          [self, generation = self->generation](const error_code& ec) {
                            on_readable(self, generation, ec);
                          });
}

void MulticastReceiver::State::rearm(const std::shared_ptr<State>& self, std::uint64_t generation) {
  // Not after stop() (or a restart, which armed its own wait) from inside the handler.
  if (!self->running || generation != self->generation) return;
  arm(self);
}

void MulticastReceiver::State::on_readable(const std::shared_ptr<State>& self,
                                           std::uint64_t generation, const error_code& ec) {
  if (!self->running || generation != self->generation) return;  // stopped or restarted
  // Re-armed when this returns, whatever happens below (an error, a throwing callback): the loop
  // goes on. Only one wait is ever outstanding, since each completion arms one. Arming costs a
  // system call (epoll_ctl), so it comes after the datagrams are handled, not before: a datagram
  // that arrives meanwhile is not lost, the edge-triggered wait fires at once for a socket that is
  // already readable. (Not in a scope guard's destructor: a failure to arm must be able to leave
  // run(), and a destructor that throws ends the program if it runs during unwinding.)
  try {
    if (ec) {
      const auto errors = self->counters.receive_errors.fetch_add(1, std::memory_order_relaxed) + 1;
      if (worth_logging(errors)) {
        spdlog::warn("multicast receiver {}: wait failed: {} (error {}, re-armed)",
                     self->describe(), ec.message(), errors);
      }
    } else {
      self->drain(generation);
    }
  } catch (...) {
    // The callback's exception leaves io_context::run() as it always did; the loop is armed
    // first, so it goes on when run() is called again. A failure to arm now is only logged:
    // the callback's exception is the one that goes on.
    try {
      rearm(self, generation);
    } catch (const std::exception& e) {
      spdlog::error("multicast receiver {}: cannot wait for the next datagram: {}",
                    self->describe(), e.what());
    } catch (...) {
      spdlog::error("multicast receiver {}: cannot wait for the next datagram", self->describe());
    }
    throw;
  }
  // A failure to arm (only bad_alloc in practice) leaves io_context::run(), as it always did.
  rearm(self, generation);
}

void MulticastReceiver::State::drain(std::uint64_t generation_at_wake) {
  const std::shared_ptr<const DatagramHandler> on_datagram = handler;
  const int fd = socket.native_handle();
  for (int i = 0; i < kMaxDatagramsPerWake; ++i) {
    if (!running || generation != generation_at_wake) return;
    sockaddr_in from{};
    iovec data{buffer.data(), buffer.size()};
    alignas(cmsghdr) unsigned char control[CMSG_SPACE(sizeof(std::uint32_t)) * 2];
    msghdr message{};
    message.msg_name = &from;
    message.msg_namelen = sizeof from;
    message.msg_iov = &data;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof control;
    const ssize_t received = ::recvmsg(fd, &message, MSG_DONTWAIT);
    if (received < 0) {
      const int error = errno;
      if (error == EAGAIN || error == EWOULDBLOCK) return;  // empty: wait for the next datagram
      if (error == EINTR) continue;
      const auto errors = counters.receive_errors.fetch_add(1, std::memory_order_relaxed) + 1;
      if (worth_logging(errors)) {
        spdlog::warn("multicast receiver {}: recvmsg failed: {} (error {}, re-armed)", describe(),
                     std::strerror(error), errors);
      }
      return;  // the wait is armed: if the socket is still readable it fires again at once
    }
    // No truncation check: the buffer holds the largest IPv4 UDP payload, so none can happen.
#ifdef SO_RXQ_OVFL
    for (cmsghdr* item = CMSG_FIRSTHDR(&message); item != nullptr;
         item = CMSG_NXTHDR(&message, item)) {
      if (item->cmsg_level == SOL_SOCKET && item->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t drops = 0;
        std::memcpy(&drops, CMSG_DATA(item), sizeof drops);
        const auto before = counters.kernel_drops.exchange(drops, std::memory_order_relaxed);
        if (drops != before) {
          spdlog::warn(
              "multicast receiver {}: the kernel dropped {} datagrams so far (receive buffer "
              "full; granted {} bytes, raise --receive-buffer or net.core.rmem_max)",
              describe(), drops, granted_buffer);
        }
      }
    }
#endif
    const auto size = static_cast<std::size_t>(received);
    counters.datagrams.fetch_add(1, std::memory_order_relaxed);
    counters.bytes.fetch_add(size, std::memory_order_relaxed);
    const udp::endpoint sender(address_v4(ntohl(from.sin_addr.s_addr)), ntohs(from.sin_port));
    if (on_datagram && *on_datagram) (*on_datagram)(std::span(buffer.data(), size), sender);
  }
}

void MulticastReceiver::State::join(const address_v4& on) {
  error_code ec;
  socket.set_option(boost::asio::ip::multicast::join_group(endpoint.group, on), ec);
  if (ec == boost::asio::error::address_in_use) ec.clear();  // already a member there
  if (ec) {
    fail("cannot join " + endpoint.group.to_string() + " (port " + std::to_string(endpoint.port) +
         ") on interface " + on.to_string() + ": " + ec.message() + join_advice(ec.value(), on));
  }
  joined.push_back(on);
}

void MulticastReceiver::State::join_all() {
  const std::string cannot_join = "cannot join " + endpoint.group.to_string() + " (port " +
                                  std::to_string(endpoint.port) +
                                  ") on any interface (--interface all): ";
  const auto interfaces = ipv4_interfaces();
  if (!interfaces) fail(cannot_join + interfaces.error().message);
  std::vector<std::string> devices;
  std::string failures;
  for (const auto& item : *interfaces) {
    if (!item.up) continue;
    // One membership per device: a second address of the same device would only repeat it.
    const std::string device = device_of(item.name);
    if (std::find(devices.begin(), devices.end(), device) != devices.end()) continue;
    error_code ec;
    socket.set_option(boost::asio::ip::multicast::join_group(endpoint.group, item.address), ec);
    if (ec == boost::asio::error::address_in_use) ec.clear();
    if (ec) {
      spdlog::warn("multicast receiver {}: cannot join on {} ({}): {}; skipped", describe(),
                   item.name, item.address.to_string(), ec.message());
      failures += "; " + item.name + " " + item.address.to_string() + ": " + ec.message();
      continue;
    }
    devices.push_back(device);
    joined.push_back(item.address);
  }
  if (joined.empty()) {
    fail(cannot_join +
         (failures.empty() ? std::string("no IPv4 interface is up") : failures.substr(2)));
  }
}

MulticastReceiver::MulticastReceiver(boost::asio::io_context& io, MulticastEndpoint endpoint,
                                     InterfaceChoice interface, int receive_buffer_bytes)
    : state_(std::make_shared<State>(io, endpoint, interface, receive_buffer_bytes)) {}

MulticastReceiver::~MulticastReceiver() { stop(); }

void MulticastReceiver::start(DatagramHandler on_datagram) {
  State& s = *state_;
  if (s.running) throw std::logic_error("MulticastReceiver::start: already started");
  ++s.generation;
  s.joined.clear();
  s.granted_buffer = 0;
  s.drops_supported = false;
  const std::string where = s.describe();

  error_code ec;
  s.socket.open(udp::v4(), ec);
  if (ec) s.fail("cannot open a UDP socket to receive " + where + ": " + ec.message());

  s.socket.set_option(udp::socket::reuse_address(true), ec);
  if (ec) s.fail("cannot set SO_REUSEADDR to receive " + where + ": " + ec.message());

  if (s.requested_buffer > 0) {
    s.socket.set_option(boost::asio::socket_base::receive_buffer_size(s.requested_buffer), ec);
    if (ec) {
      spdlog::warn("multicast receiver {}: cannot set SO_RCVBUF to {} bytes: {}", where,
                   s.requested_buffer, ec.message());
    }
  }
  boost::asio::socket_base::receive_buffer_size granted;
  s.socket.get_option(granted, ec);
  s.granted_buffer = ec ? 0 : granted.value();
  if (s.requested_buffer > 0 && s.granted_buffer < s.requested_buffer) {
    spdlog::warn(
        "multicast receiver {}: asked for a {} byte receive buffer, the kernel granted {}; "
        "raise net.core.rmem_max (sysctl -w net.core.rmem_max={}) to avoid drops at bursts",
        where, s.requested_buffer, s.granted_buffer, s.requested_buffer);
  }

#ifdef SO_RXQ_OVFL
  {
    const int on = 1;
    s.drops_supported =
        ::setsockopt(s.socket.native_handle(), SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) == 0;
    if (!s.drops_supported) {
      spdlog::warn(
          "multicast receiver {}: SO_RXQ_OVFL unavailable ({}); kernel drops are not "
          "counted",
          where, std::strerror(errno));
    }
  }
#endif
#ifdef IP_MULTICAST_ALL
  {
    // Deliver only the groups this socket joined, not every group any socket on the machine
    // joined on this port (Linux's default).
    const int off = 0;
    ::setsockopt(s.socket.native_handle(), IPPROTO_IP, IP_MULTICAST_ALL, &off, sizeof off);
  }
#endif

  s.socket.bind(udp::endpoint(s.endpoint.group, s.endpoint.port), ec);
  if (ec) {
    s.fail("cannot bind UDP port " + std::to_string(s.endpoint.port) + " on " +
           s.endpoint.group.to_string() + " (interface " + s.interface.to_string() +
           "): " + ec.message() + bind_advice(ec.value(), s.endpoint.port));
  }

  if (s.interface.all) {
    s.join_all();
  } else {
    s.join(s.interface.address);
  }

  s.handler = std::make_shared<const DatagramHandler>(std::move(on_datagram));
  s.running = true;
  State::arm(state_);

  std::string joined;
  for (const auto& address : s.joined) joined += (joined.empty() ? "" : ", ") + address.to_string();
  spdlog::info("listening on {} (joined on {}; receive buffer {} bytes)", s.endpoint.to_string(),
               joined, s.granted_buffer);
}

void MulticastReceiver::stop() noexcept {
  State& s = *state_;
  if (!s.running && !s.socket.is_open()) return;
  s.running = false;
  ++s.generation;
  error_code ignored;
  s.socket.close(ignored);  // cancels the wait (it completes with operation_aborted and returns)
}

bool MulticastReceiver::running() const { return state_->running; }
const MulticastEndpoint& MulticastReceiver::endpoint() const { return state_->endpoint; }
std::vector<address_v4> MulticastReceiver::joined_interfaces() const { return state_->joined; }
int MulticastReceiver::granted_receive_buffer() const { return state_->granted_buffer; }
bool MulticastReceiver::kernel_drops_supported() const { return state_->drops_supported; }
const ReceiverCounters& MulticastReceiver::counters() const { return state_->counters; }

void MulticastReceiver::count_parse_error() {
  state_->counters.parse_errors.fetch_add(1, std::memory_order_relaxed);
}

// ---------------------------------------------------------------------------------------------
// Sender

MulticastSender::MulticastSender(boost::asio::io_context& io, MulticastEndpoint endpoint,
                                 address_v4 interface, int ttl)
    : socket_(io),
      endpoint_(endpoint),
      destination_(endpoint.group, endpoint.port),
      interface_(interface),
      ttl_(ttl) {}

void MulticastSender::open() {
  const std::string where = endpoint_.to_string() + " from interface " + interface_.to_string();
  auto fail = [&](const std::string& what, const error_code& ec, const std::string& advice) {
    error_code ignored;
    socket_.close(ignored);
    throw MulticastError("cannot " + what + " to send to " + where + ": " + ec.message() + advice);
  };
  if (socket_.is_open()) return;
  if (ttl_ < 0 || ttl_ > 255) {
    throw MulticastError("cannot send to " + where + ": multicast TTL " + std::to_string(ttl_) +
                         " is not in 0..255");
  }
  error_code ec;
  socket_.open(udp::v4(), ec);
  if (ec) fail("open a UDP socket", ec, "");
  socket_.set_option(boost::asio::ip::multicast::outbound_interface(interface_), ec);
  if (ec) {
    fail("set the outgoing interface", ec,
         "; is " + interface_.to_string() +
             " an address of this machine? try --interface 127.0.0.1 or the address of the "
             "network card that should send");
  }
  socket_.set_option(boost::asio::ip::multicast::hops(ttl_), ec);
  if (ec) fail("set the multicast TTL to " + std::to_string(ttl_), ec, "");
  socket_.set_option(boost::asio::ip::multicast::enable_loopback(true), ec);
  if (ec) fail("enable multicast loopback", ec, "");
  spdlog::info("sending to {} from interface {} (TTL {})", endpoint_.to_string(),
               interface_.to_string(), ttl_);
}

bool MulticastSender::is_open() const { return socket_.is_open(); }

bool MulticastSender::send(std::span<const std::byte> data) {
  error_code ec;
  if (!socket_.is_open()) {
    ec = boost::asio::error::not_connected;
  } else {
    socket_.send_to(boost::asio::buffer(data.data(), data.size()), destination_, 0, ec);
  }
  if (ec) {
    const auto errors = send_errors_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (worth_logging(errors)) {
      spdlog::warn("cannot send {} bytes to {} from interface {}: {} (error {})", data.size(),
                   endpoint_.to_string(), interface_.to_string(),
                   socket_.is_open() ? ec.message() : std::string("socket not open"), errors);
    }
    return false;
  }
  sent_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

}  // namespace ssl_formation::net
