#include "ssl_formation/producer/replay_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::producer {
namespace {

constexpr std::int64_t kUnixNs = 1'700'000'000'000'000'000;  // November 2023, in nanoseconds
constexpr std::int64_t kUnixUs = 1'700'000'000'000'000;      // the same instant in microseconds
constexpr double kUnixS = 1'700'000'000.0;

// `n` packets of a 60 Hz camera: receive times `start + i * per_frame`, t_capture `t0 + i / 60`.
std::vector<ClockSample> camera(int n, std::int64_t start, std::int64_t per_frame, double t0) {
  std::vector<ClockSample> samples;
  for (int i = 0; i < n; ++i) {
    samples.push_back({start + i * per_frame, t0 + i / 60.0});
  }
  return samples;
}

// Two packets one second of t_capture apart whose receive times are `receive_span` apart: the
// ratio the choice measures is exactly `receive_span`.
std::vector<ClockSample> with_ratio(std::int64_t first, std::int64_t receive_span) {
  return {{first, 50.0}, {first + receive_span, 51.0}};
}

TEST(ChooseReplayClock, NothingToLookAtIsTheOfficialUnit) {
  const ClockChoice choice = choose_replay_clock({});
  EXPECT_EQ(choice.clock, ReplayClock::receive_ns);
  EXPECT_EQ(choice.ratio, 0.0);
  EXPECT_FALSE(choice.reason.empty());
}

TEST(ChooseReplayClock, UnixNanosecondsAreNanoseconds) {
  const auto samples = camera(300, kUnixNs, 16'666'667, kUnixS);
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::receive_ns);
  EXPECT_NEAR(choice.ratio, 1e9, 1e9 * 1e-3);
}

TEST(ChooseReplayClock, NanosecondsSinceStartAreNanosecondsByTheirRatio) {
  // A simulator's log: receive times count from zero, far below the 1e17 rule.
  const auto samples = camera(300, 5'000'000, 16'666'667, 3.0);
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::receive_ns);
  EXPECT_NEAR(choice.ratio, 1e9, 1e9 * 1e-3);
  EXPECT_NE(choice.reason.find("1e9"), std::string::npos) << choice.reason;
}

TEST(ChooseReplayClock, UnixMicrosecondsAreMicroseconds) {
  const auto samples = camera(300, kUnixUs, 16'667, kUnixS);
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::receive_us);
  EXPECT_NEAR(choice.ratio, 1e6, 1e6 * 1e-3);
  EXPECT_NE(choice.reason.find("1e6"), std::string::npos) << choice.reason;
}

TEST(ChooseReplayClock, AllZeroReceiveTimesUseTCapture) {
  const auto samples = camera(100, 0, 0, kUnixS);
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::t_capture);
  EXPECT_NE(choice.reason.find("zero"), std::string::npos) << choice.reason;
}

TEST(ChooseReplayClock, ReceiveTimesGoingBackwardsUseTCapture) {
  auto samples = camera(100, kUnixNs, 16'666'667, kUnixS);
  samples[50].receive_time = samples[49].receive_time - 1;  // one step back is enough
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::t_capture);
  EXPECT_NE(choice.reason.find("backwards"), std::string::npos) << choice.reason;
}

TEST(ChooseReplayClock, EqualNonZeroReceiveTimesUseTCapture) {
  const auto samples = camera(100, kUnixNs, 0, kUnixS);
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::t_capture);
  EXPECT_NE(choice.reason.find("same"), std::string::npos) << choice.reason;
}

TEST(ChooseReplayClock, EqualNeighboursAreNotBackwards) {
  // Two cameras' packets received in the same nanosecond: still a usable, monotonic clock.
  auto samples = camera(100, kUnixNs, 16'666'667, kUnixS);
  samples[11].receive_time = samples[10].receive_time;
  EXPECT_EQ(choose_replay_clock(samples).clock, ReplayClock::receive_ns);
}

TEST(ChooseReplayClock, OnePacketIsTheOfficialUnit) {
  const std::vector<ClockSample> samples{{12345, 1.0}};
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::receive_ns);
  EXPECT_EQ(choice.ratio, 0.0);
}

TEST(ChooseReplayClock, NoTCaptureSpanIsTheOfficialUnit) {
  // Microsecond-like receive times, but nothing to compare them with: no detection at all, one
  // detection, or detections whose t_capture does not advance.
  const std::vector<ClockSample> no_frames{{1000, std::nullopt}, {2000, std::nullopt}};
  const std::vector<ClockSample> one_frame{{1000, std::nullopt}, {2'000'000, 5.0}};
  const std::vector<ClockSample> stuck{{1000, 5.0}, {2'000'000, 5.0}};
  const std::vector<ClockSample> backwards{{1000, 6.0}, {2'000'000, 5.0}};
  for (const auto* samples : {&no_frames, &one_frame, &stuck, &backwards}) {
    const ClockChoice choice = choose_replay_clock(*samples);
    EXPECT_EQ(choice.clock, ReplayClock::receive_ns);
    EXPECT_EQ(choice.ratio, 0.0);
    EXPECT_NE(choice.reason.find("official"), std::string::npos) << choice.reason;
  }
}

TEST(ChooseReplayClock, TheRatioIsMeasuredBetweenPacketsWithFrames) {
  // A geometry packet received 40 s before the first frame: measured from it, the ratio would be
  // 4.1e7 (nanoseconds); between the frames it is 1e6 (microseconds).
  const std::vector<ClockSample> samples{{0, std::nullopt},
                                         {40'000'000, 100.0},
                                         {40'500'000, std::nullopt},
                                         {41'000'000, 101.0},
                                         {41'000'001, std::nullopt}};
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::receive_us);
  EXPECT_EQ(choice.ratio, 1e6);
}

TEST(ChooseReplayClock, NonFiniteTCaptureIsIgnored) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<ClockSample> samples{
      {1'000'000, nan}, {2'000'000, 10.0}, {2'500'000, inf}, {3'000'000, 11.0}, {9'000'000, nan}};
  const ClockChoice choice = choose_replay_clock(samples);
  EXPECT_EQ(choice.clock, ReplayClock::receive_us);
  EXPECT_EQ(choice.ratio, 1e6);
}

TEST(ChooseReplayClock, AFirstReceiveTimeOf1e17OrMoreIsNanosecondsWhateverTheRatio) {
  constexpr std::int64_t e17 = 100'000'000'000'000'000;
  // The spans say microseconds (1e6 per second of t_capture) ...
  const ClockChoice at = choose_replay_clock(with_ratio(e17, 1'000'000));
  EXPECT_EQ(at.clock, ReplayClock::receive_ns);
  EXPECT_EQ(at.ratio, 1e6);  // measured all the same, for the log
  EXPECT_NE(at.reason.find("Unix time"), std::string::npos) << at.reason;
  // ... and one below the rule the ratio decides.
  EXPECT_EQ(choose_replay_clock(with_ratio(e17 - 1, 1'000'000)).clock, ReplayClock::receive_us);
}

TEST(ChooseReplayClock, TheRatioThresholdsOfMicroseconds) {
  const std::int64_t first = 1'000'000;
  // Microseconds from 1e5 (inclusive) ...
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 100'000)).clock, ReplayClock::receive_us);
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 99'999)).clock, ReplayClock::receive_ns);
  // ... to 10^7.5 = 31,622,776.6 (exclusive).
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 31'622'776)).clock, ReplayClock::receive_us);
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 31'622'777)).clock, ReplayClock::receive_ns);
  // Far outside on both sides: the official unit.
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 1'000)).clock, ReplayClock::receive_ns);
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 1'000'000'000)).clock, ReplayClock::receive_ns);
  EXPECT_EQ(choose_replay_clock(with_ratio(first, 31'622'776)).ratio, 31'622'776.0);
}

TEST(ReplayClock, EveryClockHasItsOwnName) {
  const std::string ns = to_string(ReplayClock::receive_ns);
  const std::string us = to_string(ReplayClock::receive_us);
  const std::string tc = to_string(ReplayClock::t_capture);
  EXPECT_NE(ns, us);
  EXPECT_NE(ns, tc);
  EXPECT_NE(us, tc);
  EXPECT_NE(ns.find("nanoseconds"), std::string::npos);
  EXPECT_NE(us.find("microseconds"), std::string::npos);
  EXPECT_NE(tc.find("t_capture"), std::string::npos);
}

// ---- ReplayTimeline ----

SSL_WrapperPacket frame_packet(double t_capture) {
  SSL_WrapperPacket packet;
  SSL_DetectionFrame& frame = *packet.mutable_detection();
  frame.set_frame_number(1);
  frame.set_t_capture(t_capture);
  frame.set_t_sent(t_capture);
  frame.set_camera_id(0);
  return packet;
}

SSL_WrapperPacket geometry_packet() {
  SSL_WrapperPacket packet;
  SSL_GeometryFieldSize& field = *packet.mutable_geometry()->mutable_field();
  field.set_field_length(9000);
  field.set_field_width(6000);
  field.set_goal_width(1000);
  field.set_goal_depth(180);
  field.set_boundary_width(300);
  return packet;
}

TEST(ReplayTimeline, NanosecondsFromTheFirstPacket) {
  ReplayTimeline timeline(ReplayClock::receive_ns);
  EXPECT_EQ(timeline.clock(), ReplayClock::receive_ns);
  const SSL_WrapperPacket packet = frame_packet(999.0);  // t_capture plays no part here
  EXPECT_EQ(timeline.time_of(kUnixNs, packet), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixNs + 16'000'000, packet), 0.016);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixNs + 2'500'000'000, packet), 2.5);
}

TEST(ReplayTimeline, MicrosecondsFromTheFirstPacket) {
  ReplayTimeline timeline(ReplayClock::receive_us);
  const SSL_WrapperPacket packet = frame_packet(0.0);
  EXPECT_EQ(timeline.time_of(kUnixUs, packet), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixUs + 16'000, packet), 0.016);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixUs + 2'500'000, packet), 2.5);
}

TEST(ReplayTimeline, TCaptureFromTheFirstFrameAndGeometryGoesWithThePrevious) {
  ReplayTimeline timeline(ReplayClock::t_capture);
  // A geometry packet before any frame starts nothing: the first frame is the origin.
  EXPECT_EQ(timeline.time_of(0, geometry_packet()), 0.0);
  EXPECT_EQ(timeline.time_of(0, frame_packet(kUnixS + 10.0)), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(0, frame_packet(kUnixS + 10.5)), 0.5);
  EXPECT_DOUBLE_EQ(timeline.time_of(123, geometry_packet()), 0.5);
  // Receive times are ignored on this clock, however wild.
  EXPECT_DOUBLE_EQ(
      timeline.time_of(std::numeric_limits<std::int64_t>::min(), frame_packet(kUnixS + 11.0)), 1.0);
  // A frame whose t_capture is not a number goes with the previous packet.
  EXPECT_DOUBLE_EQ(timeline.time_of(0, frame_packet(std::nan(""))), 1.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(0, frame_packet(kUnixS + 12.0)), 2.0);
}

TEST(ReplayTimeline, SmallInterleavingJitterNeverGoesBack) {
  // Four cameras' t_capture interleave: a packet a few milliseconds behind the newest one.
  ReplayTimeline timeline(ReplayClock::t_capture);
  const std::vector<double> captures{100.000, 100.016, 100.010, 100.012, 100.033,
                                     100.020, 100.500, 99.600,  100.540};
  std::vector<double> times;
  for (double t : captures) times.push_back(timeline.time_of(0, frame_packet(t)));
  const std::vector<double> expected{0.0, 0.016, 0.016, 0.016, 0.033, 0.033, 0.5, 0.5, 0.54};
  ASSERT_EQ(times.size(), expected.size());
  for (std::size_t i = 0; i < times.size(); ++i) {
    EXPECT_NEAR(times[i], expected[i], 1e-9) << "packet " << i;
    if (i > 0) {
      EXPECT_GE(times[i], times[i - 1]) << "packet " << i;
    }
  }
}

TEST(ReplayTimeline, AJumpBackBeyondResetContinuesTheTimeline) {
  ReplayTimeline timeline(ReplayClock::receive_ns, 1.0);
  const SSL_WrapperPacket packet = frame_packet(0.0);
  EXPECT_EQ(timeline.time_of(kUnixNs, packet), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixNs + 5'000'000'000, packet), 5.0);
  // The recorder's clock restarted 1.5 s back (beyond reset_s): not all at once, nor waiting
  // for 5 s; the new segment goes on from 5 s ...
  const std::int64_t restart = kUnixNs + 3'500'000'000;
  EXPECT_DOUBLE_EQ(timeline.time_of(restart, packet), 5.0);
  // ... and advances with the restarted clock.
  EXPECT_DOUBLE_EQ(timeline.time_of(restart + 250'000'000, packet), 5.25);
  EXPECT_DOUBLE_EQ(timeline.time_of(restart + 2'000'000'000, packet), 7.0);
}

TEST(ReplayTimeline, AJumpBackWithinResetIsHeldNotANewSegment) {
  ReplayTimeline timeline(ReplayClock::receive_ns, 1.0);
  const SSL_WrapperPacket packet = frame_packet(0.0);
  timeline.time_of(kUnixNs, packet);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixNs + 5'000'000'000, packet), 5.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixNs + 4'100'000'000, packet), 5.0);  // 0.9 s back
  // Still the old clock: 5.5 s after the first packet is 5.5, not 5.0 + 1.4.
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixNs + 5'500'000'000, packet), 5.5);
}

TEST(ReplayTimeline, ResetSecondsAreTheCallersChoice) {
  ReplayTimeline timeline(ReplayClock::t_capture, 0.1);
  EXPECT_EQ(timeline.time_of(0, frame_packet(10.0)), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(0, frame_packet(11.0)), 1.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(0, frame_packet(10.8)), 1.0);   // 0.2 s back: a restart
  EXPECT_NEAR(timeline.time_of(0, frame_packet(10.9)), 1.1, 1e-9);  // on the new clock
}

TEST(ReplayTimeline, AReceiveTimeThatOverflowsTheDifferenceIsARestart) {
  ReplayTimeline timeline(ReplayClock::receive_ns);
  const SSL_WrapperPacket packet = frame_packet(0.0);
  timeline.time_of(std::numeric_limits<std::int64_t>::max() - 1'000'000'000, packet);
  EXPECT_DOUBLE_EQ(timeline.time_of(std::numeric_limits<std::int64_t>::max(), packet), 1.0);
  const std::int64_t low = std::numeric_limits<std::int64_t>::min() + 10;
  EXPECT_DOUBLE_EQ(timeline.time_of(low, packet), 1.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(low + 500'000'000, packet), 1.5);
}

TEST(ReplayTimeline, RestartBeginsANewPassAtZero) {
  ReplayTimeline timeline(ReplayClock::receive_us);
  const SSL_WrapperPacket packet = frame_packet(0.0);
  timeline.time_of(kUnixUs, packet);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixUs + 30'000'000, packet), 30.0);
  timeline.restart();  // --loop: the same file again
  EXPECT_EQ(timeline.time_of(kUnixUs, packet), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixUs + 1'000'000, packet), 1.0);
  // A restart also forgets the origin: a second file starting later begins at zero too.
  timeline.restart();
  EXPECT_EQ(timeline.time_of(kUnixUs + 999'000'000, packet), 0.0);
  EXPECT_DOUBLE_EQ(timeline.time_of(kUnixUs + 999'250'000, packet), 0.25);
}

TEST(ReplayTimeline, NeverDecreasesWhateverTheInput) {
  // A pseudo-random walk with jitter, restarts and wild values, on every clock.
  for (ReplayClock clock :
       {ReplayClock::receive_ns, ReplayClock::receive_us, ReplayClock::t_capture}) {
    ReplayTimeline timeline(clock);
    std::uint64_t x = 42;
    const auto next = [&x] {
      x = x * 6364136223846793005ULL + 1442695040888963407ULL;
      return x >> 33;
    };
    std::int64_t receive = 1'000'000;
    double capture = 100.0;
    double last = 0.0;
    for (int i = 0; i < 5000; ++i) {
      const std::uint64_t r = next() % 100;
      if (r < 80) {
        receive += static_cast<std::int64_t>(next() % 20'000'000);
        capture += static_cast<double>(next() % 20) / 1000.0;
      } else if (r < 95) {
        receive -= static_cast<std::int64_t>(next() % 5'000'000);
        capture -= static_cast<double>(next() % 5) / 1000.0;
      } else if (r < 99) {
        receive -= static_cast<std::int64_t>(next() % 100'000'000'000);
        capture -= static_cast<double>(next() % 100);
      } else {
        receive = static_cast<std::int64_t>(next() << 31);
        capture = static_cast<double>(next());
      }
      const double t = r == 50 ? timeline.time_of(receive, geometry_packet())
                               : timeline.time_of(receive, frame_packet(capture));
      ASSERT_TRUE(std::isfinite(t)) << "packet " << i;
      ASSERT_GE(t, last) << "packet " << i << " on " << to_string(clock);
      last = t;
    }
    EXPECT_GT(last, 0.0);
  }
}

}  // namespace
}  // namespace ssl_formation::producer
