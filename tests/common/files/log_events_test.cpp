// A log as the match's event stream (files/src/log_events.cpp), and RecordedMatch replay/split.

#include "ssl_formation/files/log_events.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "scratch_dir.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;

// An event as a sink saw it, copied.
struct Seen {
  MatchEventKind kind;
  double receive_s;
  bool has_frame;
  VisionFrame frame;
  std::string payload;
};

struct Collector : MatchEventSink {
  std::vector<Seen> events;
  int new_streams = 0;
  void on_event(const MatchEvent& e) override {
    events.push_back({e.kind, e.receive_s, e.frame != nullptr, e.frame ? *e.frame : VisionFrame{},
                      std::string(e.payload)});
  }
  void start_new_stream() override { ++new_streams; }
};

constexpr std::int64_t base_ns = 1'700'000'000'123'456'789;

SSL_WrapperPacket detection(std::uint32_t frame_number, double t_capture, double x) {
  DetectionFrameSpec spec;
  spec.frame_number = frame_number;
  spec.t_capture = t_capture;
  spec.yellow.push_back({3, {x, -250.0}});
  spec.blue.push_back({7, {-x, 250.0}});
  return make_detection_packet(spec);
}

// What the log holds, in order: (type, receive ns, payload).
struct Message {
  LogMessageType type;
  std::int64_t receive_ns;
  std::string payload;
};

std::vector<Message> messages() {
  const auto vision = [](const SSL_WrapperPacket& p) { return p.SerializeAsString(); };
  return {
      {LogMessageType::vision, base_ns, vision(make_geometry_packet(FieldSize{12000.0, 9000.0}))},
      {LogMessageType::referee, base_ns + 1'000'000, "referee-1"},
      {LogMessageType::vision, base_ns + 10'000'000, vision(detection(0, 50.0, 1000.0))},
      {LogMessageType::unknown, base_ns + 11'000'000, "not for us"},
      {LogMessageType::tracker, base_ns + 12'000'000, "tracker-1"},
      {LogMessageType::vision, base_ns + 26'000'000, vision(detection(1, 50.016, 1010.0))},
      {LogMessageType::blank, base_ns + 27'000'000, ""},
      {LogMessageType::vision, base_ns + 28'000'000, "\xff\xff not a packet"},
      {LogMessageType::referee, base_ns + 30'000'000, "referee-2"},
      {LogMessageType::vision, base_ns + 43'000'000, vision(detection(2, 50.033, 1020.0))},
      {LogMessageType::vision, base_ns + 60'000'000, vision(detection(3, 50.05, 1030.0))},
  };
}

// The messages the event stream keeps, in order (index into messages()).
const std::vector<std::size_t> kept{0, 1, 2, 4, 5, 8, 9, 10};

fs::path write_log(const fs::path& dir) {
  const fs::path path = dir / "match.log";
  auto writer = LogWriter::create(path);
  EXPECT_TRUE(writer.has_value());
  for (const Message& m : messages()) {
    EXPECT_TRUE(writer->write(static_cast<std::int32_t>(m.type), m.receive_ns, m.payload))
        << writer->error();
  }
  EXPECT_TRUE(writer->close()) << writer->error();
  return path;
}

// Checks `events` against the first `count` kept messages of the log.
void expect_events(const std::vector<Seen>& events, std::size_t count) {
  const std::vector<Message> all = messages();
  ASSERT_EQ(events.size(), count);
  double x = 1000.0;
  std::uint32_t frame_number = 0;
  for (std::size_t i = 0; i < count; ++i) {
    SCOPED_TRACE(i);
    const Message& m = all[kept[i]];
    const Seen& e = events[i];
    EXPECT_DOUBLE_EQ(e.receive_s, static_cast<double>(m.receive_ns) * 1e-9);
    switch (m.type) {
      case LogMessageType::vision:
        ASSERT_EQ(e.kind, MatchEventKind::vision);
        ASSERT_TRUE(e.has_frame);
        if (i == 0) {
          EXPECT_TRUE(e.frame.has_geometry);
          EXPECT_FALSE(e.frame.has_detection);
          EXPECT_EQ(e.frame.field_length, 12000);
          EXPECT_EQ(e.frame.field_width, 9000);
          break;
        }
        ASSERT_TRUE(e.frame.has_detection);
        EXPECT_EQ(e.frame.detection.frame_number, frame_number++);
        ASSERT_EQ(e.frame.detection.robots_yellow.size(), 1u);
        ASSERT_EQ(e.frame.detection.robots_blue.size(), 1u);
        EXPECT_EQ(e.frame.detection.robots_yellow[0].robot_id, 3u);
        EXPECT_FLOAT_EQ(e.frame.detection.robots_yellow[0].x, static_cast<float>(x));
        EXPECT_FLOAT_EQ(e.frame.detection.robots_blue[0].x, static_cast<float>(-x));
        x += 10.0;
        break;
      case LogMessageType::referee:
        EXPECT_EQ(e.kind, MatchEventKind::referee);
        EXPECT_FALSE(e.has_frame);
        EXPECT_EQ(e.payload, m.payload);
        break;
      case LogMessageType::tracker:
        EXPECT_EQ(e.kind, MatchEventKind::tracked_vision);
        EXPECT_FALSE(e.has_frame);
        EXPECT_EQ(e.payload, m.payload);
        break;
      default:
        ADD_FAILURE() << "message " << kept[i] << " is no event";
    }
  }
}

TEST(LogEvents, YieldVisionRefereeAndTrackerMessagesInFileOrder) {
  testing::ScratchDir dir;
  const fs::path path = write_log(dir.path());
  auto reader = LogReader::open(path);
  ASSERT_TRUE(reader.has_value()) << reader.error().message;
  LogEvents events(*reader);
  Collector collector;
  MatchEvent event;
  while (events.next(event)) collector.on_event(event);
  expect_events(collector.events, kept.size());
  EXPECT_EQ(events.vision_events(), 5u);
  EXPECT_EQ(reader->error(), "");
  EXPECT_EQ(reader->counters().parse_errors, 1u);  // the undecodable vision payload
  EXPECT_EQ(reader->counters().unknown, 1u);
  EXPECT_EQ(reader->counters().blank, 1u);
  EXPECT_FALSE(events.next(event));  // and stays at the end
}

TEST(LogEvents, ReplayHandsEveryEventToTheSinkAndReportsProgressAtTheEnd) {
  testing::ScratchDir dir;
  auto reader = LogReader::open(write_log(dir.path()));
  ASSERT_TRUE(reader.has_value());
  Collector collector;
  std::vector<std::uint64_t> progress;
  const std::uint64_t vision =
      replay_log(*reader, collector, [&](std::uint64_t n) { progress.push_back(n); });
  EXPECT_EQ(vision, 5u);
  expect_events(collector.events, kept.size());
  EXPECT_EQ(progress, (std::vector<std::uint64_t>{5}));
  EXPECT_EQ(collector.new_streams, 0);  // the caller says where a stream begins
}

TEST(LogEvents, ARecordedLogKeepsEveryEvent) {
  testing::ScratchDir dir;
  const Result<RecordedLog> log = read_recorded_log(write_log(dir.path()));
  ASSERT_TRUE(log.has_value()) << log.error().message;
  EXPECT_FALSE(log->stopped_early.has_value());
  EXPECT_EQ(log->ending, LogReader::Ending::none);
  EXPECT_EQ(log->match.size(), kept.size());
  EXPECT_EQ(log->match.vision_events(), 5u);
  EXPECT_TRUE(log->match.has_referee());
  EXPECT_EQ(log->counters.messages, messages().size());
  EXPECT_EQ(log->counters.referee, 2u);
  EXPECT_EQ(log->counters.tracker, 1u);
  Collector collector;
  log->match.replay(collector);
  expect_events(collector.events, kept.size());
  // Replayed again, the same events.
  Collector again;
  log->match.replay(again);
  expect_events(again.events, kept.size());
}

TEST(LogEvents, AFileCutInItsLastMessageKeepsEverythingBefore) {
  testing::ScratchDir dir;
  const fs::path whole = write_log(dir.path());
  std::string bytes;
  {
    std::ifstream in(whole, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const fs::path cut = dir.path() / "cut.log";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() - 5);
  const Result<RecordedLog> log = read_recorded_log(cut);
  ASSERT_TRUE(log.has_value()) << log.error().message;
  ASSERT_TRUE(log->stopped_early.has_value());
  EXPECT_NE(log->stopped_early->message.find("truncated message"), std::string::npos)
      << log->stopped_early->message;
  EXPECT_EQ(log->ending, LogReader::Ending::cut_off);
  EXPECT_EQ(log->match.vision_events(), 4u);
  Collector collector;
  log->match.replay(collector);
  expect_events(collector.events, kept.size() - 1);
}

TEST(LogEvents, AFileThatIsNoLogIsAnError) {
  testing::ScratchDir dir;
  const fs::path path = dir.path() / "not.log";
  std::ofstream(path, std::ios::binary) << "NOT_A_LOG_FILE_AT_ALL";
  EXPECT_FALSE(read_recorded_log(path).has_value());
  EXPECT_FALSE(read_recorded_log(dir.path() / "missing.log").has_value());
}

// A match built by hand: vision frames numbered 0.., and referee messages between them.
RecordedMatch hand_built(const std::string& script) {
  RecordedMatch match;
  std::uint32_t frame = 0;
  double t = 10.0;
  for (const char c : script) {
    t += 0.01;
    if (c == 'V') {
      match.add_vision(detection(frame, t, 100.0 * frame), t);
      ++frame;
    } else {
      match.add_referee("referee at " + std::to_string(t), t);
    }
  }
  return match;
}

TEST(RecordedMatch, SplitPutsTheFirstPartOfTheVisionInTheHeadAndTheRestInTheTail) {
  const RecordedMatch match = hand_built("RVRVVRVV");
  ASSERT_EQ(match.vision_events(), 5u);
  Collector all;
  match.replay(all);
  ASSERT_EQ(all.events.size(), 8u);

  const auto [head, tail] = match.split(0.5);  // floor(2.5) = 2 vision packets
  EXPECT_EQ(head.vision_events(), 2u);
  EXPECT_EQ(tail.vision_events(), 3u);
  EXPECT_EQ(head.size(), 4u);  // R V R V
  EXPECT_EQ(tail.size(), 4u);  // V R V V
  EXPECT_TRUE(head.has_referee());
  EXPECT_TRUE(tail.has_referee());
  Collector h;
  head.replay(h);
  Collector t;
  tail.replay(t);
  ASSERT_EQ(h.events.size() + t.events.size(), all.events.size());
  for (std::size_t i = 0; i < all.events.size(); ++i) {
    SCOPED_TRACE(i);
    const Seen& e = i < h.events.size() ? h.events[i] : t.events[i - h.events.size()];
    EXPECT_EQ(e.kind, all.events[i].kind);
    EXPECT_DOUBLE_EQ(e.receive_s, all.events[i].receive_s);
    EXPECT_EQ(e.payload, all.events[i].payload);
    EXPECT_EQ(e.has_frame, all.events[i].has_frame);
    if (e.has_frame) {
      EXPECT_EQ(e.frame.detection.frame_number, all.events[i].frame.detection.frame_number);
    }
  }
  EXPECT_EQ(t.events.front().frame.detection.frame_number, 2u);

  const auto [everything, nothing] = match.split(1.0);
  EXPECT_EQ(everything.size(), 8u);
  EXPECT_TRUE(nothing.empty());
  const auto [none, whole] = match.split(0.0);
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(whole.size(), 8u);
}

}  // namespace
}  // namespace ssl_formation
