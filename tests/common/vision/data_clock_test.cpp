#include "ssl_formation/vision/data_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation {
namespace {

using Log = std::vector<std::string>;

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// Writes down everything the clock reports, in order: "frame 0@1.5 r7" (camera 0, t = 1.5,
// robot 7), "instant 2@4 forced conflict", "aside", "late", "duplicate", "conflict",
// "restart take_over".
class Recorder : public DataClockListener {
 public:
  Log log;
  DataClock* reset_clock = nullptr;  // reset from inside the reset_at-th instant, if set
  int reset_at = 0;

  void on_frame(const ClockFrame& frame, const std::vector<FrameDetection>& detections) override {
    std::string line = "frame " + std::to_string(frame.camera_id) + "@" + number(frame.time_s);
    for (const FrameDetection& d : detections) line += " r" + std::to_string(d.robot_id);
    log.push_back(line);
  }
  void on_instant(const ClockInstant& instant) override {
    std::string line = "instant " + std::to_string(instant.k) + "@" + number(instant.time_s);
    if (instant.forced) line += " forced";
    if (instant.in_conflict) line += " conflict";
    log.push_back(line);
    if (reset_clock != nullptr && --reset_at == 0) reset_clock->reset();
  }
  void on_restart(ClockRestart why) override {
    log.push_back(why == ClockRestart::take_over ? "restart take_over"
                                                 : "restart instant_overflow");
  }
  void on_event(ClockEvent event) override {
    switch (event) {
      case ClockEvent::frame_late:
        log.push_back("late");
        break;
      case ClockEvent::frame_duplicate:
        log.push_back("duplicate");
        break;
      case ClockEvent::frame_set_aside:
        log.push_back("aside");
        break;
      case ClockEvent::conflict:
        log.push_back("conflict");
        break;
    }
  }
};

// A clock and what it reported; frame() returns what one frame made it report.
struct Feed {
  explicit Feed(DataClockConfig config = {}) : clock(config) {}

  // Frame numbers count up by themselves unless given (a duplicate repeats one).
  Log frame(std::uint32_t camera, double t, std::uint32_t frame_number = 0,
            std::uint32_t robot = no_robot) {
    if (frame_number == 0) frame_number = ++last_number;
    std::vector<FrameDetection> detections;
    if (robot != no_robot) detections.push_back(FrameDetection{robot, 0.0, 0.0, 1.0F});
    const std::size_t before = recorder.log.size();
    clock.place(recorder, ClockFrame{camera, frame_number, t}, detections);
    return Log(recorder.log.begin() + static_cast<std::ptrdiff_t>(before), recorder.log.end());
  }

  static constexpr std::uint32_t no_robot = 0xffffffff;
  DataClock clock;
  Recorder recorder;
  std::uint32_t last_number = 1000;
};

DataClockConfig step(double step_s) {
  DataClockConfig config;
  config.step_s = step_s;
  return config;
}

TEST(DataClock, ResolvesItsDefaultsFromTheStep) {
  const DataClockConfig two = step(2.0);
  EXPECT_EQ(two.clock_reset_window_s(), 4.0);  // two steps
  EXPECT_EQ(two.camera_live_window_s(), 3.0);  // 1.5 steps beat the 1 s camera timeout
  EXPECT_EQ(two.first_instant_wait_s(), 1.0);  // the camera timeout, shorter than a step
  EXPECT_EQ(two.conflict_hold_s(), 8.0);       // four steps

  const DataClockConfig fast = step(0.125);
  EXPECT_EQ(fast.clock_reset_window_s(), 0.25);
  EXPECT_EQ(fast.camera_live_window_s(), 1.0);  // the camera timeout beats 1.5 steps
  EXPECT_EQ(fast.first_instant_wait_s(), 0.125);
  EXPECT_EQ(fast.conflict_hold_s(), 0.5);

  DataClockConfig set = step(2.0);
  set.clock_reset_s = 0.5;
  set.clock_conflict_hold_s = 3.0;
  set.camera_timeout_s = 5.0;
  EXPECT_EQ(set.clock_reset_window_s(), 0.5);
  EXPECT_EQ(set.conflict_hold_s(), 3.0);
  EXPECT_EQ(set.camera_live_window_s(), 5.0);
  EXPECT_EQ(set.first_instant_wait_s(), 2.0);

  // Programs set the clock's fields by name on a SamplerConfig, which resolves them the same way.
  SamplerConfig sampler;
  sampler.step_s = 1.0;
  sampler.robot_timeout_s = 2.0;
  EXPECT_EQ(sampler.clock_reset_window_s(), 2.0);
  EXPECT_EQ(sampler.conflict_hold_s(), 4.0);
  EXPECT_EQ(sampler.robot_fresh_window_s(), 1.0);
  EXPECT_EQ(SamplerConfig{}.clock_confirm_times, 3);
  EXPECT_EQ(SamplerConfig{}.max_pending_frames, 256u);
}

TEST(DataClock, RejectsAStepThatIsNotPositiveAndFinite) {
  for (const double bad : {0.0, -2.0, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(DataClock{step(bad)}, std::invalid_argument) << bad;
  }
}

TEST(DataClock, OneCameraHandsEachInstantOnWithTheFrameThatReachesIt) {
  Feed feed;
  EXPECT_EQ(feed.frame(0, 0.0), (Log{"frame 0@0"}));  // the first instant waits 1 s
  EXPECT_EQ(feed.frame(0, 0.5), (Log{"frame 0@0.5"}));
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));
  EXPECT_EQ(feed.frame(0, 1.5), (Log{"frame 0@1.5"}));  // between instants: used
  EXPECT_EQ(feed.frame(0, 2.0), (Log{"frame 0@2", "instant 1@2"}));
  EXPECT_EQ(feed.frame(0, 3.5), (Log{"frame 0@3.5"}));
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"frame 0@4", "instant 2@4"}));
  EXPECT_EQ(feed.clock.next_instant(), 3);
  EXPECT_FALSE(feed.clock.open_instant());
  EXPECT_EQ(feed.clock.instant_s(3), 6.0);
}

TEST(DataClock, SeveralCamerasCompleteAnInstantWhenTheLastLiveCameraReports) {
  Feed feed;
  for (const std::uint32_t camera : {0u, 1u, 2u}) {
    EXPECT_EQ(feed.frame(camera, 0.0), (Log{"frame " + std::to_string(camera) + "@0"}));
  }
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));  // all three at or after 0
  EXPECT_EQ(feed.frame(1, 1.0), (Log{"frame 1@1"}));
  EXPECT_EQ(feed.frame(2, 1.0), (Log{"frame 2@1"}));
  EXPECT_EQ(feed.frame(0, 2.0), (Log{"frame 0@2"}));
  EXPECT_EQ(feed.frame(1, 2.0), (Log{"frame 1@2"}));
  EXPECT_EQ(feed.frame(2, 2.0), (Log{"frame 2@2", "instant 1@2"}));
  EXPECT_EQ(feed.clock.open_instant(), std::nullopt);
  // Any order: the instant goes with whichever camera reports last.
  EXPECT_EQ(feed.frame(2, 4.0), (Log{"frame 2@4"}));
  EXPECT_EQ(feed.clock.open_instant(), std::optional<std::int64_t>{2});
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"frame 0@4"}));
  EXPECT_EQ(feed.frame(1, 4.0), (Log{"frame 1@4", "instant 2@4"}));
}

TEST(DataClock, ADroppedCameraFrameForcesTheInstantBeforeTheNewerFrameIsUsed) {
  Feed feed;  // two cameras of a 2 s feed: one frame each per step
  EXPECT_EQ(feed.frame(0, 0.0), (Log{"frame 0@0"}));
  EXPECT_EQ(feed.frame(1, 0.0), (Log{"frame 1@0"}));
  // Instant 0 is still waiting for cameras to be discovered: handed on, but never "forced".
  EXPECT_EQ(feed.frame(0, 2.0), (Log{"instant 0@0", "frame 0@2"}));
  EXPECT_EQ(feed.frame(1, 2.0), (Log{"frame 1@2", "instant 1@2"}));
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"frame 0@4"}));  // camera 1's frame at 4 is lost
  // Camera 0 reaches instant 3: instant 2 goes without camera 1, before the frame at 6 is used.
  // Camera 1 (last seen at 2, 4 s ago) is no longer live, so instant 3 is complete at once.
  EXPECT_EQ(feed.frame(0, 6.0), (Log{"instant 2@4 forced", "frame 0@6", "instant 3@6"}));
  EXPECT_EQ(feed.frame(1, 6.0), (Log{"frame 1@6"}));
  EXPECT_EQ(feed.frame(0, 8.0), (Log{"frame 0@8"}));  // camera 1 is live again
  EXPECT_EQ(feed.frame(1, 8.0), (Log{"frame 1@8", "instant 4@8"}));
}

TEST(DataClock, ACameraThatFallsSilentHoldsInstantsBackOnlyWhileLive) {
  Feed feed;  // live window: 3 s
  EXPECT_EQ(feed.frame(0, 0.0), (Log{"frame 0@0"}));
  EXPECT_EQ(feed.frame(1, 0.0), (Log{"frame 1@0"}));
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));
  EXPECT_EQ(feed.frame(0, 2.0), (Log{"frame 0@2"}));  // camera 1 (at 0) holds instant 1
  EXPECT_EQ(feed.frame(0, 3.0), (Log{"frame 0@3"}));  // still: 3 s is live
  EXPECT_EQ(feed.frame(0, 3.5), (Log{"frame 0@3.5", "instant 1@2"}));
}

TEST(DataClock, TheFirstInstantWaitsForCamerasToBeDiscovered) {
  Feed feed;  // waits min(camera timeout 1 s, step 2 s)
  EXPECT_EQ(feed.frame(0, 0.0), (Log{"frame 0@0"}));
  EXPECT_EQ(feed.frame(0, 0.5), (Log{"frame 0@0.5"}));
  EXPECT_EQ(feed.frame(1, 0.75), (Log{"frame 1@0.75"}));  // discovered in time
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));

  DataClockConfig short_wait;
  short_wait.camera_timeout_s = 0.25;
  Feed hasty(short_wait);
  EXPECT_EQ(hasty.frame(0, 0.0), (Log{"frame 0@0"}));
  EXPECT_EQ(hasty.frame(0, 0.25), (Log{"frame 0@0.25", "instant 0@0"}));  // camera 1 unknown
  EXPECT_EQ(hasty.frame(1, 0.75), (Log{"frame 1@0.75"}));
}

TEST(DataClock, FramesOlderThanTheLastInstantAreLate) {
  Feed feed;
  feed.frame(0, 0.0);
  feed.frame(0, 1.0);
  feed.frame(0, 2.0);
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"frame 0@4", "instant 2@4"}));
  EXPECT_EQ(feed.frame(0, 3.5), (Log{"late"}));
  EXPECT_EQ(feed.frame(1, 2.0), (Log{"late"}));         // whatever the camera
  EXPECT_EQ(feed.frame(0, 4.5), (Log{"frame 0@4.5"}));  // after the last instant: used
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"frame 0@4"}));    // at it: used
  EXPECT_EQ(feed.frame(0, 6.0), (Log{"frame 0@6", "instant 3@6"}));
}

TEST(DataClock, ARepeatOfACamerasLastFrameIsADuplicate) {
  Feed feed;
  EXPECT_EQ(feed.frame(0, 0.0, 5), (Log{"frame 0@0"}));
  EXPECT_EQ(feed.frame(0, 0.0, 5), (Log{"duplicate"}));
  EXPECT_EQ(feed.frame(0, 0.0, 6), (Log{"frame 0@0"}));  // same time, another frame
  EXPECT_EQ(feed.frame(1, 0.0, 6), (Log{"frame 1@0"}));  // another camera
  EXPECT_EQ(feed.frame(0, 1.0, 7), (Log{"frame 0@1", "instant 0@0"}));
  EXPECT_EQ(feed.frame(0, 1.0, 7), (Log{"duplicate"}));
  EXPECT_EQ(feed.frame(1, 1.0, 7), (Log{"frame 1@1"}));
  EXPECT_EQ(feed.frame(1, 1.0, 7), (Log{"duplicate"}));
  EXPECT_EQ(feed.frame(1, 1.5, 7), (Log{"frame 1@1.5"}));  // same number, another time
}

TEST(DataClock, AGapWithinTheResetWindowSkipsTheInstantsBetween) {
  Feed feed;  // reset window: 4 s
  feed.frame(0, 0.0);
  feed.frame(0, 1.0);
  EXPECT_EQ(feed.frame(0, 2.0), (Log{"frame 0@2", "instant 1@2"}));
  EXPECT_EQ(feed.frame(0, 6.0), (Log{"frame 0@6", "instant 3@6"}));  // no instant 2
  EXPECT_EQ(feed.frame(0, 9.5), (Log{"frame 0@9.5", "instant 4@8"}));
  EXPECT_EQ(feed.frame(0, 10.0), (Log{"frame 0@10", "instant 5@10"}));
  EXPECT_EQ(feed.clock.newest_s(), 10.0);
}

TEST(DataClock, ARestartedClockIsSetAsideConfirmedThenReplayed) {
  Feed feed;  // three distinct times confirm
  feed.frame(0, 1000.0);
  feed.frame(0, 1001.0);
  EXPECT_EQ(feed.frame(0, 1002.0), (Log{"frame 0@1002", "instant 1@1002"}));
  // The sender restarted at 3 s.
  EXPECT_EQ(feed.frame(0, 3.0, 0, 1), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 3.5, 0, 2), (Log{"aside"}));
  EXPECT_EQ(feed.clock.frames_set_aside(), 2u);
  EXPECT_EQ(feed.frame(0, 4.0, 0, 3), (Log{"aside", "restart take_over", "frame 0@3 r1",
                                           "frame 0@3.5 r2", "frame 0@4 r3", "instant 0@3"}));
  EXPECT_EQ(feed.clock.frames_set_aside(), 0u);
  EXPECT_EQ(feed.clock.instant_s(0), 3.0);
  EXPECT_EQ(feed.frame(0, 5.0), (Log{"frame 0@5", "instant 1@5"}));
  EXPECT_FALSE(feed.clock.in_conflict());
}

// After a take-over the clock left behind is the other clock: if it comes back having advanced
// (it had handed on two instants, or comes back later), two senders interleave.
TEST(DataClock, TheClockLeftBehindComingBackIsAConflictIfItHadAdvanced) {
  Feed advanced;
  advanced.frame(0, 1000.0);
  advanced.frame(0, 1001.0);
  EXPECT_EQ(advanced.frame(0, 1002.0), (Log{"frame 0@1002", "instant 1@1002"}));
  advanced.frame(0, 3.0);
  advanced.frame(0, 3.5);
  EXPECT_EQ(advanced.frame(0, 4.0).back(), "instant 0@3");
  EXPECT_EQ(advanced.frame(0, 1002.0), (Log{"aside"}));  // the same time as it left
  EXPECT_EQ(advanced.frame(0, 5.0), (Log{"conflict", "frame 0@5", "instant 1@5 conflict"}));

  Feed barely;  // handed on one instant only: coming back at its last time is a stray frame
  barely.frame(0, 1000.0);
  EXPECT_EQ(barely.frame(0, 1001.0), (Log{"frame 0@1001", "instant 0@1000"}));
  barely.frame(0, 3.0);
  barely.frame(0, 3.5);
  EXPECT_EQ(barely.frame(0, 4.0).back(), "instant 0@3");
  EXPECT_EQ(barely.frame(0, 1001.0), (Log{"aside"}));
  EXPECT_EQ(barely.frame(0, 5.0), (Log{"frame 0@5", "instant 1@5"}));
}

TEST(DataClock, SetAsideFramesOfOneTimeCountAsOneTime) {
  DataClockConfig config;
  config.clock_confirm_times = 2;
  Feed feed(config);
  feed.frame(0, 100.0);
  feed.frame(1, 100.0);
  EXPECT_EQ(feed.frame(0, 101.0), (Log{"frame 0@101", "instant 0@100"}));
  EXPECT_EQ(feed.frame(0, 10.0), (Log{"aside"}));
  EXPECT_EQ(feed.frame(1, 10.0), (Log{"aside"}));  // still one time
  EXPECT_EQ(feed.frame(0, 10.5),
            (Log{"aside", "restart take_over", "frame 0@10", "frame 1@10", "frame 0@10.5"}));
}

TEST(DataClock, ARestartedClockPassingThroughTheOldTimesIsStillSetAside) {
  Feed feed;
  for (const double t : {0.0, 1.0, 2.0, 4.0, 6.0, 8.0}) feed.frame(0, t);
  EXPECT_EQ(feed.frame(0, 10.0), (Log{"frame 0@10", "instant 5@10"}));
  EXPECT_EQ(feed.frame(0, 5.0), (Log{"aside"}));  // 5 s back: another clock
  // Within 4 s of the current clock, but older than its last instant and near the other clock:
  // the other clock's, not a late frame.
  EXPECT_EQ(feed.frame(0, 6.5), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 7.0), (Log{"aside", "restart take_over", "frame 0@5", "frame 0@6.5",
                                     "instant 0@5", "frame 0@7", "instant 1@7"}));
}

TEST(DataClock, AStrayOldOrFutureFrameNeverMovesTheClock) {
  Feed feed;
  feed.frame(0, 0.0);
  feed.frame(0, 1.0);
  for (int k = 1; k <= 10; ++k) feed.frame(0, 2.0 * k);
  EXPECT_EQ(feed.frame(0, 0.0, 7), (Log{"aside"}));  // twenty seconds old
  EXPECT_EQ(feed.frame(0, 0.0, 7), (Log{"aside"}));  // and again
  EXPECT_EQ(feed.frame(0, 40.0), (Log{"aside"}));    // twenty seconds ahead: not the same one
  EXPECT_EQ(feed.clock.frames_set_aside(), 1u);
  EXPECT_EQ(feed.frame(0, 22.0), (Log{"frame 0@22", "instant 11@22"}));  // no conflict
  EXPECT_EQ(feed.clock.frames_set_aside(), 0u);
  EXPECT_EQ(feed.frame(0, 24.0), (Log{"frame 0@24", "instant 12@24"}));
  EXPECT_FALSE(feed.clock.in_conflict());
}

TEST(DataClock, ASecondSenderInterleavingIsAConflictUntilSilentForTheHoldTime) {
  Feed feed;  // hold: four steps, 8 s
  feed.frame(0, 0.0);
  feed.frame(0, 1.0);
  feed.frame(0, 2.0);
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"frame 0@4", "instant 2@4"}));
  EXPECT_EQ(feed.frame(0, 5000.0), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 6.0), (Log{"frame 0@6", "instant 3@6"}));  // a stray, so far
  EXPECT_EQ(feed.frame(0, 5002.0), (Log{"aside"}));                  // it advances
  EXPECT_EQ(feed.frame(0, 8.0), (Log{"conflict", "frame 0@8", "instant 4@8 conflict"}));
  EXPECT_TRUE(feed.clock.in_conflict());
  EXPECT_EQ(feed.frame(0, 5004.0), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 10.0), (Log{"frame 0@10", "instant 5@10 conflict"}));  // counted once
  // The second sender was last seen when the clock was at 8: it has been silent long enough
  // once the clock passes 16.
  EXPECT_EQ(feed.frame(0, 12.0), (Log{"frame 0@12", "instant 6@12 conflict"}));
  EXPECT_EQ(feed.frame(0, 14.0), (Log{"frame 0@14", "instant 7@14 conflict"}));
  EXPECT_EQ(feed.frame(0, 16.0), (Log{"frame 0@16", "instant 8@16 conflict"}));
  EXPECT_EQ(feed.frame(0, 18.0), (Log{"frame 0@18", "instant 9@18"}));
  EXPECT_FALSE(feed.clock.in_conflict());
}

TEST(DataClock, ATakeOverDuringAConflictStaysOneUntilTheClockLeftBehindFallsSilent) {
  Feed feed;
  for (const double t : {0.0, 1.0, 2.0, 4.0}) feed.frame(0, t);
  feed.frame(0, 5000.0);
  feed.frame(0, 6.0);
  feed.frame(0, 5002.0);
  EXPECT_EQ(feed.frame(0, 8.0), (Log{"conflict", "frame 0@8", "instant 4@8 conflict"}));
  // The first sender stops; the second one's clock is confirmed and takes over.
  EXPECT_EQ(feed.frame(0, 5004.0), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 5006.0), (Log{"aside"}));
  EXPECT_EQ(
      feed.frame(0, 5008.0),
      (Log{"aside", "restart take_over", "frame 0@5004", "instant 0@5004 conflict", "frame 0@5006",
           "instant 1@5006 conflict", "frame 0@5008", "instant 2@5008 conflict"}));
  EXPECT_EQ(feed.frame(0, 5010.0), (Log{"frame 0@5010", "instant 3@5010 conflict"}));
  EXPECT_EQ(feed.frame(0, 5012.0), (Log{"frame 0@5012", "instant 4@5012 conflict"}));
  EXPECT_EQ(feed.frame(0, 5014.0), (Log{"frame 0@5014", "instant 5@5014 conflict"}));
  EXPECT_EQ(feed.frame(0, 5016.0), (Log{"frame 0@5016", "instant 6@5016 conflict"}));
  EXPECT_EQ(feed.frame(0, 5018.0), (Log{"frame 0@5018", "instant 7@5018"}));
}

TEST(DataClock, MaxPendingFramesTakeOverWithoutDistinctTimes) {
  DataClockConfig config;
  config.clock_confirm_times = 100;
  config.max_pending_frames = 4;
  Feed feed(config);
  feed.frame(0, 0.0);
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));
  for (const std::uint32_t camera : {0u, 1u, 2u}) {
    EXPECT_EQ(feed.frame(camera, 1000.0), (Log{"aside"}));
  }
  EXPECT_EQ(feed.frame(3, 1000.0), (Log{"aside", "restart take_over", "frame 0@1000",
                                        "frame 1@1000", "frame 2@1000", "frame 3@1000"}));
}

TEST(DataClock, AnInstantNumberBeyondTheLimitAnchorsAfresh) {
  DataClockConfig config;
  config.clock_reset_s = 1e15;  // so that the jump is not another clock
  Feed feed(config);
  feed.frame(0, 0.0);
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));
  EXPECT_EQ(feed.frame(0, 2.5e12), (Log{"restart instant_overflow", "frame 0@2500000000000"}));
  EXPECT_EQ(feed.frame(0, 2.5e12 + 1.0), (Log{"frame 0@2500000000001", "instant 0@2500000000000"}));
}

TEST(DataClock, ResetForgetsTheStreamWithoutReportingARestart) {
  Feed feed;
  feed.frame(0, 100.0);
  EXPECT_EQ(feed.frame(0, 101.0), (Log{"frame 0@101", "instant 0@100"}));
  feed.clock.reset();
  EXPECT_FALSE(feed.clock.anchored());
  EXPECT_EQ(feed.frame(0, 0.0), (Log{"frame 0@0"}));  // not another clock: a new one
  EXPECT_EQ(feed.frame(0, 1.0), (Log{"frame 0@1", "instant 0@0"}));
}

// The sampler's handler may start a new stream from inside a sample; during a take-over the
// remaining set-aside frames then start that new stream.
TEST(DataClock, AResetFromInsideAReplayedInstantStartsANewStreamWithTheRestOfTheFrames) {
  Feed feed;
  feed.frame(0, 100.0);
  EXPECT_EQ(feed.frame(0, 101.0), (Log{"frame 0@101", "instant 0@100"}));
  feed.recorder.reset_clock = &feed.clock;
  feed.recorder.reset_at = 1;
  EXPECT_EQ(feed.frame(0, 3.0), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 4.0), (Log{"aside"}));
  EXPECT_EQ(feed.frame(0, 5.0), (Log{"aside", "restart take_over", "frame 0@3", "frame 0@4",
                                     "instant 0@3", "frame 0@5"}));
  EXPECT_EQ(feed.clock.instant_s(0), 5.0);
  EXPECT_EQ(feed.frame(0, 6.0), (Log{"frame 0@6", "instant 0@5"}));
}

}  // namespace
}  // namespace ssl_formation
