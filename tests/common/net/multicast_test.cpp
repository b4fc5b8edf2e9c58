// Tests of the multicast layer with real sockets. Network safety: everything is sent to
// multicast groups 224.5.23.100-199 with the outgoing interface 127.0.0.1 and TTL 1, and joined
// on 127.0.0.1, so no packet leaves the machine. The foreign interface addresses below are only
// handed to setsockopt (which refuses them); nothing is ever sent to them.
//
// Each test process picks a random group and a random base port in 10100-10199, and every test
// uses its own port, so parallel runs (ctest -j) do not see each other's datagrams. Every wait is
// bounded.

#include "ssl_formation/net/multicast.hpp"

#include <gtest/gtest.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/net/vision_receiver.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::net {
namespace {

using namespace std::chrono_literals;

constexpr std::chrono::milliseconds kTimeout = 3s;

// Per-process random choices, so concurrent test processes use different groups and ports.
struct Randomness {
  Randomness() {
    std::random_device device;
    std::mt19937 generator(device());
    group = address_v4(
        {224, 5, 23,
         static_cast<unsigned char>(std::uniform_int_distribution(100, 199)(generator))});
    base_port = static_cast<std::uint16_t>(10100 + std::uniform_int_distribution(0, 79)(generator));
  }
  address_v4 group;
  std::uint16_t base_port;
};
const Randomness& randomness() {
  static const Randomness value;
  return value;
}

// A group:port unique to one test (offset 0..19 within this process's range).
MulticastEndpoint endpoint_for(int offset) {
  return MulticastEndpoint{randomness().group,
                           static_cast<std::uint16_t>(randomness().base_port + offset)};
}

const InterfaceChoice kLoopback{false, address_v4::loopback()};

// Runs io until done() or the timeout; returns done().
bool run_until(boost::asio::io_context& io, const std::function<bool()>& done,
               std::chrono::milliseconds timeout = kTimeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done() && std::chrono::steady_clock::now() < deadline) {
    io.restart();
    io.run_for(10ms);
  }
  return done();
}

// Runs io for a fixed time (to see that nothing more arrives).
void run_for(boost::asio::io_context& io, std::chrono::milliseconds duration) {
  io.restart();
  io.run_for(duration);
}

std::vector<std::byte> bytes_of(const std::string& text) {
  std::vector<std::byte> result(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) result[i] = static_cast<std::byte>(text[i]);
  return result;
}

std::vector<std::byte> pattern(std::size_t size) {
  std::vector<std::byte> result(size);
  for (std::size_t i = 0; i < size; ++i)
    result[i] = static_cast<std::byte>((i * 7 + i / 251) & 0xff);
  return result;
}

bool is_local_address(const address_v4& address) {
  for (const auto& item : ipv4_interfaces().value()) {
    if (item.address == address) return true;
  }
  return false;
}

// The destructor stop()s; a stop() that could throw would end the program from there.
static_assert(noexcept(std::declval<MulticastReceiver&>().stop()));
static_assert(std::is_nothrow_destructible_v<MulticastReceiver>);

// The message of a parse that failed, or "" for one that succeeded.
template <typename T>
std::string error_of(const Result<T>& result) {
  return result ? std::string() : result.error().message;
}

SSL_WrapperPacket detection_packet(std::uint32_t frame_number) {
  SSL_WrapperPacket packet;
  auto* frame = packet.mutable_detection();
  frame->set_frame_number(frame_number);
  frame->set_t_capture(12.5);
  frame->set_t_sent(12.51);
  frame->set_camera_id(1);
  auto* robot = frame->add_robots_yellow();
  robot->set_confidence(0.9f);
  robot->set_robot_id(3);
  robot->set_x(1000.0f);
  robot->set_y(-500.0f);
  robot->set_pixel_x(10.0f);
  robot->set_pixel_y(20.0f);
  return packet;
}

// ---------------------------------------------------------------------------------------------
// Parsing

TEST(ParseMulticastEndpoint, AcceptsGroupAndPort) {
  const auto endpoint = parse_multicast_endpoint("224.5.23.2:10006");
  ASSERT_TRUE(endpoint) << error_of(endpoint);
  EXPECT_EQ(endpoint->group, address_v4({224, 5, 23, 2}));
  EXPECT_EQ(endpoint->port, 10006);
  EXPECT_EQ(endpoint->to_string(), "224.5.23.2:10006");
  EXPECT_TRUE(parse_multicast_endpoint("239.255.255.255:1"));
  EXPECT_TRUE(parse_multicast_endpoint("224.0.0.1:65535"));
}

TEST(ParseMulticastEndpoint, RejectsUnicastAddress) {
  const auto unicast = parse_multicast_endpoint("10.0.0.1:10006");
  EXPECT_FALSE(unicast);
  const std::string error = error_of(unicast);
  EXPECT_NE(error.find("10.0.0.1"), std::string::npos) << error;
  EXPECT_NE(error.find("multicast"), std::string::npos) << error;
  EXPECT_FALSE(parse_multicast_endpoint("127.0.0.1:10006"));
  EXPECT_FALSE(parse_multicast_endpoint("240.0.0.1:10006"));
}

TEST(ParseMulticastEndpoint, RejectsMissingPort) {
  const auto no_port = parse_multicast_endpoint("224.5.23.2");
  EXPECT_FALSE(no_port);
  EXPECT_NE(error_of(no_port).find("no port"), std::string::npos) << error_of(no_port);
  const auto empty_port = parse_multicast_endpoint("224.5.23.2:");
  EXPECT_FALSE(empty_port);
  EXPECT_NE(error_of(empty_port).find("port"), std::string::npos) << error_of(empty_port);
}

TEST(ParseMulticastEndpoint, RejectsPortOutOfRange) {
  const auto too_high = parse_multicast_endpoint("224.5.23.2:99999");
  EXPECT_FALSE(too_high);
  EXPECT_NE(error_of(too_high).find("99999"), std::string::npos) << error_of(too_high);
  EXPECT_NE(error_of(too_high).find("1..65535"), std::string::npos) << error_of(too_high);
  EXPECT_FALSE(parse_multicast_endpoint("224.5.23.2:0"));
  const auto huge = parse_multicast_endpoint("224.5.23.2:99999999999999999999999");
  EXPECT_FALSE(huge);
  EXPECT_NE(error_of(huge).find("1..65535"), std::string::npos) << error_of(huge);
}

TEST(ParseMulticastEndpoint, RejectsMalformedText) {
  for (const char* text : {"", ":10006", "vision:10006", "224.5.23:10006", "224.5.23.2:10x06",
                           "224.5.23.2:-1", "224.5.23.2:+5", " 224.5.23.2:10006"}) {
    const auto endpoint = parse_multicast_endpoint(text);
    EXPECT_FALSE(endpoint) << text;
    EXPECT_FALSE(error_of(endpoint).empty()) << text;
  }
}

TEST(ParseInterface, AcceptsAddressAndAll) {
  const auto loopback = parse_interface("127.0.0.1", false);
  ASSERT_TRUE(loopback) << error_of(loopback);
  EXPECT_FALSE(loopback->all);
  EXPECT_EQ(loopback->address, address_v4::loopback());
  EXPECT_EQ(loopback->to_string(), "127.0.0.1");
  const auto all = parse_interface("all", true);
  ASSERT_TRUE(all) << error_of(all);
  EXPECT_TRUE(all->all);
  EXPECT_EQ(all->to_string(), "all");
  EXPECT_EQ(InterfaceChoice{}.address, address_v4::loopback());  // the default is 127.0.0.1
}

TEST(ParseInterface, RejectsAllForSendersAndNonAddresses) {
  const auto all_for_sender = parse_interface("all", false);
  EXPECT_FALSE(all_for_sender);
  EXPECT_NE(error_of(all_for_sender).find("all"), std::string::npos) << error_of(all_for_sender);
  const auto device_name = parse_interface("eth0", true);
  EXPECT_FALSE(device_name);
  EXPECT_NE(error_of(device_name).find("eth0"), std::string::npos) << error_of(device_name);
  EXPECT_FALSE(parse_interface("224.5.23.2", true));
  EXPECT_FALSE(parse_interface("255.255.255.255", true));
  EXPECT_FALSE(parse_interface("", true));
}

TEST(Interfaces, ListsLoopback) {
  const auto interfaces = ipv4_interfaces();
  EXPECT_TRUE(interfaces) << error_of(interfaces);
  EXPECT_TRUE(is_local_address(address_v4::loopback()));
}

// ---------------------------------------------------------------------------------------------
// Byte level, real sockets on 127.0.0.1

TEST(Multicast, RoundTrip) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(0);
  MulticastReceiver receiver(io, endpoint, kLoopback);
  std::vector<std::vector<std::byte>> received;
  udp::endpoint from;
  receiver.start([&](std::span<const std::byte> data, const udp::endpoint& sender) {
    received.emplace_back(data.begin(), data.end());
    from = sender;
  });
  EXPECT_TRUE(receiver.running());
  EXPECT_GT(receiver.granted_receive_buffer(), 0);
  ASSERT_EQ(receiver.joined_interfaces().size(), 1u);
  EXPECT_EQ(receiver.joined_interfaces()[0], address_v4::loopback());

  MulticastSender sender(io, endpoint, address_v4::loopback());
  EXPECT_EQ(sender.ttl(), 1);
  sender.open();
  const auto message = bytes_of("hello, formation");
  ASSERT_TRUE(sender.send(message));
  EXPECT_EQ(sender.sent(), 1u);
  EXPECT_EQ(sender.send_errors(), 0u);

  ASSERT_TRUE(run_until(io, [&] { return !received.empty(); }));
  EXPECT_EQ(received[0], message);
  EXPECT_EQ(from.address(), boost::asio::ip::address(address_v4::loopback()));
  EXPECT_EQ(receiver.counters().datagrams.load(), 1u);
  EXPECT_EQ(receiver.counters().bytes.load(), message.size());
  EXPECT_EQ(receiver.counters().receive_errors.load(), 0u);
  EXPECT_EQ(receiver.counters().kernel_drops.load(), 0u);
}

TEST(Multicast, LargeDatagramsArriveWhole) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(1);
  MulticastReceiver receiver(io, endpoint, kLoopback);
  std::vector<std::vector<std::byte>> received;
  receiver.start([&](std::span<const std::byte> data, const udp::endpoint&) {
    received.emplace_back(data.begin(), data.end());
  });
  MulticastSender sender(io, endpoint);
  sender.open();
  const auto large = pattern(60000);
  const auto largest = pattern(kMaxUdpPayload);
  ASSERT_TRUE(sender.send(large));
  ASSERT_TRUE(sender.send(largest));
  ASSERT_TRUE(run_until(io, [&] { return received.size() >= 2; }));
  EXPECT_EQ(received[0], large);
  EXPECT_EQ(received[1], largest);
  EXPECT_EQ(receiver.counters().bytes.load(), large.size() + largest.size());
}

TEST(Multicast, BurstLargerThanOneWakeArrivesCompletely) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(2);
  MulticastReceiver receiver(io, endpoint, kLoopback);
  std::vector<std::uint32_t> sequence;
  receiver.start([&](std::span<const std::byte> data, const udp::endpoint&) {
    ASSERT_EQ(data.size(), 4u);
    std::uint32_t value = 0;
    std::memcpy(&value, data.data(), 4);
    sequence.push_back(value);
  });
  MulticastSender sender(io, endpoint);
  sender.open();
  // More than one wake reads (256), so the re-armed wait must fire again; few enough to fit in
  // the receive buffer even where net.core.rmem_max is the default 208 KiB.
  constexpr std::uint32_t kCount = 300;
  for (std::uint32_t i = 0; i < kCount; ++i) {
    std::array<std::byte, 4> data{};
    std::memcpy(data.data(), &i, 4);
    ASSERT_TRUE(sender.send(data));
  }
  ASSERT_TRUE(run_until(io, [&] { return sequence.size() >= kCount; }))
      << "received " << sequence.size();
  for (std::uint32_t i = 0; i < kCount; ++i) EXPECT_EQ(sequence[i], i);
  EXPECT_EQ(receiver.counters().kernel_drops.load(), 0u);
}

TEST(Multicast, TwoReceiversOnTheSameGroupAndPortBothReceive) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(3);
  MulticastReceiver first(io, endpoint, kLoopback);
  MulticastReceiver second(io, endpoint, kLoopback);
  int first_count = 0;
  int second_count = 0;
  first.start([&](std::span<const std::byte>, const udp::endpoint&) { ++first_count; });
  second.start([&](std::span<const std::byte>, const udp::endpoint&) { ++second_count; });
  MulticastSender sender(io, endpoint);
  sender.open();
  ASSERT_TRUE(sender.send(bytes_of("one")));
  ASSERT_TRUE(sender.send(bytes_of("two")));
  ASSERT_TRUE(run_until(io, [&] { return first_count >= 2 && second_count >= 2; }))
      << first_count << " " << second_count;
  run_for(io, 50ms);
  EXPECT_EQ(first_count, 2);
  EXPECT_EQ(second_count, 2);
}

TEST(Multicast, DifferentPortsDoNotInterfere) {
  boost::asio::io_context io;
  const auto endpoint_a = endpoint_for(4);
  const auto endpoint_b = endpoint_for(5);
  MulticastReceiver receiver_a(io, endpoint_a, kLoopback);
  MulticastReceiver receiver_b(io, endpoint_b, kLoopback);
  std::vector<std::string> got_a;
  std::vector<std::string> got_b;
  auto text = [](std::span<const std::byte> data) {
    return std::string(reinterpret_cast<const char*>(data.data()), data.size());
  };
  receiver_a.start(
      [&](std::span<const std::byte> data, const udp::endpoint&) { got_a.push_back(text(data)); });
  receiver_b.start(
      [&](std::span<const std::byte> data, const udp::endpoint&) { got_b.push_back(text(data)); });
  MulticastSender sender_a(io, endpoint_a);
  MulticastSender sender_b(io, endpoint_b);
  sender_a.open();
  sender_b.open();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(sender_a.send(bytes_of("a" + std::to_string(i))));
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(sender_b.send(bytes_of("b" + std::to_string(i))));
  ASSERT_TRUE(run_until(io, [&] { return got_a.size() >= 3 && got_b.size() >= 2; }));
  run_for(io, 50ms);
  EXPECT_EQ(got_a, (std::vector<std::string>{"a0", "a1", "a2"}));
  EXPECT_EQ(got_b, (std::vector<std::string>{"b0", "b1"}));
}

TEST(Multicast, LoopGoesOnAfterTheCallbackThrows) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(6);
  MulticastReceiver receiver(io, endpoint, kLoopback);
  int calls = 0;
  receiver.start([&](std::span<const std::byte>, const udp::endpoint&) {
    if (++calls == 1) throw std::runtime_error("callback failure");
  });
  MulticastSender sender(io, endpoint);
  sender.open();
  ASSERT_TRUE(sender.send(bytes_of("first")));
  EXPECT_THROW(run_until(io, [&] { return calls >= 1; }), std::runtime_error);
  ASSERT_TRUE(sender.send(bytes_of("second")));
  ASSERT_TRUE(run_until(io, [&] { return calls >= 2; }));
  EXPECT_EQ(receiver.counters().datagrams.load(), 2u);
}

TEST(Multicast, StopFromTheCallbackAndRestart) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(7);
  MulticastReceiver receiver(io, endpoint, kLoopback);
  int calls = 0;
  MulticastSender sender(io, endpoint);
  sender.open();
  receiver.start([&](std::span<const std::byte>, const udp::endpoint&) {
    ++calls;
    receiver.stop();
  });
  ASSERT_TRUE(sender.send(bytes_of("one")));
  ASSERT_TRUE(sender.send(bytes_of("two")));  // already queued, but not delivered after stop()
  ASSERT_TRUE(run_until(io, [&] { return calls >= 1; }));
  run_for(io, 50ms);
  EXPECT_EQ(calls, 1);
  EXPECT_FALSE(receiver.running());

  int later = 0;
  receiver.start([&](std::span<const std::byte>, const udp::endpoint&) { ++later; });
  ASSERT_TRUE(sender.send(bytes_of("three")));
  ASSERT_TRUE(run_until(io, [&] { return later >= 1; }));
  run_for(io, 50ms);
  EXPECT_EQ(later, 1);  // a new socket: nothing left over from before the stop
}

TEST(Multicast, KernelDropsAreCounted) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(8);
  // The smallest receive buffer the kernel allows, so a burst overflows it.
  MulticastReceiver receiver(io, endpoint, kLoopback, 1);
  std::uint64_t received = 0;
  receiver.start([&](std::span<const std::byte>, const udp::endpoint&) { ++received; });
  if (!receiver.kernel_drops_supported()) GTEST_SKIP() << "SO_RXQ_OVFL is not available";
  MulticastSender sender(io, endpoint);
  sender.open();
  const auto data = pattern(1000);
  constexpr int kBurst = 100;
  for (int i = 0; i < kBurst; ++i) ASSERT_TRUE(sender.send(data));  // nobody reads meanwhile
  run_until(
      io, [&] { return false; }, 200ms);
  // Drops are reported with the next datagram delivered after them.
  ASSERT_TRUE(sender.send(data));
  ASSERT_TRUE(run_until(
      io, [&] { return received + receiver.counters().kernel_drops.load() >= kBurst + 1; }));
  EXPECT_GT(receiver.counters().kernel_drops.load(), 0u);
  EXPECT_EQ(received + receiver.counters().kernel_drops.load(), kBurst + 1u);
  EXPECT_EQ(receiver.counters().datagrams.load(), received);
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST(MulticastErrors, JoinOnAnInterfaceNotOnThisMachineNamesGroupPortAndInterface) {
  // TEST-NET-2: only handed to setsockopt(IP_ADD_MEMBERSHIP) as the interface, which refuses it.
  const address_v4 foreign({198, 51, 100, 7});
  if (is_local_address(foreign)) GTEST_SKIP() << "198.51.100.7 is an address of this machine";
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(9);
  MulticastReceiver receiver(io, endpoint, InterfaceChoice{false, foreign});
  try {
    receiver.start([](std::span<const std::byte>, const udp::endpoint&) {});
    FAIL() << "start() should have thrown";
  } catch (const MulticastError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("cannot join"), std::string::npos) << message;
    EXPECT_NE(message.find(endpoint.group.to_string()), std::string::npos) << message;
    EXPECT_NE(message.find(std::to_string(endpoint.port)), std::string::npos) << message;
    EXPECT_NE(message.find("198.51.100.7"), std::string::npos) << message;
    EXPECT_NE(message.find("--interface"), std::string::npos) << message;
  }
  EXPECT_FALSE(receiver.running());
  // The receiver can still be used after the failure: a MulticastError is a runtime_error.
  static_assert(std::is_base_of_v<std::runtime_error, MulticastError>);
}

TEST(MulticastErrors, SendingFromAnInterfaceNotOnThisMachineFailsAtOpen) {
  // Only handed to setsockopt(IP_MULTICAST_IF), which refuses it; nothing is sent.
  const address_v4 foreign({198, 51, 100, 7});
  if (is_local_address(foreign)) GTEST_SKIP() << "198.51.100.7 is an address of this machine";
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(10);
  MulticastSender sender(io, endpoint, foreign);
  try {
    sender.open();
    FAIL() << "open() should have thrown";
  } catch (const MulticastError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(endpoint.to_string()), std::string::npos) << message;
    EXPECT_NE(message.find("198.51.100.7"), std::string::npos) << message;
  }
  EXPECT_FALSE(sender.is_open());
  EXPECT_FALSE(sender.send(bytes_of("x")));  // counted, not thrown
  EXPECT_EQ(sender.send_errors(), 1u);
}

TEST(MulticastErrors, TtlOutOfRangeFailsAtOpen) {
  boost::asio::io_context io;
  MulticastSender sender(io, endpoint_for(15), address_v4::loopback(), 300);
  EXPECT_THROW(sender.open(), MulticastError);
  EXPECT_FALSE(sender.is_open());
}

TEST(MulticastErrors, BindFailureNamesThePort) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(11);
  // A socket that holds the port without SO_REUSEADDR (it never sends).
  udp::socket holder(io, udp::v4());
  boost::system::error_code ec;
  holder.bind(udp::endpoint(address_v4::any(), endpoint.port), ec);
  if (ec) GTEST_SKIP() << "port " << endpoint.port << " is busy: " << ec.message();
  MulticastReceiver receiver(io, endpoint, kLoopback);
  try {
    receiver.start([](std::span<const std::byte>, const udp::endpoint&) {});
    FAIL() << "start() should have thrown";
  } catch (const MulticastError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("cannot bind"), std::string::npos) << message;
    EXPECT_NE(message.find(std::to_string(endpoint.port)), std::string::npos) << message;
    EXPECT_NE(message.find("127.0.0.1"), std::string::npos) << message;
  }
  EXPECT_FALSE(receiver.running());
}

// ---------------------------------------------------------------------------------------------
// Typed layer

TEST(ProtoMulticast, GarbageCountsAParseErrorAndTheNextPacketArrives) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(12);
  ProtoMulticastReceiver<SSL_WrapperPacket> receiver(io, endpoint, kLoopback);
  std::vector<std::uint32_t> frames;
  receiver.start([&](const SSL_WrapperPacket& packet, const udp::endpoint&) {
    frames.push_back(packet.detection().frame_number());
  });
  MulticastSender raw(io, endpoint);
  raw.open();
  ProtoMulticastSender<SSL_WrapperPacket> sender(io, endpoint);
  sender.open();

  // Field 1 with wire type 7, which does not exist: no protobuf parser accepts it.
  const std::vector<std::byte> garbage(32, std::byte{0x0f});
  ASSERT_TRUE(raw.send(garbage));
  // A detection frame without its `required` fields: it parses as bytes but is incomplete.
  ASSERT_TRUE(raw.send(bytes_of(std::string("\x0a\x02\x08\x07", 4))));
  ASSERT_TRUE(sender.send(detection_packet(42)));

  ASSERT_TRUE(run_until(io, [&] { return !frames.empty(); }));
  EXPECT_EQ(frames, (std::vector<std::uint32_t>{42}));
  EXPECT_EQ(receiver.counters().parse_errors.load(), 2u);
  EXPECT_EQ(receiver.counters().datagrams.load(), 3u);
  EXPECT_EQ(receiver.counters().receive_errors.load(), 0u);

  ASSERT_TRUE(raw.send(garbage));
  ASSERT_TRUE(sender.send(detection_packet(43)));
  ASSERT_TRUE(run_until(io, [&] { return frames.size() >= 2; }));
  EXPECT_EQ(frames, (std::vector<std::uint32_t>{42, 43}));
  EXPECT_EQ(receiver.counters().parse_errors.load(), 3u);
}

TEST(ProtoMulticast, RoundTripKeepsTheContent) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(13);
  ProtoMulticastReceiver<SSL_WrapperPacket> receiver(io, endpoint, kLoopback);
  std::vector<SSL_WrapperPacket> received;
  receiver.start([&](const SSL_WrapperPacket& packet, const udp::endpoint& from) {
    received.push_back(packet);
    EXPECT_EQ(from.address(), boost::asio::ip::address(address_v4::loopback()));
  });
  ProtoMulticastSender<SSL_WrapperPacket> sender(io, endpoint, address_v4::loopback(), 1);
  sender.open();
  const auto packet = detection_packet(7);
  ASSERT_TRUE(sender.send(packet));
  ASSERT_TRUE(sender.send(detection_packet(8)));
  ASSERT_TRUE(run_until(io, [&] { return received.size() >= 2; }));
  EXPECT_EQ(received[0].SerializeAsString(), packet.SerializeAsString());
  EXPECT_EQ(received[1].detection().frame_number(), 8u);
  EXPECT_EQ(received[1].detection().robots_yellow_size(), 1);
  EXPECT_EQ(sender.sent(), 2u);
}

TEST(ProtoMulticast, AnIncompleteMessageIsNotSent) {
  boost::asio::io_context io;
  ProtoMulticastSender<SSL_WrapperPacket> sender(io, endpoint_for(14));
  sender.open();
  SSL_WrapperPacket incomplete;
  incomplete.mutable_detection()->set_frame_number(1);  // t_capture, t_sent, camera_id missing
  EXPECT_FALSE(sender.send(incomplete));
  EXPECT_EQ(sender.encode_errors(), 1u);
  EXPECT_EQ(sender.sent(), 0u);
}

// ---------------------------------------------------------------------------------------------
// Vision layer: VisionReceiver decodes detection packets itself and leaves the rest to protobuf.

TEST(VisionReceiver, DecodesDetectionsItselfAndLeavesEverythingElseToProtobuf) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(16);
  VisionReceiver receiver(io, endpoint, kLoopback);
  std::vector<std::string> seen;  // one line per frame handed on, in order
  receiver.start([&](const VisionFrame& frame, const udp::endpoint&) {
    std::string line = frame.has_detection
                           ? "detection " + std::to_string(frame.detection.frame_number) + " " +
                                 std::to_string(frame.detection.robots_yellow.size())
                           : "no detection";
    if (frame.has_geometry) line += " geometry " + std::to_string(frame.field_length);
    seen.push_back(line);
  });
  MulticastSender raw(io, endpoint);
  raw.open();
  ProtoMulticastSender<SSL_WrapperPacket> sender(io, endpoint);
  sender.open();

  ASSERT_TRUE(sender.send(detection_packet(42)));  // the fast path
  SSL_WrapperPacket geometry;
  auto* field = geometry.mutable_geometry()->mutable_field();
  field->set_field_length(9000);
  field->set_field_width(6000);
  field->set_goal_width(1000);
  field->set_goal_depth(180);
  field->set_boundary_width(300);
  ASSERT_TRUE(sender.send(geometry));  // protobuf's
  const std::vector<std::byte> garbage(32, std::byte{0x0f});
  ASSERT_TRUE(raw.send(garbage));  // a parse error
  // A field our schema does not know (number 15, a varint): valid, but protobuf's to read.
  std::string unknown_field = detection_packet(43).SerializeAsString() + std::string("\x78\x01", 2);
  ASSERT_TRUE(raw.send(std::as_bytes(std::span(unknown_field.data(), unknown_field.size()))));

  ASSERT_TRUE(run_until(io, [&] { return seen.size() >= 3; }));
  EXPECT_EQ(seen, (std::vector<std::string>{"detection 42 1", "no detection geometry 9000",
                                            "detection 43 1"}));
  EXPECT_EQ(receiver.direct_decodes(), 1u);
  EXPECT_EQ(receiver.counters().parse_errors.load(), 1u);
  EXPECT_EQ(receiver.counters().datagrams.load(), 4u);
}

TEST(VisionReceiver, AFailedSecondStartKeepsTheRunningHandler) {
  boost::asio::io_context io;
  const auto endpoint = endpoint_for(17);
  VisionReceiver receiver(io, endpoint, kLoopback);
  std::vector<std::uint32_t> first;
  receiver.start([&](const VisionFrame& frame, const udp::endpoint&) {
    first.push_back(frame.detection.frame_number);
  });
  bool second_called = false;
  EXPECT_THROW(
      receiver.start([&](const VisionFrame&, const udp::endpoint&) { second_called = true; }),
      std::logic_error);
  ProtoMulticastSender<SSL_WrapperPacket> sender(io, endpoint);
  sender.open();
  ASSERT_TRUE(sender.send(detection_packet(7)));
  ASSERT_TRUE(run_until(io, [&] { return !first.empty(); }));
  EXPECT_EQ(first, (std::vector<std::uint32_t>{7}));
  EXPECT_FALSE(second_called);
}

}  // namespace
}  // namespace ssl_formation::net
