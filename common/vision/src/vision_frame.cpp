#include "ssl_formation/vision/vision_frame.hpp"

#include <bit>
#include <cstring>
#include <initializer_list>
#include <type_traits>

#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
inline namespace vision {

namespace {

void copy_robots(const google::protobuf::RepeatedPtrField<SSL_DetectionRobot>& from,
                 std::vector<VisionRobot>& to) {
  to.clear();
  for (const SSL_DetectionRobot& robot : from) {
    to.push_back(
        {robot.robot_id(), robot.has_robot_id(), robot.x(), robot.y(), robot.confidence()});
  }
}

void copy_balls(const google::protobuf::RepeatedPtrField<SSL_DetectionBall>& from,
                std::vector<VisionBall>& to) {
  to.clear();
  for (const SSL_DetectionBall& ball : from) to.push_back({ball.x(), ball.y(), ball.confidence()});
}

// The protobuf wire format (https://protobuf.dev/programming-guides/encoding/), read only as far
// as the detection schema needs. Every read returns false at the first thing it does not handle;
// the caller then gives the whole datagram to protobuf.
namespace wire {

enum Type : std::uint32_t { varint_type = 0, fixed64_type = 1, bytes_type = 2, fixed32_type = 5 };

constexpr std::uint32_t tag(std::uint32_t field, Type type) { return field << 3 | type; }

class Reader {
 public:
  explicit Reader(std::span<const std::byte> bytes)
      : p_(reinterpret_cast<const unsigned char*>(bytes.data())), end_(p_ + bytes.size()) {}
  Reader(const unsigned char* begin, const unsigned char* end) : p_(begin), end_(end) {}

  bool done() const { return p_ == end_; }
  // Consumes a one-byte key if it is next.
  bool take(std::uint32_t key) {
    if (p_ == end_ || *p_ != key) return false;
    ++p_;
    return true;
  }

  // A varint of at most 32 bits. Longer ones (which protobuf truncates for uint32 fields, or
  // negative enum values) are left to protobuf.
  bool varint32(std::uint32_t& out) {
    // One byte: every key of the schema, ids and frame numbers below 128.
    if (p_ != end_ && *p_ < 0x80U) {
      out = *p_++;
      return true;
    }
    std::uint32_t value = 0;
    for (int shift = 0; shift <= 28; shift += 7) {
      if (p_ == end_) return false;
      const std::uint32_t byte = *p_++;
      if (shift == 28 && (byte & 0xF0U) != 0) return false;  // beyond 32 bits, or a 6th byte
      value |= (byte & 0x7FU) << shift;
      if ((byte & 0x80U) == 0) {
        out = value;
        return true;
      }
    }
    return false;
  }

  // A float or double: fixed-size, little-endian on the wire.
  template <class Float>
  bool fixed(Float& out) {
    if (end_ - p_ < static_cast<std::ptrdiff_t>(sizeof(Float))) return false;
    out = load_fixed<Float>(p_);
    p_ += sizeof(Float);
    return true;
  }
  // The float or double at `at`, which the caller has checked holds one.
  template <class Float,
            class Bits = std::conditional_t<sizeof(Float) == 4, std::uint32_t, std::uint64_t>>
  static Float load_fixed(const unsigned char* at) {
    Bits bits = 0;
    if constexpr (std::endian::native == std::endian::little) {
      std::memcpy(&bits, at, sizeof(Bits));
    } else {
      for (int i = sizeof(Bits) - 1; i >= 0; --i) bits = bits << 8 | at[i];
    }
    return std::bit_cast<Float>(bits);
  }
  // What is left to read.
  const unsigned char* position() const { return p_; }
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
  bool skip(std::ptrdiff_t bytes) {
    if (end_ - p_ < bytes) return false;
    p_ += bytes;
    return true;
  }

  // A length-delimited field's contents, as a reader of their own.
  bool nested(Reader& out) {
    std::uint32_t length = 0;
    if (!varint32(length) || static_cast<std::uint64_t>(end_ - p_) < length) return false;
    out = Reader(p_, p_ + length);
    p_ += length;
    return true;
  }

 private:
  const unsigned char* p_;
  const unsigned char* end_;
};

// Fields of one message seen so far: for "at most once" and "every required field" checks.
class SeenFields {
 public:
  // False if the field was seen before (protobuf would merge or overwrite: its business).
  bool first(std::uint32_t field) {
    if (field >= 32) return false;  // beyond every schema here
    const std::uint32_t bit = 1U << field;
    if ((seen_ & bit) != 0) return false;
    seen_ |= bit;
    return true;
  }
  bool has_all(std::initializer_list<std::uint32_t> fields) const {
    for (const std::uint32_t field : fields)
      if ((seen_ & (1U << field)) == 0) return false;
    return true;
  }

 private:
  std::uint32_t seen_ = 0;
};

// A robot as protobuf writes it (SSL-Vision, grSim and the simulated producer alike): every field
// once, in field-number order, the optional ones maybe missing. Read in one pass, without the
// general loop's bookkeeping; false for any other layout.
bool robot_in_order(Reader in, VisionRobot& out) {
  float ignored = 0.0F;
  if (!in.take(tag(1, fixed32_type)) || !in.fixed(out.confidence)) return false;
  out.has_robot_id = in.take(tag(2, varint_type));
  if (out.has_robot_id && !in.varint32(out.robot_id)) return false;
  if (!in.take(tag(3, fixed32_type)) || !in.fixed(out.x)) return false;
  if (!in.take(tag(4, fixed32_type)) || !in.fixed(out.y)) return false;
  if (in.take(tag(5, fixed32_type)) && !in.fixed(ignored)) return false;
  if (!in.take(tag(6, fixed32_type)) || !in.fixed(ignored)) return false;
  if (!in.take(tag(7, fixed32_type)) || !in.fixed(ignored)) return false;
  if (in.take(tag(8, fixed32_type)) && !in.fixed(ignored)) return false;
  return in.done();
}

// The two layouts nearly every robot comes in, told by their size and their keys at fixed
// offsets: every field in order with an id below 128 (SSL-Vision, ssl-producer: 37 bytes), or the
// same without height (grSim: 32 bytes). A robot is most of a packet's bytes, and this reads one
// with a comparison per field instead of a bounds check and a branch per byte read; any other
// layout is robot_in_order's. Accepts exactly what robot_in_order would for these bytes.
bool robot_common_layout(const Reader& in, VisionRobot& out) {
  constexpr std::size_t with_height = 37;
  constexpr std::size_t without_height = 32;
  const std::size_t size = in.remaining();
  if (size != with_height && size != without_height) return false;
  const unsigned char* p = in.position();
  constexpr Type f32 = fixed32_type;
  if (p[0] != tag(1, f32) || p[5] != tag(2, varint_type) || p[6] >= 0x80U || p[7] != tag(3, f32) ||
      p[12] != tag(4, f32) || p[17] != tag(5, f32) || p[22] != tag(6, f32) ||
      p[27] != tag(7, f32) || (size == with_height && p[32] != tag(8, f32))) {
    return false;
  }
  out.confidence = Reader::load_fixed<float>(p + 1);
  out.has_robot_id = true;
  out.robot_id = p[6];
  out.x = Reader::load_fixed<float>(p + 8);
  out.y = Reader::load_fixed<float>(p + 13);
  return true;
}

// SSL_DetectionRobot: confidence 1, robot_id 2, x 3, y 4, orientation 5, pixel_x 6, pixel_y 7,
// height 8.
bool robot(Reader in, VisionRobot& out) {
  if (robot_common_layout(in, out) || robot_in_order(in, out)) return true;
  out = VisionRobot{};  // nothing of the attempt stays
  SeenFields seen;
  out.has_robot_id = false;
  while (!in.done()) {
    std::uint32_t key = 0;
    if (!in.varint32(key) || !seen.first(key >> 3)) return false;
    float ignored = 0.0F;
    bool ok = false;
    switch (key) {
      case tag(1, fixed32_type):
        ok = in.fixed(out.confidence);
        break;
      case tag(2, varint_type):
        ok = out.has_robot_id = in.varint32(out.robot_id);
        break;
      case tag(3, fixed32_type):
        ok = in.fixed(out.x);
        break;
      case tag(4, fixed32_type):
        ok = in.fixed(out.y);
        break;
      case tag(5, fixed32_type):
      case tag(6, fixed32_type):
      case tag(7, fixed32_type):
      case tag(8, fixed32_type):
        ok = in.fixed(ignored);
        break;
      default:
        return false;
    }
    if (!ok) return false;
  }
  return seen.has_all({1, 3, 4, 6, 7});
}

// A ball as protobuf writes it: every field once, in field-number order, area and z maybe
// missing. Read in one pass; false for any other layout.
bool ball_in_order(Reader in, VisionBall& out) {
  std::uint32_t area = 0;
  float ignored = 0.0F;
  if (!in.take(tag(1, fixed32_type)) || !in.fixed(out.confidence)) return false;
  if (in.take(tag(2, varint_type)) && !in.varint32(area)) return false;
  if (!in.take(tag(3, fixed32_type)) || !in.fixed(out.x)) return false;
  if (!in.take(tag(4, fixed32_type)) || !in.fixed(out.y)) return false;
  if (in.take(tag(5, fixed32_type)) && !in.fixed(ignored)) return false;
  if (!in.take(tag(6, fixed32_type)) || !in.fixed(ignored)) return false;
  if (!in.take(tag(7, fixed32_type)) || !in.fixed(ignored)) return false;
  return in.done();
}

// SSL_DetectionBall: confidence 1, area 2, x 3, y 4, z 5, pixel_x 6, pixel_y 7.
bool ball(Reader in, VisionBall& out) {
  if (ball_in_order(in, out)) return true;
  out = VisionBall{};  // nothing of the attempt stays
  SeenFields seen;
  while (!in.done()) {
    std::uint32_t key = 0;
    if (!in.varint32(key) || !seen.first(key >> 3)) return false;
    std::uint32_t ignored = 0;
    bool ok = false;
    switch (key) {
      case tag(1, fixed32_type):
        ok = in.fixed(out.confidence);
        break;
      case tag(2, varint_type):
        ok = in.varint32(ignored);
        break;
      case tag(3, fixed32_type):
        ok = in.fixed(out.x);
        break;
      case tag(4, fixed32_type):
        ok = in.fixed(out.y);
        break;
      case tag(5, fixed32_type):
      case tag(6, fixed32_type):
      case tag(7, fixed32_type):
        ok = in.skip(4);
        break;
      default:
        return false;
    }
    if (!ok) return false;
  }
  return seen.has_all({1, 3, 4, 6, 7});
}

// A detection frame as protobuf writes it: every field in field-number order, the repeated ones
// in runs, t_capture_camera maybe missing. Read in one pass of expected keys, whose branches the
// CPU predicts, instead of the general loop's switch on every key (an indirect jump it mispredicts
// where one run of robots ends and the next begins); false for any other layout.
bool detection_in_order(Reader in, VisionDetection& out) {
  if (!in.take(tag(1, varint_type)) || !in.varint32(out.frame_number)) return false;
  if (!in.take(tag(2, fixed64_type)) || !in.fixed(out.t_capture)) return false;
  if (!in.take(tag(3, fixed64_type)) || !in.skip(8)) return false;
  if (!in.take(tag(4, varint_type)) || !in.varint32(out.camera_id)) return false;
  Reader nested(nullptr, nullptr);
  while (in.take(tag(5, bytes_type))) {
    if (!in.nested(nested) || !ball(nested, out.balls.emplace_back())) return false;
  }
  while (in.take(tag(6, bytes_type))) {
    if (!in.nested(nested) || !robot(nested, out.robots_yellow.emplace_back())) return false;
  }
  while (in.take(tag(7, bytes_type))) {
    if (!in.nested(nested) || !robot(nested, out.robots_blue.emplace_back())) return false;
  }
  if (in.take(tag(8, fixed64_type)) && !in.skip(8)) return false;
  return in.done();
}

// SSL_DetectionFrame: frame_number 1, t_capture 2, t_sent 3, camera_id 4, balls 5,
// robots_yellow 6, robots_blue 7, t_capture_camera 8.
bool detection(Reader in, VisionDetection& out) {
  out.robots_yellow.clear();
  out.robots_blue.clear();
  out.balls.clear();
  if (detection_in_order(in, out)) return true;
  out.robots_yellow.clear();  // nothing of the attempt stays
  out.robots_blue.clear();
  out.balls.clear();
  SeenFields seen;
  while (!in.done()) {
    std::uint32_t key = 0;
    if (!in.varint32(key)) return false;
    const std::uint32_t field = key >> 3;
    if (field < 5 || field > 7) {  // the repeated fields may come many times, the others once
      if (!seen.first(field)) return false;
    }
    Reader nested(nullptr, nullptr);
    bool ok = false;
    switch (key) {
      case tag(1, varint_type):
        ok = in.varint32(out.frame_number);
        break;
      case tag(2, fixed64_type):
        ok = in.fixed(out.t_capture);
        break;
      case tag(3, fixed64_type):
      case tag(8, fixed64_type):
        ok = in.skip(8);
        break;
      case tag(4, varint_type):
        ok = in.varint32(out.camera_id);
        break;
      case tag(5, bytes_type):
        ok = in.nested(nested) && ball(nested, out.balls.emplace_back());
        break;
      case tag(6, bytes_type):
        ok = in.nested(nested) && robot(nested, out.robots_yellow.emplace_back());
        break;
      case tag(7, bytes_type):
        ok = in.nested(nested) && robot(nested, out.robots_blue.emplace_back());
        break;
      default:
        return false;
    }
    if (!ok) return false;
  }
  return seen.has_all({1, 2, 3, 4});
}

}  // namespace wire

}  // namespace

void to_vision_frame(const SSL_WrapperPacket& packet, VisionFrame& frame) {
  frame.has_detection = packet.has_detection();
  if (frame.has_detection) {
    const SSL_DetectionFrame& detection = packet.detection();
    frame.detection.frame_number = detection.frame_number();
    frame.detection.t_capture = detection.t_capture();
    frame.detection.camera_id = detection.camera_id();
    copy_robots(detection.robots_yellow(), frame.detection.robots_yellow);
    copy_robots(detection.robots_blue(), frame.detection.robots_blue);
    copy_balls(detection.balls(), frame.detection.balls);
  }
  frame.has_geometry = packet.has_geometry();
  if (frame.has_geometry) {
    const SSL_GeometryFieldSize& field = packet.geometry().field();
    frame.field_length = field.field_length();
    frame.field_width = field.field_width();
    frame.markings = FieldMarkings{field.goal_width(),         field.goal_depth(),
                                   field.boundary_width(),     field.penalty_area_depth(),
                                   field.penalty_area_width(), field.center_circle_radius()};
  }
}

bool decode_detection_datagram(std::span<const std::byte> datagram, VisionFrame& frame) {
  // SSL_WrapperPacket: detection 1, geometry 2 (left to protobuf), source 3 (an enum, 0 to 3).
  wire::Reader in(datagram);
  wire::SeenFields seen;
  frame.has_geometry = false;
  while (!in.done()) {
    std::uint32_t key = 0;
    if (!in.varint32(key) || !seen.first(key >> 3)) return false;
    wire::Reader nested(nullptr, nullptr);
    std::uint32_t source = 0;
    switch (key) {
      case wire::tag(1, wire::bytes_type):
        if (!in.nested(nested) || !wire::detection(nested, frame.detection)) return false;
        break;
      case wire::tag(3, wire::varint_type):
        // An unknown enum value goes to protobuf's unknown fields: its business.
        if (!in.varint32(source) || source > SSL_VisionSource_MAX) return false;
        break;
      default:
        return false;
    }
  }
  frame.has_detection = seen.has_all({1});
  return frame.has_detection;
}

VisionDatagram read_vision_datagram(std::span<const std::byte> datagram, VisionFrame& frame,
                                    SSL_WrapperPacket& scratch) {
  if (decode_detection_datagram(datagram, frame)) return VisionDatagram::decoded_directly;
  // ParsePartialFromArray plus IsInitialized() is ParseFromArray without protobuf's own
  // unthrottled error log per packet. A datagram's size fits in an int.
  if (!scratch.ParsePartialFromArray(datagram.data(), static_cast<int>(datagram.size())) ||
      !scratch.IsInitialized()) {
    return VisionDatagram::invalid;
  }
  to_vision_frame(scratch, frame);
  return VisionDatagram::parsed_by_protobuf;
}

}  // namespace vision
}  // namespace ssl_formation
