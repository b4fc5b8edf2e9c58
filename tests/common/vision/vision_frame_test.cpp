// decode_detection_datagram(), the daemons' fast path for vision datagrams, held to its promise:
// whenever it decodes a datagram, protobuf (the reference) accepts the same bytes and
// to_vision_frame() on its packet gives the same frame; and it refuses everything it leaves to
// protobuf. Checked on hand-written wire bytes for each rule of the fast path, on every packet of
// the grSim log and of the fuzz corpus, on random damage and random near-valid packets, and
// through the sampler fed either way.

#include "ssl_formation/vision/vision_frame.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;

const fs::path grsim_log = fs::path(SSLF_TEST_DATA_DIR) / "grsim-4cam-11v11-idle.log.gz";
const fs::path fuzz_corpus_dir = fs::path(SSLF_TEST_DATA_DIR).parent_path() / "fuzz" / "corpus";

std::span<const std::byte> bytes_of(std::string_view datagram) {
  return std::as_bytes(std::span<const char>(datagram.data(), datagram.size()));
}

// For failure messages: the bytes that broke a promise, ready to paste into a new test.
std::string hex(std::string_view bytes) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string out;
  for (const char c : bytes) {
    const auto byte = static_cast<unsigned char>(c);
    if (!out.empty()) out += ' ';
    out += digits[byte >> 4];
    out += digits[byte & 0xFU];
  }
  return out;
}

// ---- The protobuf wire format, written by hand
// (https://protobuf.dev/programming-guides/encoding/)

namespace wire {

enum Type : std::uint32_t { varint_type = 0, fixed64_type = 1, bytes_type = 2, fixed32_type = 5 };
constexpr std::array<Type, 4> all_types{varint_type, fixed64_type, bytes_type, fixed32_type};

std::string varint(std::uint64_t value) {
  std::string out;
  while (value >= 0x80) {
    out += static_cast<char>((value & 0x7FU) | 0x80U);
    value >>= 7;
  }
  out += static_cast<char>(value);
  return out;
}

// `value` in `length` bytes, padded with continuation bytes: protobuf reads the same value.
std::string padded_varint(std::uint64_t value, std::size_t length) {
  std::string out = varint(value);
  if (out.size() >= length) return out;
  out.back() = static_cast<char>(out.back() | 0x80);
  out.append(length - out.size() - 1, '\x80');
  out += '\0';
  return out;
}

std::string key(std::uint32_t field, std::uint32_t type) {
  return varint(std::uint64_t{field} << 3 | type);
}

std::string little_endian(std::uint64_t value, int bytes) {
  std::string out;
  for (int i = 0; i < bytes; ++i) out += static_cast<char>(value >> (8 * i));
  return out;
}

std::string varint_field(std::uint32_t field, std::uint64_t value) {
  return key(field, varint_type) + varint(value);
}
std::string float_field(std::uint32_t field, float value) {
  return key(field, fixed32_type) + little_endian(std::bit_cast<std::uint32_t>(value), 4);
}
std::string double_field(std::uint32_t field, double value) {
  return key(field, fixed64_type) + little_endian(std::bit_cast<std::uint64_t>(value), 8);
}
std::string bytes_field(std::uint32_t field, std::string_view contents) {
  return key(field, bytes_type) + varint(contents.size()) + std::string(contents);
}

// A well-formed field of any number and wire type, for unknown fields and wrong wire types.
std::string any_field(std::uint32_t field, Type type) {
  switch (type) {
    case varint_type:
      return varint_field(field, 300);
    case fixed64_type:
      return double_field(field, 2.5);
    case bytes_type:
      return bytes_field(field, "\x08\x01");
    case fixed32_type:
      return float_field(field, 2.5F);
  }
  return {};
}

}  // namespace wire

// A message as its encoded fields, in order, so that a test can leave one out, repeat or damage it.
struct Field {
  std::uint32_t number = 0;
  std::string bytes;  // key and value
};
using Message = std::vector<Field>;

std::string encode(const Message& message) {
  std::string out;
  for (const Field& field : message) out += field.bytes;
  return out;
}

// Every field number below 16 has a one-byte key, whose low three bits are the wire type.
wire::Type type_of(const Field& field) {
  return static_cast<wire::Type>(static_cast<unsigned char>(field.bytes[0]) & 7U);
}

Message without(Message message, std::uint32_t number) {
  std::erase_if(message, [&](const Field& field) { return field.number == number; });
  return message;
}

// The first field with this number, once more at the end.
Message twice(Message message, std::uint32_t number) {
  const auto it = std::find_if(message.begin(), message.end(),
                               [&](const Field& field) { return field.number == number; });
  if (it != message.end()) message.push_back(*it);
  return message;
}

// The first field with this number replaced by `bytes`.
Message replaced(Message message, std::uint32_t number, std::string bytes) {
  for (Field& field : message) {
    if (field.number == number) {
      field.bytes = std::move(bytes);
      break;
    }
  }
  return message;
}

// ---- A reference datagram with every field of every message, and ways to damage one message

Message reference_robot(std::uint32_t robot_id, float x, float y) {
  using namespace wire;
  return {{1, float_field(1, 0.875F)}, {2, varint_field(2, robot_id)}, {3, float_field(3, x)},
          {4, float_field(4, y)},      {5, float_field(5, -1.25F)},    {6, float_field(6, 412.5F)},
          {7, float_field(7, 96.75F)}, {8, float_field(8, 140.0F)}};
}

Message reference_ball() {
  using namespace wire;
  return {{1, float_field(1, 0.75F)},   {2, varint_field(2, 64)},  {3, float_field(3, 10.5F)},
          {4, float_field(4, -20.25F)}, {5, float_field(5, 0.0F)}, {6, float_field(6, 391.0F)},
          {7, float_field(7, 288.0F)}};
}

constexpr std::uint32_t reference_frame_number = 123456;
constexpr double reference_t_capture = 1700000000.125;
constexpr std::uint32_t reference_camera_id = 3;

// Two yellow robots (the first is `yellow_robot`) and one blue, after a ball.
Message reference_frame(const Message& ball, const Message& yellow_robot) {
  using namespace wire;
  return {{1, varint_field(1, reference_frame_number)},
          {2, double_field(2, reference_t_capture)},
          {3, double_field(3, 1700000000.25)},
          {4, varint_field(4, reference_camera_id)},
          {5, bytes_field(5, encode(ball))},
          {6, bytes_field(6, encode(yellow_robot))},
          {6, bytes_field(6, encode(reference_robot(4, -1500.5F, 2250.0F)))},
          {7, bytes_field(7, encode(reference_robot(9, 10.0F, -20.0F)))},
          {8, double_field(8, 1700000000.0625)}};
}

Message reference_wrapper(const Message& frame) {
  return {{1, wire::bytes_field(1, encode(frame))}};
}

enum class Level { wrapper, frame, robot, ball };
constexpr std::array<Level, 4> all_levels{Level::wrapper, Level::frame, Level::robot, Level::ball};

// The first field number the message's schema does not define.
std::uint32_t first_unknown_field(Level level) {
  switch (level) {
    case Level::wrapper:
      return 4;
    case Level::ball:
      return 8;
    case Level::frame:
    case Level::robot:
      return 9;
  }
  return 0;
}

const char* to_string(Level level) {
  switch (level) {
    case Level::wrapper:
      return "wrapper";
    case Level::frame:
      return "frame";
    case Level::robot:
      return "robot";
    case Level::ball:
      return "ball";
  }
  return "?";
}

using Damage = std::function<Message(Message)>;

// The reference datagram with `damage` done to the message at `level` (for a robot, the first
// yellow one; the others stay intact).
std::string datagram_with(Level level, const Damage& damage) {
  const auto at = [&](Level here, Message message) {
    return here == level ? damage(std::move(message)) : message;
  };
  const Message robot = at(Level::robot, reference_robot(7, 1234.5F, -678.25F));
  const Message ball = at(Level::ball, reference_ball());
  const Message frame = at(Level::frame, reference_frame(ball, robot));
  return encode(at(Level::wrapper, reference_wrapper(frame)));
}

std::string reference_datagram() {
  return datagram_with(Level::wrapper, [](Message message) { return message; });
}

// The field labels of each nested message's schema (the reference fills every field).
struct Schema {
  Level level;
  std::vector<std::uint32_t> required;
  std::vector<std::uint32_t> optional;  // singular
  std::vector<std::uint32_t> repeated;
};
const std::array<Schema, 3> nested_schemas{{
    {Level::frame, {1, 2, 3, 4}, {8}, {5, 6, 7}},
    {Level::robot, {1, 3, 4, 6, 7}, {2, 5, 8}, {}},
    {Level::ball, {1, 3, 4, 6, 7}, {2, 5}, {}},
}};

// ---- The promise, checked on one datagram

bool same_bits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}
bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

::testing::AssertionResult same_robots(const char* team, const std::vector<VisionRobot>& expected,
                                       const std::vector<VisionRobot>& actual) {
  if (expected.size() != actual.size()) {
    return ::testing::AssertionFailure()
           << team << ": " << actual.size() << " robots, expected " << expected.size();
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const VisionRobot& e = expected[i];
    const VisionRobot& a = actual[i];
    if (e.has_robot_id != a.has_robot_id || e.robot_id != a.robot_id || !same_bits(e.x, a.x) ||
        !same_bits(e.y, a.y) || !same_bits(e.confidence, a.confidence)) {
      return ::testing::AssertionFailure()
             << team << " robot " << i << ": id " << a.robot_id << " (has " << a.has_robot_id
             << ") at (" << a.x << ", " << a.y << ") confidence " << a.confidence
             << ", expected id " << e.robot_id << " (has " << e.has_robot_id << ") at (" << e.x
             << ", " << e.y << ") confidence " << e.confidence;
    }
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult same_balls(const std::vector<VisionBall>& expected,
                                      const std::vector<VisionBall>& actual) {
  if (expected.size() != actual.size()) {
    return ::testing::AssertionFailure() << actual.size() << " balls, expected " << expected.size();
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const VisionBall& e = expected[i];
    const VisionBall& a = actual[i];
    if (!same_bits(e.x, a.x) || !same_bits(e.y, a.y) || !same_bits(e.confidence, a.confidence)) {
      return ::testing::AssertionFailure()
             << "ball " << i << " at (" << a.x << ", " << a.y << ") confidence " << a.confidence
             << ", expected (" << e.x << ", " << e.y << ") confidence " << e.confidence;
    }
  }
  return ::testing::AssertionSuccess();
}

// Field by field, floats bit for bit (a NaN equals the same NaN).
::testing::AssertionResult same_frame(const VisionFrame& expected, const VisionFrame& actual) {
  if (expected.has_detection != actual.has_detection ||
      expected.has_geometry != actual.has_geometry) {
    return ::testing::AssertionFailure()
           << "has_detection " << actual.has_detection << " has_geometry " << actual.has_geometry
           << ", expected " << expected.has_detection << " and " << expected.has_geometry;
  }
  if (expected.has_geometry && (expected.field_length != actual.field_length ||
                                expected.field_width != actual.field_width)) {
    return ::testing::AssertionFailure()
           << "field " << actual.field_length << " x " << actual.field_width << ", expected "
           << expected.field_length << " x " << expected.field_width;
  }
  if (!expected.has_detection) return ::testing::AssertionSuccess();
  const VisionDetection& e = expected.detection;
  const VisionDetection& a = actual.detection;
  if (e.frame_number != a.frame_number || !same_bits(e.t_capture, a.t_capture) ||
      e.camera_id != a.camera_id) {
    return ::testing::AssertionFailure()
           << "frame " << a.frame_number << " at " << a.t_capture << " from camera " << a.camera_id
           << ", expected frame " << e.frame_number << " at " << e.t_capture << " from camera "
           << e.camera_id;
  }
  if (auto yellow = same_robots("yellow", e.robots_yellow, a.robots_yellow); !yellow) return yellow;
  if (auto blue = same_robots("blue", e.robots_blue, a.robots_blue); !blue) return blue;
  return same_balls(e.balls, a.balls);
}

bool has_unknown_fields(const SSL_WrapperPacket& packet) {
  if (!packet.unknown_fields().empty()) return true;
  if (!packet.has_detection()) return false;
  const SSL_DetectionFrame& frame = packet.detection();
  if (!frame.unknown_fields().empty()) return true;
  for (const SSL_DetectionBall& ball : frame.balls())
    if (!ball.unknown_fields().empty()) return true;
  for (const SSL_DetectionRobot& robot : frame.robots_yellow())
    if (!robot.unknown_fields().empty()) return true;
  for (const SSL_DetectionRobot& robot : frame.robots_blue())
    if (!robot.unknown_fields().empty()) return true;
  return false;
}

// What the daemons do with a datagram the fast path refuses: a partial parse, then a check of the
// required fields, so that a packet missing one is dropped.
bool protobuf_accepts(std::string_view datagram, SSL_WrapperPacket& packet) {
  return packet.ParsePartialFromArray(datagram.data(), static_cast<int>(datagram.size())) &&
         packet.IsInitialized();
}
bool protobuf_accepts(std::string_view datagram) {
  SSL_WrapperPacket packet;
  return protobuf_accepts(datagram, packet);
}

// Runs the fast path on `datagram` and returns whether it decoded it. If it did, checks the
// promise (a broken one fails the test): protobuf parses the same bytes into an initialised
// packet without geometry or unknown fields, whose to_vision_frame() is the same frame.
bool decodes(std::string_view datagram) {
  // A heap buffer of exactly the datagram's size, so that a read past its end (a cut datagram,
  // a length past the end) is caught by the sanitizer build, not hidden by the bytes that follow.
  const std::vector<char> exact(datagram.begin(), datagram.end());
  VisionFrame fast;
  if (!decode_detection_datagram(bytes_of({exact.data(), exact.size()}), fast)) return false;
  SSL_WrapperPacket packet;
  if (!packet.ParseFromArray(datagram.data(), static_cast<int>(datagram.size()))) {
    ADD_FAILURE() << "decoded, but protobuf refuses the bytes: " << hex(datagram);
    return true;
  }
  EXPECT_TRUE(packet.IsInitialized()) << hex(datagram);
  EXPECT_FALSE(packet.has_geometry()) << hex(datagram);
  EXPECT_FALSE(has_unknown_fields(packet)) << hex(datagram);
  VisionFrame reference;
  to_vision_frame(packet, reference);
  EXPECT_TRUE(same_frame(reference, fast)) << hex(datagram);
  return true;
}

VisionFrame decoded_frame(std::string_view datagram) {
  VisionFrame frame;
  EXPECT_TRUE(decode_detection_datagram(bytes_of(datagram), frame)) << hex(datagram);
  return frame;
}

DetectionFrameSpec frame_spec(std::uint32_t camera_id, std::uint32_t frame_number, double t_capture,
                              std::vector<RobotDetection> yellow,
                              std::vector<RobotDetection> blue) {
  DetectionFrameSpec spec;
  spec.camera_id = camera_id;
  spec.frame_number = frame_number;
  spec.t_capture = t_capture;
  spec.yellow = std::move(yellow);
  spec.blue = std::move(blue);
  return spec;
}

DetectionFrameSpec spec_with_robots_and_balls() {
  DetectionFrameSpec spec;
  spec.camera_id = 2;
  spec.frame_number = 77;
  spec.t_capture = 12.5;
  spec.t_sent = 12.51;
  spec.yellow = {{0, {-4000, 1000}}, {5, {250.5, -300.25}, 1.5F, 0.5F}};
  spec.blue = {{11, {4400, -2900}}};
  spec.balls = {{10, 20}, {-30, 40}};
  return spec;
}

// ---- Rules of the fast path, one by one

TEST(VisionFrameDecode, TheReferenceDatagramDecodesToItsValues) {
  const std::string datagram = reference_datagram();
  ASSERT_TRUE(decodes(datagram));
  const VisionFrame frame = decoded_frame(datagram);
  EXPECT_TRUE(frame.has_detection);
  EXPECT_FALSE(frame.has_geometry);
  EXPECT_EQ(frame.detection.frame_number, reference_frame_number);
  EXPECT_EQ(frame.detection.t_capture, reference_t_capture);
  EXPECT_EQ(frame.detection.camera_id, reference_camera_id);
  ASSERT_EQ(frame.detection.robots_yellow.size(), 2u);
  ASSERT_EQ(frame.detection.robots_blue.size(), 1u);
  const VisionRobot& first = frame.detection.robots_yellow[0];
  EXPECT_TRUE(first.has_robot_id);
  EXPECT_EQ(first.robot_id, 7u);
  EXPECT_EQ(first.x, 1234.5F);
  EXPECT_EQ(first.y, -678.25F);
  EXPECT_EQ(first.confidence, 0.875F);
  EXPECT_EQ(frame.detection.robots_yellow[1].robot_id, 4u);
  EXPECT_EQ(frame.detection.robots_blue[0].robot_id, 9u);
  EXPECT_EQ(frame.detection.robots_blue[0].y, -20.0F);
  ASSERT_EQ(frame.detection.balls.size(), 1u);
  EXPECT_EQ(frame.detection.balls[0].x, 10.5F);
  EXPECT_EQ(frame.detection.balls[0].y, -20.25F);
  EXPECT_EQ(frame.detection.balls[0].confidence, 0.75F);
}

TEST(VisionFrameDecode, PacketsSerialisedByProtobufDecode) {
  SSL_WrapperPacket packet = make_detection_packet(spec_with_robots_and_balls());
  EXPECT_TRUE(decodes(packet.SerializeAsString()));

  packet.mutable_detection()->mutable_robots_yellow(1)->clear_robot_id();
  packet.mutable_detection()->set_t_capture_camera(12.49);
  EXPECT_TRUE(decodes(packet.SerializeAsString()));
  EXPECT_FALSE(decoded_frame(packet.SerializeAsString()).detection.robots_yellow[1].has_robot_id);

  for (int source = SSL_VisionSource_MIN; source <= SSL_VisionSource_MAX; ++source) {
    SCOPED_TRACE(source);
    packet.set_source(static_cast<SSL_VisionSource>(source));
    EXPECT_TRUE(decodes(packet.SerializeAsString()));
  }

  // A camera that sees nothing still sends its frame: it completes the sampler's instant.
  EXPECT_TRUE(decodes(make_detection_packet(DetectionFrameSpec{}).SerializeAsString()));
}

TEST(VisionFrameDecode, AnEmptyDatagramIsRefused) {
  EXPECT_FALSE(decodes(""));
  EXPECT_TRUE(protobuf_accepts(""));  // an empty wrapper: valid, but holds nothing to sample
}

TEST(VisionFrameDecode, GeometryIsLeftToProtobufWithOrWithoutDetection) {
  const std::string geometry = make_geometry_packet(FieldSize{12000, 9000}).SerializeAsString();
  const std::string detection =
      make_detection_packet(spec_with_robots_and_balls()).SerializeAsString();
  SSL_WrapperPacket both = make_detection_packet(spec_with_robots_and_balls());
  fill_geometry(*both.mutable_geometry(), FieldSize{12000, 9000});

  // Two serialised wrappers one after the other are one wrapper with both fields (protobuf merges).
  for (const std::string& datagram :
       {geometry, both.SerializeAsString(), detection + geometry, geometry + detection}) {
    SCOPED_TRACE(hex(datagram));
    EXPECT_TRUE(protobuf_accepts(datagram));
    EXPECT_FALSE(decodes(datagram));
  }
}

TEST(VisionFrameDecode, ASecondDetectionFrameIsLeftToProtobuf) {
  const std::string datagram = datagram_with(Level::wrapper, [](Message m) { return twice(m, 1); });
  EXPECT_FALSE(decodes(datagram));
  // Protobuf merges the two: accepted, with the robots of both.
  SSL_WrapperPacket packet;
  ASSERT_TRUE(protobuf_accepts(datagram, packet));
  EXPECT_EQ(packet.detection().robots_yellow_size(), 4);

  const std::string other = make_detection_packet(spec_with_robots_and_balls()).SerializeAsString();
  EXPECT_FALSE(decodes(reference_datagram() + other));
}

TEST(VisionFrameDecode, TheSourceMustBeOneOfTheFourKnownValuesAndComeOnce) {
  const auto with_source = [](const std::string& source_field) {
    return datagram_with(Level::wrapper, [&](Message m) {
      m.push_back({3, source_field});
      return m;
    });
  };
  for (std::uint64_t source = 0; source <= 3; ++source) {
    SCOPED_TRACE(source);
    EXPECT_TRUE(decodes(with_source(wire::varint_field(3, source))));
  }
  // A padded varint is still the value 3.
  EXPECT_TRUE(decodes(with_source(wire::key(3, wire::varint_type) + wire::padded_varint(3, 5))));

  // Protobuf keeps an enum value it does not know among the unknown fields: accepted, not ours.
  for (const std::uint64_t source : {std::uint64_t{4}, std::uint64_t{7}, std::uint64_t{1000},
                                     std::uint64_t{0xFFFFFFFF}, ~std::uint64_t{0} /* -1 */}) {
    SCOPED_TRACE(source);
    const std::string datagram = with_source(wire::varint_field(3, source));
    EXPECT_TRUE(protobuf_accepts(datagram));
    EXPECT_FALSE(decodes(datagram));
  }

  const std::string source_twice = datagram_with(Level::wrapper, [](Message m) {
    m.push_back({3, wire::varint_field(3, 1)});
    m.push_back({3, wire::varint_field(3, 2)});
    return m;
  });
  EXPECT_TRUE(protobuf_accepts(source_twice));
  EXPECT_FALSE(decodes(source_twice));

  // A source alone is no detection.
  EXPECT_FALSE(decodes(wire::varint_field(3, 2)));
}

TEST(VisionFrameDecode, AMissingRequiredFieldIsRefusedAsProtobufRefusesIt) {
  for (const Schema& schema : nested_schemas) {
    for (const std::uint32_t number : schema.required) {
      SCOPED_TRACE(std::string(to_string(schema.level)) + " without field " +
                   std::to_string(number));
      const std::string datagram =
          datagram_with(schema.level, [&](Message m) { return without(m, number); });
      SSL_WrapperPacket packet;
      EXPECT_TRUE(packet.ParsePartialFromArray(datagram.data(), static_cast<int>(datagram.size())));
      EXPECT_FALSE(packet.IsInitialized());
      EXPECT_FALSE(decodes(datagram));
    }
  }
}

TEST(VisionFrameDecode, OptionalAndRepeatedFieldsMayBeLeftOut) {
  for (const Schema& schema : nested_schemas) {
    std::vector<std::uint32_t> removable = schema.optional;
    removable.insert(removable.end(), schema.repeated.begin(), schema.repeated.end());
    for (const std::uint32_t number : removable) {
      SCOPED_TRACE(std::string(to_string(schema.level)) + " without field " +
                   std::to_string(number));
      EXPECT_TRUE(
          decodes(datagram_with(schema.level, [&](Message m) { return without(m, number); })));
    }
  }
  const VisionFrame frame =
      decoded_frame(datagram_with(Level::robot, [](Message m) { return without(m, 2); }));
  ASSERT_EQ(frame.detection.robots_yellow.size(), 2u);
  EXPECT_FALSE(frame.detection.robots_yellow[0].has_robot_id);
  EXPECT_EQ(frame.detection.robots_yellow[0].robot_id, 0u);
  EXPECT_TRUE(frame.detection.robots_yellow[1].has_robot_id);

  // A ball without area and height still has its position and confidence.
  const VisionFrame bare_ball = decoded_frame(
      datagram_with(Level::ball, [](Message m) { return without(without(m, 2), 5); }));
  ASSERT_EQ(bare_ball.detection.balls.size(), 1u);
  EXPECT_EQ(bare_ball.detection.balls[0].x, 10.5F);
  EXPECT_EQ(bare_ball.detection.balls[0].y, -20.25F);
  EXPECT_EQ(bare_ball.detection.balls[0].confidence, 0.75F);
  // A frame without balls has none.
  const VisionFrame no_ball =
      decoded_frame(datagram_with(Level::frame, [](Message m) { return without(m, 5); }));
  EXPECT_TRUE(no_ball.detection.balls.empty());
}

TEST(VisionFrameDecode, ASingularFieldTwiceIsLeftToProtobuf) {
  for (const Schema& schema : nested_schemas) {
    std::vector<std::uint32_t> singular = schema.required;
    singular.insert(singular.end(), schema.optional.begin(), schema.optional.end());
    for (const std::uint32_t number : singular) {
      SCOPED_TRACE(std::string(to_string(schema.level)) + " with field " + std::to_string(number) +
                   " twice");
      const std::string datagram =
          datagram_with(schema.level, [&](Message m) { return twice(m, number); });
      EXPECT_TRUE(protobuf_accepts(datagram));  // the last one wins
      EXPECT_FALSE(decodes(datagram));
    }
  }
}

TEST(VisionFrameDecode, RepeatedFieldsMayComeAnyNumberOfTimesInAnyOrder) {
  const std::string datagram = datagram_with(Level::frame, [](Message m) {
    Message many = twice(twice(twice(m, 5), 7), 6);
    std::reverse(many.begin(), many.end());
    return many;
  });
  ASSERT_TRUE(decodes(datagram));
  const VisionFrame frame = decoded_frame(datagram);
  EXPECT_EQ(frame.detection.robots_yellow.size(), 3u);
  EXPECT_EQ(frame.detection.robots_blue.size(), 2u);
  EXPECT_EQ(frame.detection.balls.size(), 2u);
}

TEST(VisionFrameDecode, UnknownFieldsAreLeftToProtobufAtEveryLevel) {
  for (const Level level : all_levels) {
    const std::uint32_t first = first_unknown_field(level);
    // Just past the schema, the first two-byte key, the edges of a 32-bit field mask, the largest.
    for (const std::uint32_t number : {first, first + 1, 15u, 16u, 31u, 32u, 1000u, 536870911u}) {
      for (const wire::Type type : wire::all_types) {
        for (const bool in_front : {true, false}) {
          SCOPED_TRACE(std::string(to_string(level)) + " with unknown field " +
                       std::to_string(number) + " of wire type " + std::to_string(type) +
                       (in_front ? " in front" : " at the end"));
          const std::string datagram = datagram_with(level, [&](Message m) {
            const Field unknown{number, wire::any_field(number, type)};
            m.insert(in_front ? m.begin() : m.end(), unknown);
            return m;
          });
          EXPECT_TRUE(protobuf_accepts(datagram));
          EXPECT_FALSE(decodes(datagram));
        }
      }
    }
  }
}

TEST(VisionFrameDecode, AKnownFieldWithAnotherWireTypeIsRefused) {
  for (const Level level : all_levels) {
    Message fields;
    datagram_with(level, [&](Message m) {
      fields = m;
      return m;
    });
    ASSERT_FALSE(fields.empty());
    for (const Field& field : fields) {
      for (const wire::Type type : wire::all_types) {
        if (type == type_of(field)) continue;
        SCOPED_TRACE(std::string(to_string(level)) + " field " + std::to_string(field.number) +
                     " as wire type " + std::to_string(type));
        EXPECT_FALSE(decodes(datagram_with(level, [&](Message m) {
          return replaced(m, field.number, wire::any_field(field.number, type));
        })));
      }
    }
  }
}

TEST(VisionFrameDecode, FieldNumberZeroAndGroupOrReservedWireTypesAreRefused) {
  for (const Level level : all_levels) {
    for (const std::uint32_t type : {0u, 1u, 2u, 5u}) {
      SCOPED_TRACE(std::string(to_string(level)) + " field 0 of wire type " + std::to_string(type));
      const std::string datagram = datagram_with(level, [&](Message m) {
        m.push_back(
            {0, wire::key(0, type) + wire::any_field(1, static_cast<wire::Type>(type)).substr(1)});
        return m;
      });
      EXPECT_FALSE(protobuf_accepts(datagram));
      EXPECT_FALSE(decodes(datagram));
    }
    // Start group, end group, and the two wire types the format does not define.
    for (const std::uint32_t type : {3u, 4u, 6u, 7u}) {
      SCOPED_TRACE(std::string(to_string(level)) + " field 1 of wire type " + std::to_string(type));
      EXPECT_FALSE(decodes(datagram_with(level, [&](Message m) {
        m.push_back({1, wire::key(1, type)});
        return m;
      })));
    }
  }
}

TEST(VisionFrameDecode, Uint32VarintsBeyondFiveBytesOr32BitsAreLeftToProtobuf) {
  struct Uint32Field {
    Level level;
    std::uint32_t number;
  };
  const std::array<Uint32Field, 4> uint32_fields{
      {{Level::robot, 2}, {Level::ball, 2}, {Level::frame, 1}, {Level::frame, 4}}};
  const auto with_value = [](Uint32Field field, const std::string& encoded) {
    return datagram_with(field.level, [&](Message m) {
      return replaced(m, field.number, wire::key(field.number, wire::varint_type) + encoded);
    });
  };
  for (const Uint32Field field : uint32_fields) {
    SCOPED_TRACE(std::string(to_string(field.level)) + " field " + std::to_string(field.number));
    // Protobuf reads the low 32 bits of these; the fast path leaves them to it.
    for (const std::string& encoded :
         {wire::varint((std::uint64_t{1} << 32) + 5),  // 5 bytes, 33 bits
          wire::varint((std::uint64_t{1} << 35) + 5),  // 6 bytes
          wire::varint(~std::uint64_t{0}),             // 10 bytes
          wire::padded_varint(5, 6), wire::padded_varint(5, 10)}) {
      SCOPED_TRACE(hex(encoded));
      const std::string datagram = with_value(field, encoded);
      EXPECT_TRUE(protobuf_accepts(datagram));
      EXPECT_FALSE(decodes(datagram));
    }
    // Up to five bytes and 32 bits it is the fast path's, padded or not.
    for (const std::string& encoded :
         {wire::varint(0xFFFFFFFF), wire::padded_varint(5, 5), wire::padded_varint(0, 2),
          wire::padded_varint(0x0FFFFFFF, 5)}) {
      SCOPED_TRACE(hex(encoded));
      EXPECT_TRUE(decodes(with_value(field, encoded)));
    }
  }
  const VisionFrame frame = decoded_frame(with_value({Level::robot, 2}, wire::varint(0xFFFFFFFF)));
  EXPECT_EQ(frame.detection.robots_yellow[0].robot_id, 0xFFFFFFFFu);
}

TEST(VisionFrameDecode, PaddedKeysAndLengthsReadAsProtobufReadsThem) {
  // The robot's x with a five-byte key, the robot itself with a five-byte length.
  const std::string padded_key = datagram_with(Level::robot, [](Message m) {
    return replaced(m, 3,
                    wire::padded_varint(3 << 3 | wire::fixed32_type, 5) +
                        wire::little_endian(std::bit_cast<std::uint32_t>(1.5F), 4));
  });
  EXPECT_TRUE(decodes(padded_key));
  EXPECT_EQ(decoded_frame(padded_key).detection.robots_yellow[0].x, 1.5F);

  const std::string robot = encode(reference_robot(7, 1.0F, 2.0F));
  const std::string padded_length = datagram_with(Level::frame, [&](Message m) {
    return replaced(m, 6,
                    wire::key(6, wire::bytes_type) + wire::padded_varint(robot.size(), 5) + robot);
  });
  EXPECT_TRUE(decodes(padded_length));
}

TEST(VisionFrameDecode, LengthsPastTheEndAreRefused) {
  const std::string robot = encode(reference_robot(7, 1.0F, 2.0F));
  for (const std::uint64_t length :
       {std::uint64_t{robot.size() + 1}, std::uint64_t{0xFFFFFFFF}, std::uint64_t{1} << 40}) {
    SCOPED_TRACE(length);
    EXPECT_FALSE(decodes(datagram_with(Level::frame, [&](Message m) {
      return replaced(m, 6, wire::key(6, wire::bytes_type) + wire::varint(length) + robot);
    })));
  }
  // The wrapper's detection claims one byte more than the datagram holds.
  const std::string frame =
      encode(reference_frame(reference_ball(), reference_robot(7, 1.0F, 2.0F)));
  EXPECT_TRUE(decodes(wire::bytes_field(1, frame)));
  EXPECT_FALSE(decodes(wire::key(1, wire::bytes_type) + wire::varint(frame.size() + 1) + frame));
}

TEST(VisionFrameDecode, EveryTruncationIsRefused) {
  const std::string detection_only =
      make_detection_packet(spec_with_robots_and_balls()).SerializeAsString();
  for (const std::string& datagram : {reference_datagram(), detection_only}) {
    for (std::size_t length = 0; length < datagram.size(); ++length) {
      SCOPED_TRACE(length);
      EXPECT_FALSE(decodes(std::string_view(datagram).substr(0, length)));
    }
  }

  // With a source after the detection, exactly one cut gives a valid packet: the one that
  // removes the whole source field.
  SSL_WrapperPacket packet = make_detection_packet(spec_with_robots_and_balls());
  packet.set_source(SSL_VISION_SOURCE_SIMULATION);
  const std::string with_source = packet.SerializeAsString();
  ASSERT_EQ(with_source.substr(with_source.size() - 2), wire::varint_field(3, 2));
  std::vector<std::size_t> decoded_lengths;
  for (std::size_t length = 0; length < with_source.size(); ++length) {
    if (decodes(std::string_view(with_source).substr(0, length))) decoded_lengths.push_back(length);
  }
  EXPECT_EQ(decoded_lengths, std::vector<std::size_t>{with_source.size() - 2});
}

TEST(VisionFrameDecode, FloatsAreCopiedBitForBit) {
  const float nan_with_payload = std::bit_cast<float>(0x7FC12345U);
  const float negative_nan = std::bit_cast<float>(0xFFA00001U);  // signalling, with a sign
  const float denormal = std::numeric_limits<float>::denorm_min();
  const double t_nan = std::bit_cast<double>(0x7FF8000000ABCDEFULL);
  const Message odd_robot = replaced(reference_robot(1, nan_with_payload, negative_nan), 1,
                                     wire::float_field(1, denormal));
  const std::string datagram = datagram_with(Level::frame, [&](Message m) {
    m = replaced(m, 2, wire::double_field(2, t_nan));
    return replaced(m, 6, wire::bytes_field(6, encode(odd_robot)));
  });
  ASSERT_TRUE(decodes(datagram));  // and protobuf's frame is the same, bit for bit
  const VisionFrame frame = decoded_frame(datagram);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(frame.detection.t_capture), 0x7FF8000000ABCDEFULL);
  const VisionRobot& robot = frame.detection.robots_yellow[0];
  EXPECT_EQ(std::bit_cast<std::uint32_t>(robot.x), 0x7FC12345U);
  EXPECT_EQ(std::bit_cast<std::uint32_t>(robot.y), 0xFFA00001U);
  EXPECT_EQ(std::bit_cast<std::uint32_t>(robot.confidence), std::bit_cast<std::uint32_t>(denormal));

  const std::string infinities = datagram_with(Level::robot, [](Message m) {
    m = replaced(m, 3, wire::float_field(3, std::numeric_limits<float>::infinity()));
    return replaced(m, 4, wire::float_field(4, -std::numeric_limits<float>::infinity()));
  });
  EXPECT_TRUE(decodes(infinities));
  EXPECT_TRUE(std::isinf(decoded_frame(infinities).detection.robots_yellow[0].x));
}

// Robots come in two layouts nearly always (every field with a one-byte id, 37 bytes; grSim's
// without height, 32), which the decoder reads by their size and their keys at fixed offsets.
// Every byte of such a robot changed to values that make other keys, long varints or other sizes
// must still decode exactly as protobuf parses, or be left to it.
TEST(VisionFrameDecode, EveryByteOfARobotInACommonLayoutChangedStillAgreesWithProtobuf) {
  for (const bool with_height : {true, false}) {
    SCOPED_TRACE(with_height ? "with height" : "without height (grSim)");
    SSL_WrapperPacket packet =
        make_detection_packet(frame_spec(1, 9, 3.5, {{7, {-1234.5, 678.25}, 0.5F, 0.75F}}, {}));
    SSL_DetectionRobot& robot = *packet.mutable_detection()->mutable_robots_yellow(0);
    if (!with_height) robot.clear_height();
    const std::string robot_bytes = robot.SerializeAsString();
    ASSERT_EQ(robot_bytes.size(), with_height ? 37u : 32u);
    const std::string datagram = packet.SerializeAsString();
    const std::size_t at = datagram.find(robot_bytes);
    ASSERT_NE(at, std::string::npos);

    const VisionFrame frame = decoded_frame(datagram);
    ASSERT_EQ(frame.detection.robots_yellow.size(), 1u);
    const VisionRobot& decoded = frame.detection.robots_yellow[0];
    EXPECT_TRUE(decoded.has_robot_id);
    EXPECT_EQ(decoded.robot_id, 7u);
    EXPECT_EQ(decoded.x, -1234.5F);
    EXPECT_EQ(decoded.y, 678.25F);
    EXPECT_EQ(decoded.confidence, 0.75F);

    int still_decoded = 0;
    int left_to_protobuf = 0;
    for (std::size_t i = 0; i < robot_bytes.size(); ++i) {
      for (const unsigned value : {0x00U, 0x01U, 0x05U, 0x0DU, 0x10U, 0x15U, 0x1DU, 0x25U, 0x2DU,
                                   0x35U, 0x3DU, 0x45U, 0x4DU, 0x7FU, 0x80U, 0x81U, 0xFFU}) {
        std::string changed = datagram;
        if (static_cast<unsigned char>(changed[at + i]) == value) continue;
        changed[at + i] = static_cast<char>(value);
        SCOPED_TRACE("byte " + std::to_string(i) + " = " + std::to_string(value));
        (decodes(changed) ? still_decoded : left_to_protobuf) += 1;
      }
    }
    // Changed floats and ids still decode; changed keys mostly do not.
    EXPECT_GT(still_decoded, 200);
    EXPECT_GT(left_to_protobuf, 50);
  }
}

// A ball as protobuf writes it (every field in order) is read in one pass; every byte of it changed
// must still decode exactly as protobuf parses, or be left to it.
TEST(VisionFrameDecode, EveryByteOfABallChangedStillAgreesWithProtobuf) {
  DetectionFrameSpec spec = frame_spec(1, 9, 3.5, {}, {{2, {100, 200}}});
  spec.balls = {{-1234.5, 678.25}};
  const SSL_WrapperPacket packet = make_detection_packet(spec);
  const std::string ball_bytes = packet.detection().balls(0).SerializeAsString();
  const std::string datagram = packet.SerializeAsString();
  const std::size_t at = datagram.find(ball_bytes);
  ASSERT_NE(at, std::string::npos);

  const VisionFrame frame = decoded_frame(datagram);
  ASSERT_EQ(frame.detection.balls.size(), 1u);
  EXPECT_EQ(frame.detection.balls[0].x, -1234.5F);
  EXPECT_EQ(frame.detection.balls[0].y, 678.25F);
  EXPECT_EQ(frame.detection.balls[0].confidence, 0.95F);

  int still_decoded = 0;
  int left_to_protobuf = 0;
  for (std::size_t i = 0; i < ball_bytes.size(); ++i) {
    for (const unsigned value : {0x00U, 0x05U, 0x0DU, 0x10U, 0x15U, 0x1DU, 0x25U, 0x2DU, 0x35U,
                                 0x3DU, 0x45U, 0x7FU, 0x80U, 0xFFU}) {
      std::string changed = datagram;
      if (static_cast<unsigned char>(changed[at + i]) == value) continue;
      changed[at + i] = static_cast<char>(value);
      SCOPED_TRACE("byte " + std::to_string(i) + " = " + std::to_string(value));
      (decodes(changed) ? still_decoded : left_to_protobuf) += 1;
    }
  }
  EXPECT_GT(still_decoded, 100);
  EXPECT_GT(left_to_protobuf, 30);
}

TEST(VisionFrameDecode, AReusedFrameKeepsNothingOfTheLastDatagram) {
  SSL_WrapperPacket small_packet = make_detection_packet(frame_spec(1, 9, 3.0, {{2, {1, 1}}}, {}));
  small_packet.mutable_detection()->mutable_robots_yellow(0)->clear_robot_id();
  const std::string small = small_packet.SerializeAsString();
  const std::string large = make_detection_packet(spec_with_robots_and_balls()).SerializeAsString();

  VisionFrame reused;
  reused.has_geometry = true;
  ASSERT_TRUE(decode_detection_datagram(bytes_of(large), reused));
  EXPECT_FALSE(reused.has_geometry);
  ASSERT_EQ(reused.detection.balls.size(), 2u);
  ASSERT_TRUE(decode_detection_datagram(bytes_of(small), reused));
  EXPECT_TRUE(same_frame(decoded_frame(small), reused));
  EXPECT_FALSE(reused.detection.robots_yellow[0].has_robot_id);
  EXPECT_TRUE(reused.detection.balls.empty());

  // A refused datagram in between leaves the frame unspecified, but not the next one decoded.
  EXPECT_FALSE(decode_detection_datagram(bytes_of(large.substr(0, large.size() / 2)), reused));
  ASSERT_TRUE(decode_detection_datagram(bytes_of(large), reused));
  EXPECT_TRUE(same_frame(decoded_frame(large), reused));
}

// ---- to_vision_frame()

TEST(VisionFrameConversion, AGeometryPacketGivesTheFieldSize) {
  VisionFrame frame;
  to_vision_frame(make_geometry_packet(FieldSize{12000, 9000}), frame);
  EXPECT_FALSE(frame.has_detection);
  EXPECT_TRUE(frame.has_geometry);
  EXPECT_EQ(frame.field_length, 12000);
  EXPECT_EQ(frame.field_width, 9000);
}

TEST(VisionFrameConversion, DetectionAndGeometryInOnePacketGiveBoth) {
  SSL_WrapperPacket packet = make_detection_packet(spec_with_robots_and_balls());
  fill_geometry(*packet.mutable_geometry(), FieldSize{9000, 6000});
  VisionFrame frame;
  to_vision_frame(packet, frame);
  EXPECT_TRUE(frame.has_detection);
  EXPECT_TRUE(frame.has_geometry);
  EXPECT_EQ(frame.field_length, 9000);
  EXPECT_EQ(frame.field_width, 6000);
  EXPECT_EQ(frame.detection.frame_number, 77u);
  EXPECT_EQ(frame.detection.t_capture, 12.5);
  EXPECT_EQ(frame.detection.camera_id, 2u);
  ASSERT_EQ(frame.detection.robots(TeamColor::yellow).size(), 2u);
  ASSERT_EQ(frame.detection.robots(TeamColor::blue).size(), 1u);
  const VisionRobot& robot = frame.detection.robots_yellow[1];
  EXPECT_EQ(robot.robot_id, 5u);
  EXPECT_TRUE(robot.has_robot_id);
  EXPECT_EQ(robot.x, 250.5F);
  EXPECT_EQ(robot.y, -300.25F);
  EXPECT_EQ(robot.confidence, 0.5F);
  EXPECT_EQ(frame.detection.robots_blue[0].robot_id, 11u);
  ASSERT_EQ(frame.detection.balls.size(), 2u);
  EXPECT_EQ(frame.detection.balls[0].x, 10.0F);
  EXPECT_EQ(frame.detection.balls[0].y, 20.0F);
  EXPECT_EQ(frame.detection.balls[0].confidence, 0.95F);
  EXPECT_EQ(frame.detection.balls[1].x, -30.0F);
  EXPECT_EQ(frame.detection.balls[1].y, 40.0F);
}

TEST(VisionFrameConversion, APacketWithNeitherClearsBothFlags) {
  VisionFrame frame;
  SSL_WrapperPacket both = make_detection_packet(spec_with_robots_and_balls());
  fill_geometry(*both.mutable_geometry(), FieldSize{9000, 6000});
  to_vision_frame(both, frame);
  SSL_WrapperPacket empty;
  empty.set_source(SSL_VISION_SOURCE_CAMERA);
  to_vision_frame(empty, frame);
  EXPECT_FALSE(frame.has_detection);
  EXPECT_FALSE(frame.has_geometry);
}

TEST(VisionFrameConversion, ARobotWithoutIdHasNone) {
  SSL_WrapperPacket packet = make_detection_packet(spec_with_robots_and_balls());
  packet.mutable_detection()->mutable_robots_blue(0)->clear_robot_id();
  VisionFrame frame;
  to_vision_frame(packet, frame);
  ASSERT_EQ(frame.detection.robots_blue.size(), 1u);
  EXPECT_FALSE(frame.detection.robots_blue[0].has_robot_id);
  EXPECT_EQ(frame.detection.robots_blue[0].robot_id, 0u);
  EXPECT_TRUE(frame.detection.robots_yellow[0].has_robot_id);
}

TEST(VisionFrameConversion, AReusedFrameGetsExactlyTheNewRobots) {
  VisionFrame reused;
  to_vision_frame(make_detection_packet(spec_with_robots_and_balls()), reused);
  const SSL_WrapperPacket fewer = make_detection_packet(frame_spec(0, 1, 1.0, {}, {{3, {5, 6}}}));
  to_vision_frame(fewer, reused);
  VisionFrame fresh;
  to_vision_frame(fewer, fresh);
  EXPECT_TRUE(same_frame(fresh, reused));
  EXPECT_TRUE(reused.detection.robots_yellow.empty());
  EXPECT_TRUE(reused.detection.balls.empty());
}

// ---- Many inputs: whenever the fast path decodes, protobuf agrees

// The vision datagrams of a log file as they came off the network: the payloads of its type 4
// messages, unparsed.
std::vector<std::string> vision_datagrams(const fs::path& path, std::string* error = nullptr) {
  Result<LogReader> reader = LogReader::open(path);
  std::vector<std::string> datagrams;
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return datagrams;
  }
  LogMessage message;
  while (reader->next(message)) {
    if (message.type == static_cast<std::int32_t>(LogMessageType::vision))
      datagrams.push_back(message.payload);
  }
  if (error != nullptr) *error = reader->error();
  return datagrams;
}

std::vector<std::string> grsim_datagrams() {
  std::string error;
  std::vector<std::string> datagrams = vision_datagrams(grsim_log, &error);
  EXPECT_EQ(error, "");
  EXPECT_EQ(datagrams.size(), 2353u);  // as tests/common/sampler_grsim_test.cpp reads it
  return datagrams;
}

bool detection_only(std::string_view datagram) {
  SSL_WrapperPacket packet;
  return protobuf_accepts(datagram, packet) && packet.has_detection() && !packet.has_geometry();
}

TEST(VisionFrameDifferential, EveryGrsimDetectionPacketTakesTheFastPathAndAgrees) {
  const std::vector<std::string> datagrams = grsim_datagrams();
  std::size_t detection_only_count = 0;
  std::size_t decoded = 0;
  for (std::size_t i = 0; i < datagrams.size(); ++i) {
    SCOPED_TRACE("datagram " + std::to_string(i));
    const bool fast = decodes(datagrams[i]);
    decoded += fast;
    if (detection_only(datagrams[i])) {
      ++detection_only_count;
      EXPECT_TRUE(fast) << hex(datagrams[i]);
    }
    if (HasFailure()) return;
  }
  EXPECT_GT(detection_only_count, 2000u);
  EXPECT_LT(detection_only_count, datagrams.size());  // grSim also sends geometry
  EXPECT_EQ(decoded, detection_only_count);
}

TEST(VisionFrameDifferential, NoCutGrsimPacketFoolsTheFastPath) {
  const std::vector<std::string> datagrams = grsim_datagrams();
  const auto it = std::find_if(datagrams.begin(), datagrams.end(), detection_only);
  ASSERT_NE(it, datagrams.end());
  for (std::size_t length = 0; length < it->size(); ++length) {
    SCOPED_TRACE(length);
    EXPECT_FALSE(decodes(std::string_view(*it).substr(0, length)));
  }
}

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The datagrams of a sampler fuzz seed, read as tests/fuzz/fuzz_paths.hpp reads them: a config
// byte, then records of a little-endian u16 length and that many bytes (the length 0xFFFF
// starts a new stream and has no bytes; the last record may be cut short).
std::vector<std::string> sampler_seed_datagrams(const std::string& seed) {
  constexpr std::size_t new_stream_record = 0xFFFF;
  std::vector<std::string> datagrams;
  std::size_t at = 1;
  while (at + 2 <= seed.size()) {
    const std::size_t length = static_cast<unsigned char>(seed[at]) |
                               static_cast<std::size_t>(static_cast<unsigned char>(seed[at + 1]))
                                   << 8;
    at += 2;
    if (length == new_stream_record) continue;
    const std::size_t n = std::min(length, seed.size() - at);
    datagrams.push_back(seed.substr(at, n));
    at += n;
  }
  return datagrams;
}

TEST(VisionFrameDifferential, EveryVisionPacketOfTheFuzzCorpusAgrees) {
  std::size_t datagram_count = 0;
  std::size_t decoded = 0;
  const auto check = [&](const fs::path& file, const std::vector<std::string>& datagrams) {
    for (std::size_t i = 0; i < datagrams.size(); ++i) {
      SCOPED_TRACE(file.filename().string() + " datagram " + std::to_string(i));
      decoded += decodes(datagrams[i]);
      ++datagram_count;
    }
  };
  const std::vector<fs::path> sampler_seeds = files_in(fuzz_corpus_dir / "sampler");
  ASSERT_GE(sampler_seeds.size(), 5u);
  for (const fs::path& seed : sampler_seeds) check(seed, sampler_seed_datagrams(read_file(seed)));
  const std::size_t decoded_from_sampler_seeds = decoded;
  // Log seeds hold type 4 vision messages among others (one of them deliberately undecodable).
  for (const fs::path& log : files_in(fuzz_corpus_dir / "log")) check(log, vision_datagrams(log));

  EXPECT_GT(datagram_count, 100u);
  EXPECT_GT(decoded_from_sampler_seeds, 50u);
  EXPECT_GT(decoded, decoded_from_sampler_seeds);
  EXPECT_LT(decoded, datagram_count);  // geometry and hostile packets are among them
}

// A valid detection datagram damaged by one to three random edits.
std::string damaged(std::string bytes, std::mt19937& rng) {
  const auto random_below = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  const auto random_byte = [&] { return static_cast<char>(random_below(256)); };
  const std::size_t edits = 1 + random_below(3);
  for (std::size_t edit = 0; edit < edits; ++edit) {
    const std::size_t at = bytes.empty() ? 0 : random_below(bytes.size());
    switch (random_below(6)) {
      case 0:  // flip a bit
        if (!bytes.empty()) bytes[at] = static_cast<char>(bytes[at] ^ (1 << random_below(8)));
        break;
      case 1:  // overwrite a byte
        if (!bytes.empty()) bytes[at] = random_byte();
        break;
      case 2:
        bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at), random_byte());
        break;
      case 3:
        if (!bytes.empty()) bytes.erase(at, 1);
        break;
      case 4: {  // copy a slice elsewhere: fields twice, keys inside values
        const std::size_t length = 1 + random_below(24);
        const std::string slice = bytes.substr(at, length);
        bytes.insert(random_below(bytes.size() + 1), slice);
        break;
      }
      case 5:
        bytes.resize(at);
        break;
    }
  }
  return bytes;
}

TEST(VisionFrameDifferential, RandomDamageNeverFoolsTheFastPath) {
  std::vector<std::string> valid = {
      reference_datagram(),
      make_detection_packet(spec_with_robots_and_balls()).SerializeAsString()};
  SSL_WrapperPacket with_source = make_detection_packet(spec_with_robots_and_balls());
  with_source.set_source(SSL_VISION_SOURCE_REPLAY);
  with_source.mutable_detection()->mutable_robots_blue(0)->clear_robot_id();
  valid.push_back(with_source.SerializeAsString());
  const std::vector<std::string> grsim = grsim_datagrams();
  for (std::size_t i = 0; i < grsim.size() && valid.size() < 40; i += 50)
    if (detection_only(grsim[i])) valid.push_back(grsim[i]);

  std::mt19937 rng(20240611);
  constexpr int mutations = 20000;
  int decoded = 0;
  for (int i = 0; i < mutations && !HasFailure(); ++i) {
    const std::string& original = valid[static_cast<std::size_t>(i) % valid.size()];
    SCOPED_TRACE("mutation " + std::to_string(i) + " of " + hex(original));
    decoded += decodes(damaged(original, rng));
  }
  // Damage to a float keeps a datagram valid; most other damage does not.
  EXPECT_GT(decoded, mutations / 20);
  EXPECT_LT(decoded, mutations * 9 / 10);
}

// ---- Random datagrams near the schema

enum class Anomaly {
  none,
  missing_required,
  singular_twice,
  unknown_field,
  wrong_wire_type,
  uint32_over_five_bytes_or_32_bits,
  source_out_of_range,
};
constexpr std::size_t anomaly_kinds = 7;

// Random datagrams the fast path must decode (fields in any order, optional fields left out,
// keys, lengths and uint32 values padded to up to five bytes, any float bits), or, with one
// anomaly in one message, must leave to protobuf.
class NearSchemaDatagrams {
 public:
  explicit NearSchemaDatagrams(std::uint32_t seed) : rng_(seed) {}

  struct Datagram {
    std::string bytes;
    Anomaly anomaly = Anomaly::none;
    Level level = Level::wrapper;
  };

  Datagram next() {
    Datagram out;
    out.anomaly = static_cast<Anomaly>(below(anomaly_kinds));
    if (chance(0.4)) out.anomaly = Anomaly::none;
    switch (out.anomaly) {
      case Anomaly::none:
        break;
      case Anomaly::uint32_over_five_bytes_or_32_bits:
        out.level = pick<Level>({Level::frame, Level::robot, Level::ball});
        break;
      case Anomaly::source_out_of_range:
        out.level = Level::wrapper;
        break;
      default:
        out.level = pick<Level>({Level::wrapper, Level::frame, Level::robot, Level::ball});
    }
    anomaly_ = out.anomaly;
    target_ = out.level;

    const std::size_t balls = below(4) + (target_ == Level::ball ? 1 : 0);
    const std::size_t robots = below(12) + (target_ == Level::robot ? 1 : 0);
    target_index_ = below(target_ == Level::ball ? balls : std::max<std::size_t>(robots, 1));
    Message frame{
        {1, uint32_field(1)}, {2, double_field(2)}, {3, double_field(3)}, {4, uint32_field(4)}};
    if (chance(0.5)) frame.push_back({8, double_field(8)});
    for (std::size_t i = 0; i < balls; ++i)
      frame.push_back({5, nested_field(5, finish(Level::ball, i == target_index_, ball()))});
    for (std::size_t i = 0; i < robots; ++i) {
      const std::uint32_t team = chance(0.5) ? 6 : 7;
      frame.push_back(
          {team, nested_field(team, finish(Level::robot, i == target_index_, robot()))});
    }
    Message wrapper{{1, nested_field(1, finish(Level::frame, true, std::move(frame)))}};
    if (chance(0.3) || anomaly_ == Anomaly::source_out_of_range) {
      const std::uint64_t source = anomaly_ == Anomaly::source_out_of_range
                                       ? pick<std::uint64_t>({4, 5, 100, 0xFFFFFFFF, ~0ULL})
                                       : below(4);
      wrapper.push_back({3, key(3, wire::varint_type) + padded(source)});
    }
    out.bytes = finish(Level::wrapper, true, std::move(wrapper));
    return out;
  }

 private:
  std::size_t below(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_);
  }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }
  template <typename T>
  T pick(std::initializer_list<T> values) {
    return *(values.begin() + static_cast<std::ptrdiff_t>(below(values.size())));
  }

  // Up to five bytes: what the fast path reads itself.
  std::string padded(std::uint64_t value) {
    const std::size_t canonical = wire::varint(value).size();
    return chance(0.1) && canonical < 5
               ? wire::padded_varint(value, canonical + 1 + below(5 - canonical))
               : wire::varint(value);
  }
  std::string key(std::uint32_t number, wire::Type type) {
    return padded(std::uint64_t{number} << 3 | type);
  }
  std::string uint32_field(std::uint32_t number) {
    const std::uint32_t value = pick<std::uint32_t>(
        {0, 1, 7, 127, 128, 16383, 16384, 0xFFFFFFFF, static_cast<std::uint32_t>(rng_())});
    return key(number, wire::varint_type) + padded(value);
  }
  std::string float_field(std::uint32_t number) {
    const std::uint32_t bits =
        chance(0.2) ? static_cast<std::uint32_t>(rng_())
                    : std::bit_cast<std::uint32_t>(static_cast<float>(
                          std::uniform_real_distribution<double>(-7000, 7000)(rng_)));
    return key(number, wire::fixed32_type) + wire::little_endian(bits, 4);
  }
  std::string double_field(std::uint32_t number) {
    const std::uint64_t bits =
        chance(0.1)
            ? (std::uint64_t{rng_()} << 32 | rng_())
            : std::bit_cast<std::uint64_t>(std::uniform_real_distribution<double>(0, 2e9)(rng_));
    return key(number, wire::fixed64_type) + wire::little_endian(bits, 8);
  }
  std::string nested_field(std::uint32_t number, const std::string& contents) {
    return key(number, wire::bytes_type) + padded(contents.size()) + contents;
  }

  Message robot() {
    Message m{{1, float_field(1)},
              {3, float_field(3)},
              {4, float_field(4)},
              {6, float_field(6)},
              {7, float_field(7)}};
    if (chance(0.8) || anomaly_ == Anomaly::uint32_over_five_bytes_or_32_bits)
      m.push_back({2, uint32_field(2)});
    if (chance(0.5)) m.push_back({5, float_field(5)});
    if (chance(0.5)) m.push_back({8, float_field(8)});
    return m;
  }
  Message ball() {
    Message m{{1, float_field(1)},
              {3, float_field(3)},
              {4, float_field(4)},
              {6, float_field(6)},
              {7, float_field(7)}};
    if (chance(0.5) || anomaly_ == Anomaly::uint32_over_five_bytes_or_32_bits)
      m.push_back({2, uint32_field(2)});
    if (chance(0.5)) m.push_back({5, float_field(5)});
    return m;
  }

  // The anomaly, if this is its message, then the fields shuffled and encoded.
  std::string finish(Level level, bool is_target, Message m) {
    if (level == target_ && is_target) damage(level, m);
    std::shuffle(m.begin(), m.end(), rng_);
    return encode(m);
  }

  void damage(Level level, Message& m) {
    const std::map<Level, std::vector<std::uint32_t>> required{{Level::wrapper, {1}},
                                                               {Level::frame, {1, 2, 3, 4}},
                                                               {Level::robot, {1, 3, 4, 6, 7}},
                                                               {Level::ball, {1, 3, 4, 6, 7}}};
    switch (anomaly_) {
      case Anomaly::none:
      case Anomaly::source_out_of_range:
        break;  // made with the source field itself
      case Anomaly::missing_required: {
        const std::vector<std::uint32_t>& numbers = required.at(level);
        m = without(std::move(m), numbers[below(numbers.size())]);
        break;
      }
      case Anomaly::singular_twice: {
        std::vector<const Field*> singular;
        for (const Field& field : m)
          if (level != Level::frame || field.number < 5 || field.number > 7)
            singular.push_back(&field);
        const Field copy = *singular[below(singular.size())];
        m.push_back(copy);
        break;
      }
      case Anomaly::unknown_field: {
        constexpr std::uint32_t largest_field_number = 536870911;
        const std::uint32_t first = first_unknown_field(level);
        const std::uint32_t number =
            first + static_cast<std::uint32_t>(
                        chance(0.5) ? below(40) : rng_() % (largest_field_number - first));
        m.push_back({number, wire::any_field(number, wire::all_types[below(4)])});
        break;
      }
      case Anomaly::wrong_wire_type: {
        Field& field = m[below(m.size())];
        const wire::Type type = type_of(field);
        wire::Type other = type;
        while (other == type) other = wire::all_types[below(4)];
        field.bytes = wire::any_field(field.number, other);
        break;
      }
      case Anomaly::uint32_over_five_bytes_or_32_bits: {
        const std::uint32_t number = level == Level::frame ? pick<std::uint32_t>({1, 4}) : 2;
        const std::string value = chance(0.5)
                                      ? wire::varint(std::uint64_t{1} << (32 + below(32)) | rng_())
                                      : wire::padded_varint(rng_() & 0x0FFFFFFF, 6 + below(5));
        m = replaced(std::move(m), number, wire::key(number, wire::varint_type) + value);
        break;
      }
    }
  }

  std::mt19937 rng_;
  Anomaly anomaly_ = Anomaly::none;
  Level target_ = Level::wrapper;
  std::size_t target_index_ = 0;
};

TEST(VisionFrameDifferential, RandomDatagramsNearTheSchemaAreDecodedExactlyWhenValid) {
  NearSchemaDatagrams datagrams(7);
  std::array<int, anomaly_kinds> seen{};
  for (int i = 0; i < 5000 && !HasFailure(); ++i) {
    const NearSchemaDatagrams::Datagram datagram = datagrams.next();
    SCOPED_TRACE("datagram " + std::to_string(i) + " with anomaly " +
                 std::to_string(static_cast<int>(datagram.anomaly)) + " in the " +
                 to_string(datagram.level) + ": " + hex(datagram.bytes));
    EXPECT_EQ(decodes(datagram.bytes), datagram.anomaly == Anomaly::none);
    ++seen[static_cast<std::size_t>(datagram.anomaly)];
  }
  for (std::size_t kind = 0; kind < anomaly_kinds; ++kind) EXPECT_GT(seen[kind], 50) << kind;
}

// ---- The sampler, fed either way

struct SamplerRun {
  std::vector<FormationSample> samples;
  SamplerCounters counters;
  std::size_t fast_path = 0;  // datagrams decode_detection_datagram() took
  std::size_t protobuf = 0;   // datagrams protobuf took (all of them, or those the fast path left)
  std::size_t dropped = 0;    // datagrams neither took
};

enum class Decoder { protobuf, fast_path_then_protobuf };

// Feeds `datagrams` to a sampler as a daemon does, one reused frame or packet for all of them.
SamplerRun run_sampler(const SamplerConfig& config, const std::vector<std::string>& datagrams,
                       Decoder decoder) {
  SamplerRun run;
  FormationSampler sampler(config,
                           [&](const FormationSample& sample) { run.samples.push_back(sample); });
  SSL_WrapperPacket packet;
  VisionFrame frame;
  for (const std::string& datagram : datagrams) {
    if (decoder == Decoder::fast_path_then_protobuf &&
        decode_detection_datagram(bytes_of(datagram), frame)) {
      ++run.fast_path;
      sampler.add(frame);
    } else if (protobuf_accepts(datagram, packet)) {
      ++run.protobuf;
      if (decoder == Decoder::protobuf) {
        sampler.add(packet);
      } else {
        to_vision_frame(packet, frame);
        sampler.add(frame);
      }
    } else {
      ++run.dropped;
    }
  }
  run.counters = sampler.counters();
  return run;
}

// Only 64-bit counters, so equal bytes are equal counters, whichever are added later.
static_assert(std::has_unique_object_representations_v<SamplerCounters>);
bool same_counters(const SamplerCounters& a, const SamplerCounters& b) {
  return std::memcmp(&a, &b, sizeof(SamplerCounters)) == 0;
}

void expect_same_robot(const FormationRobot& expected, const FormationRobot& actual) {
  EXPECT_EQ(expected.robot_id, actual.robot_id);
  EXPECT_EQ(expected.feed_position, actual.feed_position);
  EXPECT_EQ(expected.position, actual.position);
  EXPECT_EQ(expected.cell, actual.cell);
  EXPECT_EQ(expected.previous_cell, actual.previous_cell);
  EXPECT_EQ(expected.state, actual.state);
}

// Everything the sampler produced, compared exactly: the same input must give the same doubles.
void expect_same_output(const SamplerRun& expected, const SamplerRun& actual) {
  EXPECT_TRUE(same_counters(expected.counters, actual.counters))
      << describe_rejections(actual.counters) << "\nexpected\n"
      << describe_rejections(expected.counters);
  EXPECT_EQ(expected.dropped, actual.dropped);
  ASSERT_EQ(expected.samples.size(), actual.samples.size());
  for (std::size_t i = 0; i < expected.samples.size(); ++i) {
    SCOPED_TRACE("sample " + std::to_string(i));
    const Formation& e = expected.samples[i].formation;
    const Formation& a = actual.samples[i].formation;
    EXPECT_EQ(e.time_s, a.time_s);
    EXPECT_EQ(e.frame_number, a.frame_number);
    EXPECT_EQ(e.centroid, a.centroid);
    EXPECT_EQ(e.centroid_cell, a.centroid_cell);
    EXPECT_EQ(e.continues_previous, a.continues_previous);
    ASSERT_EQ(e.robots.size(), a.robots.size());
    for (std::size_t r = 0; r < e.robots.size(); ++r) {
      SCOPED_TRACE("robot " + std::to_string(r));
      expect_same_robot(e.robots[r], a.robots[r]);
    }
    EXPECT_EQ(expected.samples[i].transitions, actual.samples[i].transitions);
    if (::testing::Test::HasFailure()) return;
  }
}

SamplerConfig sampler_config(TeamColor opponent, Grid grid, double step_s,
                             AttackDirection attacks = AttackDirection::positive_x) {
  SamplerConfig config;
  config.opponent_color = opponent;
  config.grid = grid;
  config.step_s = step_s;
  config.opponent_attacks = attacks;
  return config;
}

TEST(VisionFrameSampler, TheGrsimLogSamplesIdenticallyThroughEitherDecoder) {
  const std::vector<std::string> datagrams = grsim_datagrams();
  for (const SamplerConfig& config :
       {sampler_config(TeamColor::yellow, Grid(12, 9), 2.0),
        sampler_config(TeamColor::blue, Grid(12, 9), 0.1, AttackDirection::negative_x),
        sampler_config(TeamColor::yellow, Grid(16, 16), 1.0 / 60.0)}) {
    SCOPED_TRACE("step " + std::to_string(config.step_s));
    const SamplerRun reference = run_sampler(config, datagrams, Decoder::protobuf);
    const SamplerRun fast = run_sampler(config, datagrams, Decoder::fast_path_then_protobuf);
    EXPECT_GE(reference.samples.size(), 5u);
    EXPECT_GT(reference.counters.transitions, 0u);
    EXPECT_GT(fast.fast_path, 2000u);
    EXPECT_GT(fast.protobuf, 0u);  // the geometry
    EXPECT_EQ(fast.fast_path + fast.protobuf, reference.protobuf);
    expect_same_output(reference, fast);
  }
}

// Four overlapping cameras at 60 Hz over 12 s of moving 11 v 11 play, with what a real feed also
// brings: geometry alone and inside detection wrappers, a field change, robots without id or at
// NaN or absurd positions, a camera id over the limit, a repeated and a late frame, a restarted
// clock, a damaged datagram, and datagrams the fast path leaves to protobuf (a trailing unknown
// field, a second detection frame, a source out of range).
std::vector<std::string> generated_stream() {
  std::vector<std::string> datagrams;
  constexpr int frames = 720;
  for (int k = 0; k < frames; ++k) {
    // The clock restarts at frame 500, as when the sender is restarted.
    const double t = k < 500 ? 100.0 + k / 60.0 : (k - 500) / 60.0;
    for (std::uint32_t camera = 0; camera < 4; ++camera) {
      DetectionFrameSpec spec;
      spec.camera_id = k == 300 && camera == 3 ? 99 : camera;
      spec.frame_number = static_cast<std::uint32_t>(k);
      spec.t_capture = t;
      spec.balls = {{1000 * std::sin(t), 500 * std::cos(t)}};
      for (std::uint32_t id = 0; id < 11; ++id) {
        for (const TeamColor team : {TeamColor::yellow, TeamColor::blue}) {
          const double phase = id * 0.7 + (team == TeamColor::blue ? 2.0 : 0.0);
          const Point at{-5000.0 + 900.0 * id + 1500.0 * std::sin(0.3 * t + phase),
                         3500.0 * std::cos(0.2 * t + phase)};
          // Each camera covers a quarter of the field and 300 mm beyond it.
          const bool right = camera >= 2;
          const bool top = camera % 2 == 1;
          if ((right ? at.x < -300 : at.x > 300) || (top ? at.y < -300 : at.y > 300)) continue;
          const Point seen{at.x + camera, at.y - camera};  // cameras disagree by a few mm
          (team == TeamColor::yellow ? spec.yellow : spec.blue).push_back({id, seen});
        }
      }
      SSL_WrapperPacket packet = make_detection_packet(spec);
      SSL_DetectionFrame& detection = *packet.mutable_detection();
      for (auto* robots : {detection.mutable_robots_yellow(), detection.mutable_robots_blue()}) {
        if (robots->size() < 3) continue;
        if (k % 97 == 0) robots->Mutable(0)->clear_robot_id();
        if (k % 89 == 0) robots->Mutable(1)->set_x(std::numeric_limits<float>::quiet_NaN());
        if (k % 83 == 0) robots->Mutable(2)->set_y(1e9F);
      }
      if (k % 150 == 0 && camera == 0)
        fill_geometry(*packet.mutable_geometry(), FieldSize{12000, 9000});
      if (k % 73 == 0) packet.set_source(SSL_VISION_SOURCE_SIMULATION);

      std::string datagram = packet.SerializeAsString();
      if (k % 71 == 0 && camera == 1) datagram += wire::varint_field(4, 1);
      if (k % 79 == 0 && camera == 2) datagram += datagram;  // protobuf merges: robots twice
      if (k % 61 == 0 && camera == 3) datagram += wire::varint_field(3, 7);
      if (k % 67 == 0 && camera == 0) datagram.resize(datagram.size() - 3);  // dropped
      datagrams.push_back(datagram);
      if (k == 200 && camera == 1) datagrams.push_back(datagram);  // sent twice
    }
    if (k % 120 == 60) {
      const FieldSize field = k == 420 ? FieldSize{9000, 6000} : FieldSize{12000, 9000};
      datagrams.push_back(make_geometry_packet(field).SerializeAsString());
    }
    if (k == 250) {  // a frame from half a second ago, late
      datagrams.push_back(make_detection_packet(
                              frame_spec(0, 220, 100.0 + 220 / 60.0, {{3, {0, 0}}}, {{3, {0, 0}}}))
                              .SerializeAsString());
    }
  }
  return datagrams;
}

TEST(VisionFrameSampler, AGeneratedMultiCameraStreamSamplesIdenticallyThroughEitherDecoder) {
  const std::vector<std::string> datagrams = generated_stream();
  for (const SamplerConfig& config :
       {sampler_config(TeamColor::yellow, Grid(12, 9), 0.5),
        sampler_config(TeamColor::blue, Grid(3, 2), 2.0, AttackDirection::negative_x),
        sampler_config(TeamColor::blue, Grid(16, 16), 0.1)}) {
    SCOPED_TRACE("step " + std::to_string(config.step_s));
    const SamplerRun reference = run_sampler(config, datagrams, Decoder::protobuf);
    const SamplerRun fast = run_sampler(config, datagrams, Decoder::fast_path_then_protobuf);
    EXPECT_GE(reference.samples.size(), 5u);
    EXPECT_GT(reference.counters.transitions, 0u);
    EXPECT_GT(reference.dropped, 0u);
    // The stream reaches the sampler's refusals, not just its happy path.
    const SamplerCounters& c = reference.counters;
    EXPECT_GT(c.robots_bad_id, 0u);
    EXPECT_GT(c.robots_non_finite, 0u);
    EXPECT_GT(c.robots_out_of_range, 0u);
    EXPECT_GT(c.robots_duplicate_in_frame, 0u);
    EXPECT_GT(c.frames_bad_camera, 0u);
    EXPECT_GT(c.frames_duplicate + c.frames_late, 0u);
    EXPECT_GT(c.field_changes, 1u);
    EXPECT_GT(c.clock_resets, 0u);
    EXPECT_GT(fast.fast_path, 2000u);
    EXPECT_GT(fast.protobuf, 30u);  // geometry and the damaged datagrams above
    EXPECT_EQ(fast.fast_path + fast.protobuf, reference.protobuf);
    expect_same_output(reference, fast);
  }
}

}  // namespace
}  // namespace ssl_formation
