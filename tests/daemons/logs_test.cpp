// End-to-end tests of the log tools: ssl-producer --write-log and --replay, and ssl-record, as
// real processes with real files and real multicast sockets on 127.0.0.1 (each test on its own
// group and port). Every test ends by itself within a few seconds.

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <cmath>
#include <fstream>
#include <mutex>
#include <thread>

#include "child_process.hpp"
#include "match_logs.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_vision_wrapper_tracked.pb.h"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using testing::ChildProcess;
using testing::new_group;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path record_program = SSLF_RECORD_PATH;

// Every datagram sent to a group, with its arrival time, collected on a thread of its own.
class Listener {
 public:
  struct Datagram {
    Clock::time_point at;
    std::string bytes;
  };

  explicit Listener(const std::string& group)
      : group_(group), receiver_(io_, net::parse_multicast_endpoint(group).value()) {
    receiver_.start([this](std::span<const std::byte> data, const net::udp::endpoint&) {
      const auto at = Clock::now();
      std::string bytes(reinterpret_cast<const char*>(data.data()), data.size());
      std::lock_guard lock(mutex_);
      if (bytes == testing::end_marker) {
        ++markers_;
      } else {
        datagrams_.push_back({at, std::move(bytes)});
      }
    });
    thread_ = std::thread([this] { io_.run_for(30s); });
  }
  ~Listener() {
    io_.stop();
    thread_.join();
  }
  // Waits until `n` datagrams arrived (or the time-out); then, the sender having stopped, sends
  // an end marker and waits for it, so that any datagram beyond the `n` has arrived too.
  std::vector<Datagram> wait_for(std::size_t n, std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline && count() < n) std::this_thread::sleep_for(5ms);
    std::size_t markers = 0;
    {
      std::lock_guard lock(mutex_);
      markers = markers_;
    }
    EXPECT_TRUE(testing::send_to_group(group_, testing::end_marker));
    const auto marker_deadline = Clock::now() + 5s;
    while (Clock::now() < marker_deadline) {
      {
        std::lock_guard lock(mutex_);
        if (markers_ > markers) return datagrams_;
      }
      std::this_thread::sleep_for(2ms);
    }
    ADD_FAILURE() << "the end marker sent to " << group_ << " did not come back";
    std::lock_guard lock(mutex_);
    return datagrams_;
  }
  std::size_t count() {
    std::lock_guard lock(mutex_);
    return datagrams_.size();
  }

 private:
  const std::string group_;
  boost::asio::io_context io_;
  net::MulticastReceiver receiver_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<Datagram> datagrams_;
  std::size_t markers_ = 0;
};

SSL_WrapperPacket detection_packet(std::uint32_t frame_number, double t_capture) {
  SSL_WrapperPacket packet;
  SSL_DetectionFrame& frame = *packet.mutable_detection();
  frame.set_frame_number(frame_number);
  frame.set_t_capture(t_capture);
  frame.set_t_sent(t_capture + 0.004);
  frame.set_camera_id(0);
  SSL_DetectionRobot& robot = *frame.add_robots_yellow();
  robot.set_confidence(1.0f);
  robot.set_robot_id(frame_number % 6);
  robot.set_x(100.0f * static_cast<float>(frame_number % 40) - 2000.0f);
  robot.set_y(0.0f);
  robot.set_pixel_x(0.0f);
  robot.set_pixel_y(0.0f);
  return packet;
}

// A log of `n` detection packets, t_capture 0.05 s apart, frame numbers 0..n-1, with receive time
// receive_time(i). Returns the offset of each message header.
std::vector<std::uint64_t> write_paced_log(const std::filesystem::path& path, int n,
                                           const std::function<std::int64_t(int)>& receive_time) {
  auto writer = LogWriter::create(path);
  EXPECT_TRUE(writer) << writer.error().message;
  std::vector<std::uint64_t> offsets;
  for (int i = 0; i < n; ++i) {
    offsets.push_back(writer->offset());
    EXPECT_TRUE(writer->write_vision(
        detection_packet(static_cast<std::uint32_t>(i), 1000.0 + 0.05 * i), receive_time(i)))
        << writer->error();
  }
  EXPECT_TRUE(writer->close()) << writer->error();
  return offsets;
}

std::int64_t unix_ns_paced(int i) {
  return 1'700'000'000'000'000'000 + std::int64_t{i} * 50'000'000;
}

std::vector<std::uint32_t> frame_numbers(const std::vector<Listener::Datagram>& datagrams) {
  std::vector<std::uint32_t> out;
  for (const auto& d : datagrams) {
    SSL_WrapperPacket packet;
    EXPECT_TRUE(packet.ParseFromString(d.bytes));
    out.push_back(packet.detection().frame_number());
  }
  return out;
}

double span_s(const std::vector<Listener::Datagram>& datagrams) {
  if (datagrams.size() < 2) return 0.0;
  return std::chrono::duration<double>(datagrams.back().at - datagrams.front().at).count();
}

double median_gap_s(const std::vector<Listener::Datagram>& datagrams) {
  std::vector<double> gaps;
  for (std::size_t i = 1; i < datagrams.size(); ++i) {
    gaps.push_back(std::chrono::duration<double>(datagrams[i].at - datagrams[i - 1].at).count());
  }
  if (gaps.empty()) return 0.0;
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  return gaps[gaps.size() / 2];
}

testing::RunResult replay(const TempDir& dir, const std::filesystem::path& log,
                          const std::string& group, std::vector<std::string> extra,
                          const std::string& name = "replay") {
  std::vector<std::string> args{"--replay", log.string(),        "--vision-address",
                                group,      "--status-interval", "0.1"};
  args.insert(args.end(), extra.begin(), extra.end());
  return testing::run_to_end(producer_program, args, dir.path(), name, 20s);
}

// --------------------------------------------------------------------------------------------
// --write-log

TEST(Logs, WriteLogHoldsExactlyTheSimulatedStream) {
  TempDir dir;
  for (const std::string name : {"feed.log", "feed.log.gz"}) {
    SCOPED_TRACE(name);
    const auto path = dir / name;
    const auto result = testing::run_to_end(
        producer_program,
        {"--simulation", "paper", "--referee",    "off", "--write-log",      path.string(),
         "--count",      "80",    "--seed",       "7",   "--cameras",        "3",
         "--jitter-mm",  "12",    "--drop-rate",  "0.1", "--opponent-color", "blue",
         "--step",       "0.5",   "--start-time", "100"},
        dir.path(), "write-log", 20s);
    ASSERT_EQ(result.exit_code, 0) << result.err;

    simulation::SimulationConfig config;
    config.seed = 7;
    config.cameras = 3;
    config.jitter_mm = 12.0;
    config.drop_rate = 0.1;
    config.opponent_color = TeamColor::blue;
    config.step_s = 0.5;
    config.start_time_s = 100.0;
    simulation::SimulatedVision vision(config);
    std::vector<std::pair<std::int64_t, std::string>> expected;
    for (int i = 0; i < 80; ++i) {
      const auto formation = vision.next();
      for (const auto& packet : formation.packets) {
        expected.emplace_back(std::llround(formation.t_capture * 1e9), packet.SerializeAsString());
      }
    }

    auto reader = LogReader::open(path);
    ASSERT_TRUE(reader) << reader.error().message;
    LogMessage message;
    std::size_t i = 0;
    while (reader->next(message)) {
      ASSERT_LT(i, expected.size());
      EXPECT_EQ(message.type, static_cast<std::int32_t>(LogMessageType::vision));
      EXPECT_EQ(message.receive_time_ns, expected[i].first) << "message " << i;
      ASSERT_EQ(message.payload, expected[i].second) << "message " << i;
      ++i;
    }
    EXPECT_EQ(reader->error(), "");
    EXPECT_EQ(i, expected.size());
    EXPECT_GT(expected.size(), 200u);  // 80 x 3 cameras minus drops, plus geometry

    std::ifstream file(path, std::ios::binary);
    char magic[2] = {};
    file.read(magic, 2);
    const bool gzip = magic[0] == '\x1f' && magic[1] == '\x8b';
    EXPECT_EQ(gzip, name.ends_with(".gz"));
  }
}

TEST(Logs, WriteLogNeedsACountAndRefusesReplayToo) {
  TempDir dir;
  const auto no_count = testing::run_to_end(
      producer_program, {"--simulation", "paper", "--write-log", (dir / "a.log").string()},
      dir.path(), "no-count", 5s);
  EXPECT_EQ(no_count.exit_code, 2) << no_count.err;
  const auto both = testing::run_to_end(
      producer_program,
      {"--write-log", (dir / "a.log").string(), "--replay", (dir / "b.log").string()}, dir.path(),
      "both", 5s);
  EXPECT_EQ(both.exit_code, 2) << both.err;
  const auto unwritable =
      testing::run_to_end(producer_program,
                          {"--simulation", "paper", "--write-log",
                           (dir / "no-such-dir" / "a.log").string(), "--count", "3"},
                          dir.path(), "unwritable", 5s);
  EXPECT_EQ(unwritable.exit_code, 1);
  EXPECT_NE(unwritable.err.find("no-such-dir"), std::string::npos) << unwritable.err;
}

// --------------------------------------------------------------------------------------------
// --replay

TEST(Logs, ReplaySendsExactlyTheFilesPackets) {
  TempDir dir;
  const auto path = dir / "feed.log.gz";
  ASSERT_EQ(testing::run_to_end(producer_program,
                                {"--simulation", "paper", "--referee", "off", "--write-log",
                                 path.string(), "--count", "40", "--seed", "5", "--cameras", "2"},
                                dir.path(), "write-log", 20s)
                .exit_code,
            0);
  const LogVisionPackets file = read_vision_log(path).value();
  ASSERT_FALSE(file.stopped_early) << file.stopped_early->message;
  const std::string group = new_group();
  Listener listener(group);
  const auto result = replay(dir, path, group, {"--speed", "0"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto received = listener.wait_for(file.packets.size(), 5s);
  ASSERT_EQ(received.size(), file.packets.size());
  for (std::size_t i = 0; i < received.size(); ++i) {
    ASSERT_EQ(received[i].bytes, file.packets[i].SerializeAsString()) << "packet " << i;
  }
  EXPECT_EQ(testing::last_status(result.err, "done:").at("sent"), file.packets.size())
      << result.err;
}

TEST(Logs, ReplaySendsLegacyVisionAndCountsWhatItSkips) {
  TempDir dir;
  const auto path = dir / "mixed.log";
  {
    auto writer = LogWriter::create(path);
    ASSERT_TRUE(writer) << writer.error().message;
    const auto vision = static_cast<std::int32_t>(LogMessageType::vision);
    const auto legacy = static_cast<std::int32_t>(LogMessageType::legacy_vision);
    ASSERT_TRUE(writer->write(static_cast<std::int32_t>(LogMessageType::referee), unix_ns_paced(0),
                              "referee"));
    ASSERT_TRUE(
        writer->write(vision, unix_ns_paced(0), detection_packet(0, 1000.0).SerializeAsString()));
    ASSERT_TRUE(
        writer->write(legacy, unix_ns_paced(1), detection_packet(1, 1000.05).SerializeAsString()));
    ASSERT_TRUE(writer->write(static_cast<std::int32_t>(LogMessageType::tracker), unix_ns_paced(1),
                              "tracker"));
    // A 2010 packet with geometry only (field 2, empty): nothing usable today.
    ASSERT_TRUE(writer->write(legacy, unix_ns_paced(2), std::string("\x12\x00", 2)));
    ASSERT_TRUE(writer->write(vision, unix_ns_paced(2), "\xff\xff not protobuf"));
    ASSERT_TRUE(writer->write(static_cast<std::int32_t>(LogMessageType::referee), unix_ns_paced(2),
                              "referee"));
    ASSERT_TRUE(
        writer->write(vision, unix_ns_paced(3), detection_packet(3, 1000.15).SerializeAsString()));
    ASSERT_TRUE(writer->close(/*indexed=*/true)) << writer->error();
  }
  const std::string group = new_group();
  const std::string referee_group = new_group();
  const std::string tracker_group = new_group();
  Listener listener(group);
  Listener referee_listener(referee_group);
  Listener tracker_listener(tracker_group);
  const auto result = replay(
      dir, path, group,
      {"--speed", "0", "--referee-address", referee_group, "--tracker-address", tracker_group});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto received = listener.wait_for(3, 5s);
  EXPECT_EQ(frame_numbers(received), (std::vector<std::uint32_t>{0, 1, 3}));
  const testing::Status done = testing::last_status(result.err, "done:");
  EXPECT_EQ(done.at("sent"), 3u) << result.err;
  // The referee messages and tracked vision go to their own groups as they are, the first
  // referee message (before any vision) too; the rest is skipped and counted.
  EXPECT_EQ(referee_listener.wait_for(2, 5s).size(), 2u);
  EXPECT_EQ(tracker_listener.wait_for(1, 5s).size(), 1u);
  EXPECT_EQ(done.at("referee_sent"), 2u) << result.err;
  EXPECT_EQ(done.at("referee_unsent"), 0u) << result.err;
  EXPECT_EQ(done.at("tracker_sent"), 1u) << result.err;
  EXPECT_EQ(done.at("tracker_unsent"), 0u) << result.err;
  EXPECT_EQ(done.at("blank"), 0u) << result.err;
  EXPECT_EQ(done.at("unknown"), 0u) << result.err;
  EXPECT_EQ(done.at("legacy_vision_unusable"), 1u) << result.err;
  EXPECT_EQ(done.at("undecodable"), 1u) << result.err;
}

TEST(Logs, ReplayKeepsTheRecordedPaceAndScalesItWithSpeed) {
  TempDir dir;
  const auto path = dir / "paced.log";
  write_paced_log(path, 21, unix_ns_paced);  // 20 gaps of 50 ms: 1 s
  {
    const std::string group = new_group();
    Listener listener(group);
    const auto result = replay(dir, path, group, {"--speed", "1"}, "speed-1");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const auto received = listener.wait_for(21, 5s);
    ASSERT_EQ(received.size(), 21u);
    EXPECT_NEAR(span_s(received), 1.0, 0.15);
    EXPECT_NEAR(median_gap_s(received), 0.05, 0.015);
    EXPECT_NE(result.err.find("nanoseconds"), std::string::npos) << result.err;
  }
  {
    const std::string group = new_group();
    Listener listener(group);
    const auto result = replay(dir, path, group, {"--speed", "10"}, "speed-10");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const auto received = listener.wait_for(21, 5s);
    ASSERT_EQ(received.size(), 21u);
    EXPECT_GT(span_s(received), 0.08);
    EXPECT_LT(span_s(received), 0.25);
    EXPECT_NEAR(median_gap_s(received), 0.005, 0.004);
  }
}

TEST(Logs, MicrosecondReceiveTimesReplayAtTheRightPace) {
  TempDir dir;
  const auto path = dir / "old-recorder.log";
  // Unix time in microseconds, as older recorders wrote it: 50,000 per 0.05 s of t_capture.
  write_paced_log(path, 21, [](int i) { return 1'700'000'000'000'000 + std::int64_t{i} * 50'000; });
  const std::string group = new_group();
  Listener listener(group);
  const auto result = replay(dir, path, group, {"--speed", "1"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto received = listener.wait_for(21, 5s);
  ASSERT_EQ(received.size(), 21u);
  EXPECT_NEAR(span_s(received), 1.0, 0.15);  // taken as ns it would last 1 ms
  EXPECT_NE(result.err.find("microseconds"), std::string::npos) << result.err;
}

TEST(Logs, ZeroReceiveTimesReplayOnTheFramesClock) {
  TempDir dir;
  const auto path = dir / "zeros.log";
  write_paced_log(path, 21, [](int) { return std::int64_t{0}; });
  const std::string group = new_group();
  Listener listener(group);
  const auto result = replay(dir, path, group, {"--speed", "2"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto received = listener.wait_for(21, 5s);
  ASSERT_EQ(received.size(), 21u);
  EXPECT_NEAR(span_s(received), 0.5, 0.1);
  EXPECT_NE(result.err.find("t_capture"), std::string::npos) << result.err;
}

TEST(Logs, ReplayStartAndEndSelectTheirPackets) {
  TempDir dir;
  const auto path = dir / "window.log";
  write_paced_log(path, 40, unix_ns_paced);
  const std::string group = new_group();
  Listener listener(group);
  const auto result =
      replay(dir, path, group, {"--speed", "0", "--start", "0.475", "--end", "1.025"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto received = listener.wait_for(11, 5s);
  std::vector<std::uint32_t> expected;
  for (std::uint32_t i = 10; i <= 20; ++i) expected.push_back(i);
  EXPECT_EQ(frame_numbers(received), expected);

  // At the recorded pace the window lasts its own length, starting at once.
  const std::string paced_group = new_group();
  Listener paced(paced_group);
  const auto started = Clock::now();
  const auto paced_result =
      replay(dir, path, paced_group, {"--speed", "1", "--start", "1.0", "--end", "1.5"}, "paced");
  ASSERT_EQ(paced_result.exit_code, 0) << paced_result.err;
  const auto paced_received = paced.wait_for(11, 5s);
  ASSERT_EQ(paced_received.size(), 11u);
  EXPECT_EQ(frame_numbers(paced_received).front(), 20u);
  EXPECT_NEAR(span_s(paced_received), 0.5, 0.1);
  EXPECT_LT(paced_received.front().at - started, 800ms);  // no waiting for the skipped second
}

TEST(Logs, ReplayLoopsUntilTheCount) {
  TempDir dir;
  const auto path = dir / "loop.log";
  write_paced_log(path, 20, unix_ns_paced);
  const std::string group = new_group();
  Listener listener(group);
  const auto result = replay(dir, path, group, {"--speed", "0", "--loop", "--count", "50"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto received = listener.wait_for(50, 5s);
  std::vector<std::uint32_t> expected;
  for (int i = 0; i < 50; ++i) expected.push_back(static_cast<std::uint32_t>(i % 20));
  EXPECT_EQ(frame_numbers(received), expected);
  EXPECT_EQ(testing::last_status(result.err, "done:").at("passes"), 3u) << result.err;

  // Paced, the second pass follows the first at once and keeps the pace.
  const std::string paced_group = new_group();
  Listener paced(paced_group);
  const auto paced_result =
      replay(dir, path, paced_group, {"--speed", "4", "--loop", "--count", "30"}, "paced");
  ASSERT_EQ(paced_result.exit_code, 0) << paced_result.err;
  const auto paced_received = paced.wait_for(30, 5s);
  ASSERT_EQ(paced_received.size(), 30u);
  EXPECT_NEAR(span_s(paced_received), 28 * 0.05 / 4, 0.1);
}

TEST(Logs, ReplayStopsOnASignal) {
  TempDir dir;
  const auto path = dir / "loop.log";
  write_paced_log(path, 20, unix_ns_paced);
  const std::string group = new_group();
  Listener listener(group);
  ChildProcess producer(producer_program,
                        {"--replay", path.string(), "--vision-address", group, "--loop"},
                        dir.path(), "replay", Readiness::ready_file);
  ASSERT_TRUE(producer.wait_until_ready(10s)) << producer.stderr_text();
  EXPECT_EQ(producer.ready_fact("mode"), "replay");
  // Stopped mid-replay: once its packets arrive.
  const auto deadline = Clock::now() + 10s;
  while (listener.count() < 3 && Clock::now() < deadline) std::this_thread::sleep_for(5ms);
  ASSERT_GE(listener.count(), 3u) << producer.stderr_text();
  producer.signal(SIGINT);
  EXPECT_EQ(producer.wait(1s), 0);
  EXPECT_NE(producer.stderr_text().find("stopped: "), std::string::npos) << producer.stderr_text();
}

TEST(Logs, TruncatedLogReplaysWhatPrecedesTheDamageAndFails) {
  TempDir dir;
  const auto path = dir / "cut.log";
  const auto offsets = write_paced_log(path, 30, unix_ns_paced);
  std::filesystem::resize_file(path,
                               std::filesystem::file_size(path) - 10);  // into the last message
  const std::string group = new_group();
  Listener listener(group);
  const auto result = replay(dir, path, group, {"--speed", "0"});
  EXPECT_EQ(result.exit_code, 1) << result.err;
  const auto received = listener.wait_for(29, 5s);
  std::vector<std::uint32_t> expected;
  for (std::uint32_t i = 0; i < 29; ++i) expected.push_back(i);
  EXPECT_EQ(frame_numbers(received), expected);
  EXPECT_NE(result.err.find("at byte " + std::to_string(offsets.back())), std::string::npos)
      << result.err;
}

TEST(Logs, ReplayOfAMissingOrForeignFileFails) {
  TempDir dir;
  const auto missing = replay(dir, dir / "missing.log", new_group(), {});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("missing.log"), std::string::npos) << missing.err;
  { std::ofstream(dir / "foreign.log") << "not a log at all"; }
  const auto foreign = replay(dir, dir / "foreign.log", new_group(), {});
  EXPECT_EQ(foreign.exit_code, 1);
  EXPECT_NE(foreign.err.find("not an SSL log file"), std::string::npos) << foreign.err;
  const auto bad_speed = replay(dir, dir / "foreign.log", new_group(), {"--speed", "-1"});
  EXPECT_EQ(bad_speed.exit_code, 2) << bad_speed.err;
}

// --------------------------------------------------------------------------------------------
// ssl-record

std::vector<FormationSample> sample_all(const std::vector<SSL_WrapperPacket>& packets) {
  std::vector<FormationSample> samples;
  FormationSampler sampler(SamplerConfig{},
                           [&](const FormationSample& s) { samples.push_back(s); });
  for (const auto& packet : packets) sampler.add(packet);
  return samples;
}

TEST(Logs, RecordingOfTheLiveProducerSamplesLikeTheLibrary) {
  TempDir dir;
  const std::string group = new_group();
  const auto path = dir / "match.log.gz";
  std::vector<SSL_WrapperPacket> expected;
  simulation::SimulatedVision vision(simulation::SimulationConfig{.seed = 3});
  for (int i = 0; i < 100; ++i) {
    for (auto& packet : vision.next().packets) expected.push_back(std::move(packet));
  }

  const auto before_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  ChildProcess recorder(
      record_program,
      {"--vision-address", group, "--output", path.string(), "--status-interval", "0.05"},
      dir.path(), "record", Readiness::ready_file);
  ASSERT_TRUE(recorder.wait_until_ready(10s)) << recorder.stderr_text();
  EXPECT_EQ(recorder.ready_fact("output"), path.string());
  const auto produced = testing::run_to_end(
      producer_program,
      {"--simulation", "paper", "--referee", "off", "--vision-address", group, "--period", "0.002",
       "--count", "100", "--seed", "3", "--cameras", "1", "--status-interval", "100"},
      dir.path(), "producer", 20s);
  ASSERT_EQ(produced.exit_code, 0) << produced.err;
  ASSERT_TRUE(testing::wait_for_status(recorder, "recorded", expected.size(), 10s))
      << recorder.stderr_text();
  recorder.signal(SIGINT);
  const auto code = recorder.wait(2s);
  ASSERT_TRUE(code.has_value()) << recorder.stderr_text();
  EXPECT_EQ(*code, 0) << recorder.stderr_text();
  const auto after_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::system_clock::now().time_since_epoch())
                            .count();

  const LogVisionPackets recorded = read_vision_log(path).value();
  ASSERT_FALSE(recorded.stopped_early)
      << recorded.stopped_early->message;  // complete: the gzip stream was closed properly
  EXPECT_EQ(recorded.counters.messages, expected.size());
  ASSERT_EQ(recorded.packets.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(recorded.packets[i].SerializeAsString(), expected[i].SerializeAsString())
        << "packet " << i;
    EXPECT_GE(recorded.receive_times_ns[i], before_ns);
    EXPECT_LE(recorded.receive_times_ns[i], after_ns);
    if (i > 0) {
      EXPECT_GE(recorded.receive_times_ns[i], recorded.receive_times_ns[i - 1]);
    }
  }

  const auto got = sample_all(recorded.packets);
  const auto want = sample_all(expected);
  ASSERT_EQ(got.size(), want.size());
  ASSERT_GE(want.size(), 99u);
  for (std::size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE("sample " + std::to_string(i));
    const Formation& a = got[i].formation;
    const Formation& b = want[i].formation;
    EXPECT_EQ(a.time_s, b.time_s);
    EXPECT_EQ(a.frame_number, b.frame_number);
    EXPECT_EQ(a.centroid_cell, b.centroid_cell);
    EXPECT_EQ(a.continues_previous, b.continues_previous);
    ASSERT_EQ(a.robots.size(), b.robots.size());
    for (std::size_t r = 0; r < b.robots.size(); ++r) {
      EXPECT_EQ(a.robots[r].robot_id, b.robots[r].robot_id);
      EXPECT_EQ(a.robots[r].cell, b.robots[r].cell);
      EXPECT_EQ(a.robots[r].previous_cell, b.robots[r].previous_cell);
      EXPECT_EQ(a.robots[r].state, b.robots[r].state);
    }
    EXPECT_EQ(got[i].transitions, want[i].transitions);
  }

  // And the recording replays into the same stream.
  const std::string replay_group = new_group();
  Listener listener(replay_group);
  const auto replayed = replay(dir, path, replay_group, {"--speed", "0"});
  ASSERT_EQ(replayed.exit_code, 0) << replayed.err;
  EXPECT_NE(replayed.err.find("Unix time in nanoseconds"), std::string::npos) << replayed.err;
  const auto received = listener.wait_for(expected.size(), 5s);
  ASSERT_EQ(received.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(received[i].bytes, expected[i].SerializeAsString()) << "packet " << i;
  }
}

TEST(Logs, RecordCountsButSkipsDatagramsThatAreNotVisionAndStopsAtItsCount) {
  TempDir dir;
  const std::string group = new_group();
  const auto path = dir / "count.log";
  ChildProcess recorder(record_program,
                        {"--vision-address", group, "--output", path.string(), "--count", "5",
                         "--index", "--status-interval", "0.05"},
                        dir.path(), "record", Readiness::ready_file);
  ASSERT_TRUE(recorder.wait_until_ready(10s)) << recorder.stderr_text();
  boost::asio::io_context io;
  net::MulticastSender sender(io, net::parse_multicast_endpoint(group).value());
  sender.open();
  const std::string garbage = "\xff\xff\xff garbage";
  ASSERT_TRUE(sender.send(std::as_bytes(std::span(garbage))));
  for (std::uint32_t i = 0; i < 8; ++i) {
    const std::string bytes = detection_packet(i, 10.0 + 0.1 * i).SerializeAsString();
    sender.send(std::as_bytes(std::span(bytes)));
    std::this_thread::sleep_for(2ms);  // the sender's pace, not a wait for anything
  }
  const auto code = recorder.wait(3s);
  ASSERT_TRUE(code.has_value()) << recorder.stderr_text();
  EXPECT_EQ(*code, 0) << recorder.stderr_text();
  const testing::Status done = testing::last_status(recorder.stderr_text(), "done:");
  ASSERT_TRUE(done.contains("recorded") && done.contains("skipped")) << recorder.stderr_text();
  EXPECT_EQ(done.at("recorded"), 5u) << recorder.stderr_text();
  EXPECT_EQ(done.at("skipped"), 1u) << recorder.stderr_text();
  const LogVisionPackets recorded = read_vision_log(path).value();
  EXPECT_FALSE(recorded.stopped_early) << recorded.stopped_early->message;
  EXPECT_EQ(recorded.counters.index, 1u);  // --index
  ASSERT_EQ(recorded.packets.size(), 5u);
  for (std::uint32_t i = 0; i < 5; ++i)
    EXPECT_EQ(recorded.packets[i].detection().frame_number(), i);
}

TEST(Logs, RecordKeepsTheRefereeMessagesInPlaceAndReplaySendsThemToTheirGroup) {
  TempDir dir;
  const std::string vision = new_group();
  const std::string referee = new_group();
  const std::string tracker = new_group();
  const auto path = dir / "match.log";
  ChildProcess recorder(
      record_program,
      {"--vision-address", vision, "--referee-address", referee, "--tracker-address", tracker,
       "--output", path.string(), "--count", "4", "--status-interval", "0.05"},
      dir.path(), "record", Readiness::ready_file);
  ASSERT_TRUE(recorder.wait_until_ready(10s)) << recorder.stderr_text();
  EXPECT_EQ(recorder.ready_fact("referee"), referee);
  testing::RefereeSpec spec;
  spec.command = Referee::STOP;
  const std::string stop = testing::referee_payload(spec);
  spec.command = Referee::NORMAL_START;
  spec.command_counter = 2;
  const std::string start = testing::referee_payload(spec);
  // Two sockets: a pause after each datagram keeps the order they reach the recorder in.
  const auto send = [](const std::string& group, const std::string& bytes) {
    ASSERT_TRUE(testing::send_to_group(group, bytes));
    std::this_thread::sleep_for(150ms);
  };
  send(vision, detection_packet(0, 10.0).SerializeAsString());
  send(referee, stop);
  send(referee, "not a referee message");
  send(vision, detection_packet(1, 10.1).SerializeAsString());
  send(referee, start);
  TrackerWrapperPacket tracked;
  tracked.set_uuid("tracker-1");
  tracked.mutable_tracked_frame()->set_frame_number(1);
  tracked.mutable_tracked_frame()->set_timestamp(10.15);
  send(tracker, tracked.SerializeAsString());
  send(tracker, "not tracked vision");
  send(vision, detection_packet(2, 10.2).SerializeAsString());
  send(vision, detection_packet(3, 10.3).SerializeAsString());
  ASSERT_EQ(recorder.wait(5s), 0) << recorder.stderr_text();
  const testing::Status done = testing::last_status(recorder.stderr_text(), "done:");
  EXPECT_EQ(done.at("recorded"), 4u) << recorder.stderr_text();
  EXPECT_EQ(done.at("referee_recorded"), 2u) << recorder.stderr_text();
  EXPECT_EQ(done.at("referee_skipped"), 1u) << recorder.stderr_text();
  EXPECT_EQ(done.at("tracked_recorded"), 1u) << recorder.stderr_text();
  EXPECT_EQ(done.at("tracked_skipped"), 1u) << recorder.stderr_text();

  // In the file as they came: types 4 3 4 3 5 4 4, the referee's bytes unchanged.
  auto reader = LogReader::open(path);
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<std::int32_t> types;
  std::vector<std::string> referee_payloads;
  LogMessage message;
  while (reader->next(message)) {
    types.push_back(message.type);
    if (message.type == 3) referee_payloads.push_back(message.payload);
  }
  EXPECT_EQ(types, (std::vector<std::int32_t>{4, 3, 4, 3, 5, 4, 4}));
  EXPECT_EQ(referee_payloads, (std::vector<std::string>{stop, start}));

  // The replay sends them to the referee group, the vision to the vision group.
  const std::string vision_out = new_group();
  const std::string referee_out = new_group();
  const std::string tracker_out = new_group();
  Listener vision_listener(vision_out);
  Listener referee_listener(referee_out);
  Listener tracker_listener(tracker_out);
  const auto result =
      replay(dir, path, vision_out,
             {"--speed", "0", "--referee-address", referee_out, "--tracker-address", tracker_out});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(vision_listener.wait_for(4, 5s).size(), 4u);
  const auto tracked_sent = tracker_listener.wait_for(1, 5s);
  ASSERT_EQ(tracked_sent.size(), 1u);
  EXPECT_EQ(tracked_sent[0].bytes, tracked.SerializeAsString());
  const auto sent = referee_listener.wait_for(2, 5s);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].bytes, stop);
  EXPECT_EQ(sent[1].bytes, start);
}

TEST(Logs, RecordStopsAfterItsDurationWithAValidFile) {
  TempDir dir;
  const auto path = dir / "quiet.log.gz";
  const auto started = Clock::now();
  const auto result = testing::run_to_end(
      record_program,
      {"--vision-address", new_group(), "--output", path.string(), "--duration", "0.3"}, dir.path(),
      "record", 5s);
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_GE(Clock::now() - started, 300ms);
  const LogVisionPackets recorded = read_vision_log(path).value();
  EXPECT_FALSE(recorded.stopped_early) << recorded.stopped_early->message;
  EXPECT_TRUE(recorded.packets.empty());

  // An existing recording is not overwritten by accident.
  const auto again = testing::run_to_end(
      record_program,
      {"--vision-address", new_group(), "--output", path.string(), "--duration", "0.1"}, dir.path(),
      "again", 5s);
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(again.err.find("--overwrite"), std::string::npos) << again.err;
  const auto overwrite = testing::run_to_end(record_program,
                                             {"--vision-address", new_group(), "--output",
                                              path.string(), "--duration", "0.1", "--overwrite"},
                                             dir.path(), "overwrite", 5s);
  EXPECT_EQ(overwrite.exit_code, 0) << overwrite.err;
}

TEST(Logs, RecordAndReplayShareTheDaemonsOptionStyle) {
  TempDir dir;
  const auto help = testing::run_to_end(record_program, {"--help"}, dir.path(), "help", 5s);
  EXPECT_EQ(help.exit_code, 0);
  for (const std::string option :
       {"--vision-address arg (=224.5.23.2:10006)", "--interface arg (=127.0.0.1)", "--output",
        "--duration", "--count", "--status-interval"}) {
    EXPECT_NE(help.out.find(option), std::string::npos) << "ssl-record lacks " << option;
  }
  const auto producer_help =
      testing::run_to_end(producer_program, {"--help"}, dir.path(), "help", 5s);
  for (const std::string option :
       {"--write-log", "--replay", "--speed arg (=1)", "--loop", "--start", "--end"}) {
    EXPECT_NE(producer_help.out.find(option), std::string::npos) << "ssl-producer lacks " << option;
  }
  const auto bad = testing::run_to_end(record_program, {"--no-such-option"}, dir.path(), "bad", 5s);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  const auto no_output = testing::run_to_end(record_program, {"--vision-address", new_group()},
                                             dir.path(), "no-output", 5s);
  EXPECT_EQ(no_output.exit_code, 2) << no_output.err;
  const auto bad_group = testing::run_to_end(
      record_program, {"--vision-address", "10.1.2.3:10006", "--output", (dir / "x.log").string()},
      dir.path(), "bad-group", 5s);
  EXPECT_EQ(bad_group.exit_code, 2) << bad_group.err;
}

}  // namespace
}  // namespace ssl_formation
