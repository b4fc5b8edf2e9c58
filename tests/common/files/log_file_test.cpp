#include "ssl_formation/files/log_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <thread>
#include <tuple>
#include <type_traits>

#include "fed_pipe.hpp"
#include "gzip_member.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;
using namespace std::string_literals;

static_assert(std::is_nothrow_move_constructible_v<LogReader>);
static_assert(std::is_nothrow_move_constructible_v<LogWriter>);
static_assert(!std::is_copy_constructible_v<LogReader>);

// The error of a failed open or create, or "(opened)" when it did not fail.
template <typename T>
std::string error_of(const Result<T>& result) {
  return result ? "(opened)" : result.error().message;
}
// Why reading stopped before the end of the file, or "" for a file read to its end.
std::string stop_of(const LogVisionPackets& log) {
  return log.stopped_early ? log.stopped_early->message : "";
}

// A fresh directory per test, removed afterwards.
class LogFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("sslf-log-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    fs::remove_all(dir_);
    ASSERT_TRUE(fs::create_directories(dir_));
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path path(const std::string& name) const { return dir_ / name; }

  fs::path dir_;
};

// Writes raw bytes, gzip-compressed when the name ends in ".gz", as an independent check on the
// writer under test.
void write_file(const fs::path& path, const std::string& bytes) {
  if (path.extension() == ".gz") {
    gzFile file = gzopen(path.c_str(), "wb");
    ASSERT_NE(file, nullptr);
    ASSERT_EQ(gzwrite(file, bytes.data(), static_cast<unsigned>(bytes.size())),
              static_cast<int>(bytes.size()));
    ASSERT_EQ(gzclose(file), Z_OK);
  } else {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    ASSERT_TRUE(out.good());
  }
}

// The uncompressed bytes of a file, gzip or not.
std::string read_file(const fs::path& path) {
  gzFile file = gzopen(path.c_str(), "rb");
  EXPECT_NE(file, nullptr);
  if (file == nullptr) return {};
  std::string bytes;
  char buffer[65536];
  int got = 0;
  while ((got = gzread(file, buffer, sizeof buffer)) > 0) bytes.append(buffer, got);
  gzclose(file);
  return bytes;
}

std::string raw_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void put_be(std::string& out, std::uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

std::int64_t get_be64(const std::string& bytes, std::size_t at) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
  return static_cast<std::int64_t>(v);
}

std::string file_header(std::int32_t version = 1) {
  std::string out = "SSL_LOG_FILE";
  put_be(out, static_cast<std::uint32_t>(version), 4);
  return out;
}

std::string message_bytes(std::int64_t time_ns, std::int32_t type, std::int32_t size,
                          const std::string& payload) {
  std::string out;
  put_be(out, static_cast<std::uint64_t>(time_ns), 8);
  put_be(out, static_cast<std::uint32_t>(type), 4);
  put_be(out, static_cast<std::uint32_t>(size), 4);
  return out + payload;
}

std::string message_bytes(std::int64_t time_ns, std::int32_t type, const std::string& payload) {
  return message_bytes(time_ns, type, static_cast<std::int32_t>(payload.size()), payload);
}

SSL_WrapperPacket detection_packet(std::uint32_t camera, std::uint32_t frame_number) {
  SSL_WrapperPacket packet;
  SSL_DetectionFrame& frame = *packet.mutable_detection();
  frame.set_frame_number(frame_number);
  frame.set_t_capture(100.0 + frame_number / 60.0);
  frame.set_t_sent(100.001 + frame_number / 60.0);
  frame.set_camera_id(camera);
  SSL_DetectionRobot& robot = *frame.add_robots_yellow();
  robot.set_confidence(0.9f);
  robot.set_robot_id(3);
  robot.set_x(1000.0f + static_cast<float>(frame_number));
  robot.set_y(-500.0f);
  robot.set_pixel_x(1.0f);
  robot.set_pixel_y(2.0f);
  return packet;
}

std::string vision_message(std::int64_t time_ns, std::uint32_t camera, std::uint32_t frame) {
  return message_bytes(time_ns, 4, detection_packet(camera, frame).SerializeAsString());
}

// ---------------------------------------------------------------------------------------------
// Round trips

class LogFileRoundTrip : public LogFileTest, public ::testing::WithParamInterface<const char*> {};

INSTANTIATE_TEST_SUITE_P(LogFile, LogFileRoundTrip, ::testing::Values(".log", ".log.gz"),
                         [](const auto& info) {
                           return std::string(info.param) == ".log" ? "Plain" : "Gzip";
                         });

struct Written {
  std::int32_t type;
  std::int64_t time_ns;
  std::string payload;
};

std::vector<Written> every_type() {
  std::string large(600 * 1024, '\0');  // larger than the reader's buffer
  for (std::size_t i = 0; i < large.size(); ++i) large[i] = static_cast<char>(i * 7 + i / 1000);
  return {
      {0, 1'000'000'000, ""},
      {1, 1'000'000'001, "unknown bytes"},
      {2, 1'000'000'002, detection_packet(0, 1).SerializeAsString()},
      {3, 1'000'000'003, "referee"},
      {4, 1'000'000'004, detection_packet(1, 2).SerializeAsString()},
      {5, 1'000'000'005, "tracker"},
      {99, -7, large},
      {4, std::int64_t{1} << 62, detection_packet(2, 3).SerializeAsString()},
  };
}

TEST_P(LogFileRoundTrip, EveryMessageTypeComesBackWithItsTimeOffsetAndPayload) {
  const fs::path file = path(std::string("round") + GetParam());
  const std::vector<Written> written = every_type();
  {
    Result<LogWriter> writer = LogWriter::create(file);
    ASSERT_TRUE(writer) << error_of(writer);
    for (const Written& w : written) ASSERT_TRUE(writer->write(w.type, w.time_ns, w.payload));
    ASSERT_TRUE(writer->write_vision(detection_packet(3, 4), 42));
    ASSERT_TRUE(writer->close()) << writer->error();
  }
  // Compressed exactly when the name says so.
  const std::string on_disk = raw_bytes(file);
  const bool gzip = std::string(GetParam()) == ".log.gz";
  ASSERT_GE(on_disk.size(), 2u);
  EXPECT_EQ(on_disk.rfind("\x1f\x8b", 0) == 0, gzip);
  EXPECT_EQ(on_disk.rfind("SSL_LOG_FILE", 0) == 0, !gzip);

  Result<LogReader> reader = LogReader::open(file);
  ASSERT_TRUE(reader) << error_of(reader);
  EXPECT_EQ(reader->offset(), 16u);
  EXPECT_EQ(reader->compressed_size(), on_disk.size());
  LogMessage message;
  std::uint64_t expected_offset = 16;
  for (const Written& w : written) {
    ASSERT_TRUE(reader->next(message)) << reader->error();
    EXPECT_EQ(message.type, w.type);
    EXPECT_EQ(message.receive_time_ns, w.time_ns);
    EXPECT_EQ(message.offset, expected_offset);
    EXPECT_TRUE(message.payload == w.payload) << "type " << w.type;
    expected_offset += 16 + w.payload.size();
    EXPECT_EQ(reader->offset(), expected_offset);
  }
  ASSERT_TRUE(reader->next(message));
  EXPECT_EQ(message.type, 4);
  EXPECT_EQ(message.receive_time_ns, 42);
  SSL_WrapperPacket packet;
  ASSERT_TRUE(packet.ParseFromString(message.payload));
  EXPECT_EQ(packet.detection().camera_id(), 3u);
  EXPECT_FALSE(reader->next(message));
  EXPECT_EQ(reader->error(), "");
  EXPECT_FALSE(reader->next(message)) << "stays at the end";
  EXPECT_EQ(reader->offset(), read_file(file).size());
  EXPECT_EQ(reader->compressed_offset(), on_disk.size());

  const LogReadCounters& c = reader->counters();
  EXPECT_EQ(c.messages, written.size() + 1);
  EXPECT_EQ(c.blank, 1u);
  EXPECT_EQ(c.unknown, 2u);  // type 1 and type 99
  EXPECT_EQ(c.legacy_vision, 1u);
  EXPECT_EQ(c.referee, 1u);
  EXPECT_EQ(c.vision, 3u);
  EXPECT_EQ(c.tracker, 1u);
  EXPECT_EQ(c.index, 0u);
  EXPECT_EQ(c.parse_errors, 0u);
  EXPECT_EQ(c.bytes, reader->offset());
}

// `ssl-trainer --from-log <(zcat day1/*.log.gz)` and the like: a log read from a pipe loses
// nothing, also its first bytes (the reader must not peek at them before zlib reads).
TEST_P(LogFileRoundTrip, ALogReadFromAPipeGivesEveryMessage) {
  const fs::path file = path(std::string("piped") + GetParam());
  const std::vector<Written> written = every_type();
  {
    Result<LogWriter> writer = LogWriter::create(file);
    ASSERT_TRUE(writer) << error_of(writer);
    for (const Written& w : written) ASSERT_TRUE(writer->write(w.type, w.time_ns, w.payload));
    ASSERT_TRUE(writer->close()) << writer->error();
  }
  // A pipe, named as a shell's process substitution names one (/dev/fd/N). Everything is read
  // before anything is checked.
  std::vector<LogMessage> got;
  std::string open_error, read_error;
  {
    const testing::FedPipe pipe(raw_bytes(file));
    Result<LogReader> reader = LogReader::open(pipe.path());
    if (reader) {
      LogMessage message;
      while (reader->next(message)) got.push_back(message);
      read_error = reader->error();
    } else {
      open_error = error_of(reader);
    }
  }
  ASSERT_EQ(open_error, "");
  EXPECT_EQ(read_error, "");
  ASSERT_EQ(got.size(), written.size());
  for (std::size_t i = 0; i < written.size(); ++i) {
    EXPECT_EQ(got[i].type, written[i].type);
    EXPECT_EQ(got[i].receive_time_ns, written[i].time_ns);
    EXPECT_TRUE(got[i].payload == written[i].payload) << "type " << written[i].type;
  }
}

TEST_P(LogFileRoundTrip, IndexedFileEndsWithTheOfficialIndexAndReadsCleanly) {
  const fs::path file = path(std::string("indexed") + GetParam());
  const std::vector<Written> written = every_type();
  {
    Result<LogWriter> writer = LogWriter::create(file);
    ASSERT_TRUE(writer);
    for (const Written& w : written) ASSERT_TRUE(writer->write(w.type, w.time_ns, w.payload));
    ASSERT_TRUE(writer->close(true)) << writer->error();
  }
  // Layout as ssl-go-tools writes it: index message whose payload is the offsets, the distance
  // back from the end of the file to the index message, and "INDEXED".
  const std::string bytes = read_file(file);
  ASSERT_GT(bytes.size(), 16u + 15u);
  EXPECT_EQ(bytes.substr(bytes.size() - 7), "INDEXED");
  const std::int64_t back = get_be64(bytes, bytes.size() - 15);
  ASSERT_GT(back, 16);
  ASSERT_LE(static_cast<std::size_t>(back), bytes.size());
  const std::size_t index_at = bytes.size() - static_cast<std::size_t>(back);
  EXPECT_EQ(get_be64(bytes, index_at + 8) >> 32, 6) << "type of the index message";
  EXPECT_EQ(static_cast<std::size_t>(get_be64(bytes, index_at + 8) & 0xffffffff),
            written.size() * 8 + 15)
      << "size of the index message";

  Result<LogReader> reader = LogReader::open(file);
  ASSERT_TRUE(reader);
  LogMessage message;
  std::size_t i = 0;
  while (reader->next(message)) {
    ASSERT_LT(i, written.size());
    EXPECT_EQ(message.type, written[i].type);
    EXPECT_EQ(static_cast<std::int64_t>(message.offset), get_be64(bytes, index_at + 16 + 8 * i))
        << "index entry " << i;
    ++i;
  }
  EXPECT_EQ(reader->error(), "");
  EXPECT_EQ(i, written.size());
  EXPECT_EQ(reader->counters().index, 1u);
  EXPECT_EQ(reader->offset(), index_at) << "stops at the index message";
}

// Reads `file` with both next_vision overloads: the frames must be to_vision_frame() of the
// packets, with the same receive times, the same counters, the same ending and error.
bool same_robots(const std::vector<VisionRobot>& a, const std::vector<VisionRobot>& b) {
  return std::equal(
      a.begin(), a.end(), b.begin(), b.end(), [](const VisionRobot& x, const VisionRobot& y) {
        return x.robot_id == y.robot_id && x.has_robot_id == y.has_robot_id &&
               std::bit_cast<std::uint32_t>(x.x) == std::bit_cast<std::uint32_t>(y.x) &&
               std::bit_cast<std::uint32_t>(x.y) == std::bit_cast<std::uint32_t>(y.y) &&
               std::bit_cast<std::uint32_t>(x.confidence) ==
                   std::bit_cast<std::uint32_t>(y.confidence);
      });
}

std::size_t expect_frames_as_packets(const fs::path& file) {
  Result<LogReader> by_packet = LogReader::open(file);
  Result<LogReader> by_frame = LogReader::open(file);
  if (!by_packet || !by_frame) {
    ADD_FAILURE() << error_of(by_packet);
    return 0;
  }
  SSL_WrapperPacket packet;
  VisionFrame frame;
  VisionFrame expected;
  std::int64_t packet_ns = -1;
  std::int64_t frame_ns = -1;
  std::size_t n = 0;
  for (;; ++n) {
    const bool more = by_packet->next_vision(packet, &packet_ns);
    EXPECT_EQ(by_frame->next_vision(frame, &frame_ns), more) << "packet " << n;
    if (!more) break;
    to_vision_frame(packet, expected);
    const VisionDetection& a = frame.detection;
    const VisionDetection& b = expected.detection;
    EXPECT_EQ(frame_ns, packet_ns) << "packet " << n;
    EXPECT_EQ(frame.has_detection, expected.has_detection) << "packet " << n;
    EXPECT_EQ(frame.has_geometry, expected.has_geometry) << "packet " << n;
    if (frame.has_geometry && expected.has_geometry) {
      EXPECT_EQ(frame.field_length, expected.field_length) << "packet " << n;
      EXPECT_EQ(frame.field_width, expected.field_width) << "packet " << n;
    }
    if (frame.has_detection && expected.has_detection) {
      EXPECT_EQ(a.frame_number, b.frame_number) << "packet " << n;
      EXPECT_EQ(std::bit_cast<std::uint64_t>(a.t_capture),
                std::bit_cast<std::uint64_t>(b.t_capture))
          << "packet " << n;
      EXPECT_EQ(a.camera_id, b.camera_id) << "packet " << n;
      EXPECT_TRUE(same_robots(a.robots_yellow, b.robots_yellow)) << "packet " << n;
      EXPECT_TRUE(same_robots(a.robots_blue, b.robots_blue)) << "packet " << n;
    }
    if (::testing::Test::HasFailure()) return n;
  }
  const LogReadCounters& a = by_frame->counters();
  const LogReadCounters& b = by_packet->counters();
  EXPECT_EQ(std::tie(a.messages, a.vision, a.legacy_vision, a.referee, a.tracker, a.index,
                     a.unknown, a.parse_errors, a.bytes, a.blank, a.legacy_unusable),
            std::tie(b.messages, b.vision, b.legacy_vision, b.referee, b.tracker, b.index,
                     b.unknown, b.parse_errors, b.bytes, b.blank, b.legacy_unusable));
  EXPECT_EQ(by_frame->error(), by_packet->error());
  EXPECT_EQ(by_frame->ending(), by_packet->ending());
  return n;
}

TEST_P(LogFileRoundTrip, NextVisionReturnsVisionAndCompatibleLegacyPacketsAndCountsTheRest) {
  const fs::path file = path(std::string("mixed") + GetParam());
  // A 2010-schema packet: today's detection fields plus the old geometry, whose field 1 was the
  // line width (10 mm) and field 2 the field length (9000 mm).
  SSL_WrapperPacket legacy_detection = detection_packet(5, 77);
  legacy_detection.mutable_detection()->clear_t_sent();
  legacy_detection.mutable_detection()->mutable_robots_yellow(0)->clear_pixel_x();
  const std::string old_field_size = "\x08\x0a\x10\xa8\x46";
  const std::string old_geometry =
      std::string("\x0a") + char(old_field_size.size()) + old_field_size;
  const std::string legacy = legacy_detection.SerializePartialAsString() + "\x12" +
                             char(old_geometry.size()) + old_geometry;
  SSL_WrapperPacket probe;
  ASSERT_TRUE(probe.ParsePartialFromString(legacy));
  ASSERT_EQ(probe.geometry().field().field_length(), 10) << "the test's premise";

  SSL_WrapperPacket ball_without_y = detection_packet(5, 78);
  SSL_DetectionBall& ball = *ball_without_y.mutable_detection()->add_balls();
  ball.set_x(1.0f);

  SSL_WrapperPacket geometry_only;
  geometry_only.mutable_geometry()->mutable_field()->set_field_length(9000);

  std::string bytes = file_header();
  bytes += message_bytes(1, 3, "referee");
  bytes += vision_message(2, 0, 10);
  bytes += message_bytes(3, 5, "tracker");
  bytes += message_bytes(4, 4, "\xff\xff\xff garbage");  // does not parse
  bytes += message_bytes(5, 4, "");                      // an empty packet: valid
  bytes += message_bytes(6, 2, legacy);
  bytes += message_bytes(7, 2, geometry_only.SerializePartialAsString());  // no detection
  bytes += message_bytes(8, 2, "\xff\xff\xff");
  bytes += message_bytes(8, 2, ball_without_y.SerializePartialAsString());
  bytes += message_bytes(9, 0, "");
  bytes += message_bytes(10, 99, "?");
  bytes += vision_message(11, 1, 12);
  write_file(file, bytes);

  Result<LogReader> reader = LogReader::open(file);
  ASSERT_TRUE(reader);
  SSL_WrapperPacket packet;
  std::int64_t time_ns = 0;
  std::vector<std::int64_t> times;
  std::vector<SSL_WrapperPacket> packets;
  while (reader->next_vision(packet, &time_ns)) {
    packets.push_back(packet);
    times.push_back(time_ns);
  }
  EXPECT_EQ(reader->error(), "");
  // An empty type-4 payload is a valid SSL_WrapperPacket (all its fields are optional).
  ASSERT_EQ(times, (std::vector<std::int64_t>{2, 5, 6, 11}));
  EXPECT_EQ(packets[0].detection().frame_number(), 10u);
  EXPECT_FALSE(packets[1].has_detection());
  const SSL_WrapperPacket& adopted = packets[2];
  EXPECT_EQ(adopted.detection().camera_id(), 5u);
  EXPECT_EQ(adopted.detection().frame_number(), 77u);
  EXPECT_FLOAT_EQ(adopted.detection().robots_yellow(0).x(), 1077.0f);
  EXPECT_FALSE(adopted.has_geometry()) << "2010 geometry would be misread, so it is dropped";
  EXPECT_TRUE(adopted.IsInitialized()) << adopted.InitializationErrorString();
  EXPECT_DOUBLE_EQ(adopted.detection().t_sent(), adopted.detection().t_capture());
  EXPECT_EQ(packets[3].detection().camera_id(), 1u);

  const LogReadCounters& c = reader->counters();
  EXPECT_EQ(c.messages, 12u);
  EXPECT_EQ(c.vision, 4u);
  EXPECT_EQ(c.legacy_vision, 4u);
  EXPECT_EQ(c.referee, 1u);
  EXPECT_EQ(c.tracker, 1u);
  EXPECT_EQ(c.blank, 1u);
  EXPECT_EQ(c.unknown, 1u);
  EXPECT_EQ(c.parse_errors, 2u);     // the garbage type 4 and the garbage type 2
  EXPECT_EQ(c.legacy_unusable, 2u);  // no detection; a ball without y

  EXPECT_EQ(expect_frames_as_packets(file), 4u) << "the VisionFrame reader sees the same packets";
}

// ---------------------------------------------------------------------------------------------
// The real recording

TEST(LogFileGrSim, ReadsAllVisionPacketsOfTheRecording) {
  const fs::path file = fs::path(SSLF_TEST_DATA_DIR) / "grsim-4cam-11v11-idle.log.gz";
  const LogVisionPackets log = read_vision_log(file).value();
  EXPECT_EQ(stop_of(log), "");
  EXPECT_EQ(log.ending, LogReader::Ending::none);
  ASSERT_EQ(log.packets.size(), 2353u);
  ASSERT_EQ(log.receive_times_ns.size(), log.packets.size());
  std::set<std::uint32_t> cameras;
  for (const SSL_WrapperPacket& packet : log.packets) {
    ASSERT_TRUE(packet.has_detection());
    cameras.insert(packet.detection().camera_id());
  }
  EXPECT_EQ(cameras.size(), 4u);
  EXPECT_EQ(log.counters.vision, 2353u);
  EXPECT_EQ(log.counters.messages, 2353u);
  EXPECT_EQ(log.counters.parse_errors, 0u);
  // Ten seconds of nanosecond receive times.
  const std::int64_t span = log.receive_times_ns.back() - log.receive_times_ns.front();
  EXPECT_GT(span, 9'000'000'000);
  EXPECT_LT(span, 11'000'000'000);

  Result<LogReader> reader = LogReader::open(file);
  ASSERT_TRUE(reader);
  EXPECT_EQ(reader->compressed_size(), fs::file_size(file));
  SSL_WrapperPacket packet;
  while (reader->next_vision(packet)) {
  }
  EXPECT_EQ(reader->offset(), read_file(file).size());
  EXPECT_EQ(reader->compressed_offset(), fs::file_size(file));
}

// Offline training reads frames (detection packets decoded straight from the bytes, the
// geometry-carrying ones through protobuf): the same frames, times and counters as the packets.
TEST(LogFileGrSim, VisionFramesAreThePacketsOfTheRecording) {
  EXPECT_EQ(expect_frames_as_packets(fs::path(SSLF_TEST_DATA_DIR) / "grsim-4cam-11v11-idle.log.gz"),
            2353u);
  EXPECT_GT(expect_frames_as_packets(fs::path(SSLF_TEST_DATA_DIR) / "step-golden.log.gz"), 0u);
}

// ---------------------------------------------------------------------------------------------
// Damaged files: the error names the byte, and what came before is kept

class LogFileDamaged : public LogFileTest, public ::testing::WithParamInterface<const char*> {
 protected:
  fs::path file() const { return path(std::string("damaged") + GetParam()); }
  // The file header and three good vision messages.
  std::string good_prefix() const {
    return file_header() + vision_message(1, 0, 1) + vision_message(2, 1, 2) +
           vision_message(3, 2, 3);
  }
};

INSTANTIATE_TEST_SUITE_P(LogFile, LogFileDamaged, ::testing::Values(".log", ".log.gz"),
                         [](const auto& info) {
                           return std::string(info.param) == ".log" ? "Plain" : "Gzip";
                         });

TEST_P(LogFileDamaged, BadHeader) {
  std::string bytes = good_prefix();
  bytes[3] = 'X';
  write_file(file(), bytes);
  const auto opened = LogReader::open(file());
  EXPECT_FALSE(opened);
  EXPECT_EQ(error_of(opened), file().string() + ": not an SSL log file (bad header at byte 0)");
  const auto log = read_vision_log(file());
  EXPECT_FALSE(log) << "no packets from a file without a header";
  EXPECT_EQ(error_of(log), error_of(opened));
}

TEST_P(LogFileDamaged, TextFileIsNotALog) {
  write_file(file(), "hello\n");
  const auto opened = LogReader::open(file());
  EXPECT_FALSE(opened);
  EXPECT_EQ(error_of(opened), file().string() + ": not an SSL log file (bad header at byte 0)");
}

TEST_P(LogFileDamaged, EmptyFile) {
  write_file(file(), "");
  const auto opened = LogReader::open(file());
  EXPECT_FALSE(opened);
  EXPECT_EQ(error_of(opened), file().string() + ": not an SSL log file (empty)");
}

TEST_P(LogFileDamaged, HeaderCutInsideTheVersion) {
  write_file(file(), "SSL_LOG_FILE\0\0"s);
  const auto opened = LogReader::open(file());
  EXPECT_FALSE(opened);
  EXPECT_EQ(error_of(opened),
            file().string() + ": truncated header at byte 12: the version needs 4 bytes, 2 remain");
}

TEST_P(LogFileDamaged, WrongVersion) {
  write_file(file(), file_header(2) + vision_message(1, 0, 1));
  const auto opened = LogReader::open(file());
  EXPECT_FALSE(opened);
  EXPECT_EQ(error_of(opened), file().string() + ": unsupported log version 2 at byte 12");
}

TEST_P(LogFileDamaged, NegativeSize) {
  const std::string prefix = good_prefix();
  write_file(file(), prefix + message_bytes(4, 4, -5, "") + vision_message(5, 3, 4));
  const LogVisionPackets log = read_vision_log(file()).value();
  EXPECT_EQ(stop_of(log),
            file().string() + ": absurd message size -5 at byte " + std::to_string(prefix.size()));
  ASSERT_EQ(log.packets.size(), 3u) << "the packets before the bad message are kept";
  EXPECT_EQ(log.ending, LogReader::Ending::damaged);
  EXPECT_EQ(log.packets[2].detection().frame_number(), 3u);
  EXPECT_EQ(log.receive_times_ns, (std::vector<std::int64_t>{1, 2, 3}));
}

TEST_P(LogFileDamaged, AbsurdSize) {
  const std::string prefix = good_prefix();
  write_file(file(), prefix + message_bytes(4, 4, 16 * 1024 * 1024 + 1, "abc"));
  Result<LogReader> reader = LogReader::open(file());
  ASSERT_TRUE(reader);
  LogMessage message;
  int read = 0;
  while (reader->next(message)) ++read;
  EXPECT_EQ(read, 3);
  EXPECT_EQ(reader->error(), file().string() + ": absurd message size 16777217 at byte " +
                                 std::to_string(prefix.size()));
  EXPECT_FALSE(reader->next(message)) << "an error is final";
}

TEST_P(LogFileDamaged, SixteenMebibytesIsNotAbsurdButTruncated) {
  const std::string prefix = good_prefix();
  write_file(file(), prefix + message_bytes(4, 1, 16 * 1024 * 1024, std::string(300'000, 'x')));
  const LogVisionPackets log = read_vision_log(file()).value();
  EXPECT_EQ(stop_of(log), file().string() + ": truncated message at byte " +
                              std::to_string(prefix.size()) +
                              ": header says 16777216 bytes, 300000 remain");
  EXPECT_EQ(log.packets.size(), 3u);
}

TEST_P(LogFileDamaged, TruncatedLastMessage) {
  const std::string prefix = good_prefix();
  const std::string last = vision_message(4, 3, 4);
  write_file(file(), prefix + last.substr(0, 16 + 10));
  const LogVisionPackets log = read_vision_log(file()).value();
  EXPECT_EQ(stop_of(log), file().string() + ": truncated message at byte " +
                              std::to_string(prefix.size()) + ": header says " +
                              std::to_string(last.size() - 16) + " bytes, 10 remain");
  EXPECT_EQ(log.packets.size(), 3u);
  EXPECT_EQ(log.ending, LogReader::Ending::cut_off);
  EXPECT_EQ(log.counters.vision, 3u);
  EXPECT_EQ(expect_frames_as_packets(file()), 3u);
}

TEST_P(LogFileDamaged, TruncatedInsideAMessageHeader) {
  const std::string prefix = good_prefix();
  write_file(file(), prefix + vision_message(4, 3, 4).substr(0, 5));
  const LogVisionPackets log = read_vision_log(file()).value();
  EXPECT_EQ(stop_of(log), file().string() + ": truncated message header at byte " +
                              std::to_string(prefix.size()) + ": 16 bytes needed, 5 remain");
  EXPECT_EQ(log.packets.size(), 3u);
}

TEST_F(LogFileTest, CutOffGzipStreamIsAnErrorAndKeepsWhatCameBefore) {
  const fs::path whole = path("whole.log.gz");
  {
    Result<LogWriter> writer = LogWriter::create(whole);
    ASSERT_TRUE(writer);
    for (std::uint32_t i = 0; i < 2000; ++i)
      ASSERT_TRUE(writer->write_vision(detection_packet(i % 4, i), i));
    ASSERT_TRUE(writer->close());
  }
  const std::string bytes = raw_bytes(whole);
  const fs::path cut = path("cut.log.gz");
  {
    std::ofstream out(cut, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
  }
  const LogVisionPackets log = read_vision_log(cut).value();
  EXPECT_NE(stop_of(log).find(cut.string() + ": truncated message"), std::string::npos)
      << stop_of(log);
  EXPECT_NE(stop_of(log).find("gzip stream is cut off"), std::string::npos) << stop_of(log);
  EXPECT_GT(log.packets.size(), 100u);
  EXPECT_LT(log.packets.size(), 2000u);
  for (std::size_t i = 0; i < log.packets.size(); ++i)
    ASSERT_EQ(log.packets[i].detection().frame_number(), i);
}

// ---------------------------------------------------------------------------------------------
// The two inflaters: ISA-L's reads what zlib's reads, and loses nothing more when a file is bad

// Everything a reader gives with one inflater, and where it got to on disk after each message.
struct Reading {
  Inflater inflater = Inflater::automatic;
  std::vector<LogMessage> messages;
  std::vector<std::uint64_t> compressed_offsets;
  std::string error;
  LogReader::Ending ending = LogReader::Ending::none;
};

Reading read_with(const fs::path& file, Inflater inflater) {
  Reading out;
  Result<LogReader> reader = LogReader::open(file, inflater);
  if (!reader) {
    ADD_FAILURE() << error_of(reader);
    return out;
  }
  out.inflater = reader->inflater();
  LogMessage message;
  while (reader->next(message)) {
    out.messages.push_back(message);
    out.compressed_offsets.push_back(reader->compressed_offset());
  }
  out.error = reader->error();
  out.ending = reader->ending();
  return out;
}

bool same_message(const LogMessage& a, const LogMessage& b) {
  return a.type == b.type && a.receive_time_ns == b.receive_time_ns && a.offset == b.offset &&
         a.payload == b.payload;
}

// How many of `got` come first in `expected`, each the same message (reported when not).
std::size_t same_prefix(const std::vector<LogMessage>& got,
                        const std::vector<LogMessage>& expected) {
  std::size_t i = 0;
  for (; i < got.size() && i < expected.size(); ++i) {
    if (!same_message(got[i], expected[i])) {
      ADD_FAILURE() << "message " << i << " differs";
      break;
    }
  }
  return i;
}

// Both inflaters read every message of `file`, the same as zlib's, to a clean end.
void expect_both_read_it_all(const fs::path& file, std::size_t expected_messages) {
  const Reading zlib = read_with(file, Inflater::zlib);
  const Reading isal = read_with(file, Inflater::isal);
  EXPECT_EQ(zlib.inflater, Inflater::zlib);
  EXPECT_EQ(isal.inflater, Inflater::isal);
  for (const Reading* reading : {&zlib, &isal}) {
    EXPECT_EQ(reading->error, "");
    EXPECT_EQ(reading->ending, LogReader::Ending::none);
    ASSERT_EQ(reading->messages.size(), expected_messages);
    // Progress moves forward to the end of the file.
    EXPECT_TRUE(
        std::is_sorted(reading->compressed_offsets.begin(), reading->compressed_offsets.end()));
    EXPECT_EQ(reading->compressed_offsets.back(), fs::file_size(file));
  }
  EXPECT_EQ(same_prefix(isal.messages, zlib.messages), expected_messages);
}

std::vector<Written> many_vision_messages(std::uint32_t count) {
  std::vector<Written> out;
  for (std::uint32_t i = 0; i < count; ++i) {
    out.push_back({4, 1'000'000 * std::int64_t{i}, detection_packet(i % 4, i).SerializeAsString()});
  }
  return out;
}

#define SKIP_WITHOUT_ISAL() \
  if (!isal_available()) GTEST_SKIP() << "this build has no ISA-L (SSLF_ISAL)"

TEST_F(LogFileTest, BothInflatersReadEveryMessageOfAWrittenLog) {
  SKIP_WITHOUT_ISAL();
  const fs::path file = path("written.log.gz");
  std::vector<Written> written = every_type();
  for (Written& w : many_vision_messages(40'000)) written.push_back(std::move(w));
  {
    Result<LogWriter> writer = LogWriter::create(file);
    ASSERT_TRUE(writer) << error_of(writer);
    for (const Written& w : written) ASSERT_TRUE(writer->write(w.type, w.time_ns, w.payload));
    ASSERT_TRUE(writer->close()) << writer->error();
  }
  expect_both_read_it_all(file, written.size());
  const Reading isal = read_with(file, Inflater::isal);
  ASSERT_EQ(isal.messages.size(), written.size());
  for (std::size_t i = 0; i < written.size(); ++i) {
    ASSERT_EQ(isal.messages[i].type, written[i].type) << "message " << i;
    ASSERT_TRUE(isal.messages[i].payload == written[i].payload) << "message " << i;
  }
  // Several reads of compressed input, each showing in the progress.
  const std::set<std::uint64_t> offsets(isal.compressed_offsets.begin(),
                                        isal.compressed_offsets.end());
  EXPECT_GE(offsets.size(), 3u) << "a file of " << fs::file_size(file) << " bytes";
  EXPECT_LT(isal.compressed_offsets.front(), fs::file_size(file));
}

// `cat a.log.gz b.log.gz`, split inside a message: the members read as one stream.
TEST_F(LogFileTest, BothInflatersReadALogOfSeveralGzipMembers) {
  SKIP_WITHOUT_ISAL();
  std::string bytes = file_header();
  const std::vector<Written> written = many_vision_messages(5'000);
  for (const Written& w : written) bytes += message_bytes(w.time_ns, w.type, w.payload);
  const std::size_t split = bytes.size() / 3 + 5;
  const fs::path file = path("members.log.gz");
  std::ofstream(file, std::ios::binary)
      << testing::gzip_member(bytes.substr(0, split))
      << testing::gzip_member(bytes.substr(split, split), 1, "second.log")
      << testing::gzip_member(bytes.substr(2 * split));
  expect_both_read_it_all(file, written.size());
}

TEST_F(LogFileTest, BothInflatersReadTheRecording) {
  SKIP_WITHOUT_ISAL();
  expect_both_read_it_all(fs::path(SSLF_TEST_DATA_DIR) / "grsim-4cam-11v11-idle.log.gz", 2353u);
}

fs::path write_vision_log(const fs::path& file, std::uint32_t count) {
  Result<LogWriter> writer = LogWriter::create(file);
  EXPECT_TRUE(writer) << error_of(writer);
  for (std::uint32_t i = 0; writer && i < count; ++i) {
    EXPECT_TRUE(writer->write_vision(detection_packet(i % 4, i), i));
  }
  EXPECT_TRUE(writer && writer->close());
  return file;
}

TEST_F(LogFileTest, ACutOffGzipLogIsCutOffWithBothAndBothKeepTheSame) {
  SKIP_WITHOUT_ISAL();
  const std::string bytes = raw_bytes(write_vision_log(path("whole.log.gz"), 20'000));
  const fs::path cut = path("cut.log.gz");
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
  const Reading zlib = read_with(cut, Inflater::zlib);
  const Reading isal = read_with(cut, Inflater::isal);
  EXPECT_EQ(isal.ending, LogReader::Ending::cut_off);
  EXPECT_NE(isal.error.find("the gzip stream is cut off"), std::string::npos) << isal.error;
  EXPECT_GT(isal.messages.size(), 10'000u);
  EXPECT_LT(isal.messages.size(), 20'000u);
  // zlib gives what comes before a cut too: the same messages and the same error.
  EXPECT_EQ(isal.ending, zlib.ending);
  EXPECT_EQ(isal.error, zlib.error);
  EXPECT_EQ(same_prefix(isal.messages, zlib.messages), zlib.messages.size());
  EXPECT_EQ(isal.messages.size(), zlib.messages.size());
}

// A second member whose first deflate block has the reserved type 3: invalid from its first bit.
TEST_F(LogFileTest, ADamagedGzipMemberIsDamagedWithBothAndIsalKeepsAllBeforeIt) {
  SKIP_WITHOUT_ISAL();
  const std::vector<Written> written = many_vision_messages(12'000);
  std::string first = file_header();
  std::string second;
  for (std::size_t i = 0; i < written.size(); ++i) {
    (i < 10'000 ? first : second) += message_bytes(written[i].time_ns, 4, written[i].payload);
  }
  std::string damaged = testing::gzip_member(second);
  damaged[10] = static_cast<char>(damaged[10] | 0x06);  // after the 10-byte header: BTYPE = 3
  const fs::path file = path("damaged-member.log.gz");
  std::ofstream(file, std::ios::binary) << testing::gzip_member(first) << damaged;

  const Reading zlib = read_with(file, Inflater::zlib);
  const Reading isal = read_with(file, Inflater::isal);
  EXPECT_EQ(isal.ending, LogReader::Ending::damaged);
  EXPECT_EQ(isal.error, file.string() + ": read failed at byte " + std::to_string(first.size()) +
                            " (gzip: invalid deflate block)");
  EXPECT_EQ(isal.messages.size(), 10'000u) << "every message of the good member";
  EXPECT_EQ(zlib.ending, LogReader::Ending::damaged);
  EXPECT_NE(zlib.error.find("(gzip: invalid block type)"), std::string::npos) << zlib.error;
  // zlib drops what its last read inflated before the damage; ISA-L keeps it.
  EXPECT_LE(zlib.messages.size(), isal.messages.size());
  EXPECT_EQ(same_prefix(zlib.messages, isal.messages), zlib.messages.size());
}

// A byte changed in the middle of the deflate data: the data may still decode, to other bytes,
// until an invalid code, the CRC-32 of the trailer or a message header that makes no sense stops
// it. Both stop damaged, ISA-L having given at least what zlib gave, the same.
TEST_F(LogFileTest, ACorruptByteInTheDeflateDataIsDamagedWithBoth) {
  SKIP_WITHOUT_ISAL();
  std::string bytes = raw_bytes(write_vision_log(path("whole.log.gz"), 20'000));
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x5a);
  const fs::path file = path("corrupt.log.gz");
  std::ofstream(file, std::ios::binary) << bytes;
  const Reading zlib = read_with(file, Inflater::zlib);
  const Reading isal = read_with(file, Inflater::isal);
  EXPECT_EQ(zlib.ending, LogReader::Ending::damaged) << zlib.error;
  EXPECT_EQ(isal.ending, LogReader::Ending::damaged) << isal.error;
  EXPECT_LE(zlib.messages.size(), isal.messages.size());
  EXPECT_EQ(same_prefix(zlib.messages, isal.messages), zlib.messages.size());
}

TEST_F(LogFileTest, MissingFileNamesThePathAndTheCause) {
  const auto opened = LogReader::open(path("nope.log"));
  EXPECT_FALSE(opened);
  EXPECT_EQ(error_of(opened),
            path("nope.log").string() + ": cannot open: No such file or directory");
}

// ---------------------------------------------------------------------------------------------
// Reader mechanics

TEST_F(LogFileTest, NextReusesThePayloadStorageAndAMovedReaderCarriesOn) {
  const fs::path file = path("reuse.log");
  write_file(file, file_header() + message_bytes(1, 3, std::string(1000, 'a')) +
                       message_bytes(2, 3, std::string(500, 'b')) +
                       message_bytes(3, 3, std::string(700, 'c')));
  Result<LogReader> reader = LogReader::open(file);
  ASSERT_TRUE(reader);
  LogMessage message;
  ASSERT_TRUE(reader->next(message));
  const char* storage = message.payload.data();
  ASSERT_TRUE(reader->next(message));
  EXPECT_EQ(message.payload, std::string(500, 'b'));
  EXPECT_EQ(message.payload.data(), storage) << "no new allocation for a smaller payload";

  LogReader moved = std::move(*reader);
  ASSERT_TRUE(moved.next(message));
  EXPECT_EQ(message.payload, std::string(700, 'c'));
  EXPECT_EQ(message.payload.data(), storage);
  EXPECT_FALSE(moved.next(message));
  EXPECT_EQ(moved.error(), "");
  EXPECT_EQ(moved.counters().referee, 3u);
}

// ---------------------------------------------------------------------------------------------
// Writer failures

TEST_F(LogFileTest, WriterReportsUncreatableFiles) {
  const fs::path file = path("no/such/dir/x.log");
  const auto created = LogWriter::create(file);
  EXPECT_FALSE(created);
  EXPECT_EQ(error_of(created), file.string() + ": cannot create: No such file or directory");
}

TEST_F(LogFileTest, WriterRefusesWhatNoReaderWouldAccept) {
  const fs::path file = path("refuse.log");
  Result<LogWriter> writer = LogWriter::create(file);
  ASSERT_TRUE(writer);
  EXPECT_FALSE(writer->write(6, 0, "index"));
  EXPECT_NE(writer->error().find("close(true)"), std::string::npos) << writer->error();
  EXPECT_FALSE(writer->write(3, 0, std::string(16 * 1024 * 1024 + 1, 'x')));
  EXPECT_NE(writer->error().find("16777217 bytes at byte 16"), std::string::npos)
      << writer->error();
  SSL_WrapperPacket incomplete;
  incomplete.mutable_detection()->set_camera_id(1);
  EXPECT_FALSE(writer->write_vision(incomplete, 0));
  EXPECT_NE(writer->error().find("frame_number"), std::string::npos) << writer->error();
  // Refusals write nothing and leave the writer usable.
  EXPECT_TRUE(writer->write(3, 5, "ok"));
  EXPECT_TRUE(writer->close());
  EXPECT_FALSE(writer->write(3, 6, "late"));
  EXPECT_EQ(writer->error(), file.string() + ": already closed");
  EXPECT_FALSE(writer->close());

  Result<LogReader> reader = LogReader::open(file);
  ASSERT_TRUE(reader);
  LogMessage message;
  ASSERT_TRUE(reader->next(message));
  EXPECT_EQ(message.payload, "ok");
  EXPECT_FALSE(reader->next(message));
  EXPECT_EQ(reader->error(), "");
}

TEST_F(LogFileTest, WriterReportsAFullDisk) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  Result<LogWriter> writer = LogWriter::create("/dev/full");
  ASSERT_TRUE(writer);
  // Small writes sit in zlib's buffer, so the failure may show at write or at close.
  bool ok = true;
  for (int i = 0; i < 100 && ok; ++i) ok = writer->write(3, i, std::string(4096, 'x'));
  if (ok) ok = writer->close();
  EXPECT_FALSE(ok);
  EXPECT_NE(writer->error().find("/dev/full: cannot "), std::string::npos) << writer->error();
  EXPECT_NE(writer->error().find("No space left on device"), std::string::npos) << writer->error();
}

}  // namespace
}  // namespace ssl_formation
