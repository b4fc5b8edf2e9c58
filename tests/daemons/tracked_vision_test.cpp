// Tracked vision as the predictor's input, as processes on loopback: a tracker's frames of a set
// of positions (in metres) give the same formations as SSL-Vision's raw detections of the same
// positions, and a second tracker publishing on the same group is not mixed in.

#include <gtest/gtest.h>
#include <signal.h>

#include <thread>

#include "child_process.hpp"
#include "moving_robots.hpp"
#include "pipeline_support.hpp"
#include "ssl_vision_wrapper_tracked.pb.h"
#include "status_lines.hpp"
#include "tracked_frames.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

constexpr double start_s = 700.0;

std::string raw_frame(int f) {
  return testing::raw_frame_of_six(f, start_s, 7).SerializeAsString();
}
std::string tracked_frame(int f, const std::string& uuid, int seed) {
  return testing::tracked_frame_of_six(f, start_s, uuid, seed, true);
}

TEST(TrackedVision, ATrackersFramesGiveTheFormationsOfRawVisionAndASecondTrackerIsNotMixedIn) {
  TempDir dir;
  testing::MovingRobots moving;
  moving.seed = 7;
  moving.seconds = 30.0;
  ASSERT_EQ(testing::write_vision_log(dir / "train.log", testing::moving_robots_packets(moving)),
            "");
  const auto trained = testing::run_to_end(
      trainer_program,
      {"--from-log", (dir / "train.log").string(), "--table", (dir / "t.table").string()},
      dir.path(), "train", 60s);
  ASSERT_EQ(trained.exit_code, 0) << trained.err;

  const std::string raw = new_group();
  const std::string tracker = new_group();
  const std::string raw_predictions = new_group();
  const std::string tracked_predictions = new_group();
  const auto predictor = [&](std::vector<std::string> input, const std::string& out,
                             const std::string& name) {
    std::vector<std::string> args{
        "--prediction-address", out,    "--table", (dir / "t.table").string(),
        "--referee-address",    "none", "--quiet"};
    args.insert(args.end(), input.begin(), input.end());
    return std::make_unique<ChildProcess>(predictor_program, args, dir.path(), name,
                                          Readiness::ready_file);
  };
  auto from_raw = predictor({"--vision-address", raw}, raw_predictions, "raw");
  auto from_tracker = predictor(
      {"--vision-source", "tracked", "--tracker-address", tracker, "--vision-address", raw},
      tracked_predictions, "tracked");
  ASSERT_TRUE(from_raw->wait_until_ready(10s)) << from_raw->stderr_text();
  ASSERT_TRUE(from_tracker->wait_until_ready(10s)) << from_tracker->stderr_text();
  EXPECT_EQ(from_tracker->ready_fact("vision"), "tracked " + tracker);
  testing::PredictionListener raw_listener(raw_predictions);
  testing::PredictionListener tracked_listener(tracked_predictions);

  // The same positions both ways; a second tracker ("b", other robots' paths) interleaved on
  // the tracker group from the second frame on. (That the tracked predictor takes the raw
  // feed's geometry, in its place among the frames, is tests/predictor/
  // tracked_vision_daemon_test.cpp's: two sockets have no order on the network.)
  for (int f = 0; f < 240; ++f) {
    ASSERT_TRUE(testing::send_to_group(raw, raw_frame(f)));
    ASSERT_TRUE(testing::send_to_group(tracker, tracked_frame(f, "a", 7)));
    if (f > 0) {
      ASSERT_TRUE(testing::send_to_group(tracker, tracked_frame(f, "b", 8)));
    }
    std::this_thread::sleep_for(1ms);
  }
  const auto from_raw_messages = raw_listener.drain(5s);
  const auto from_tracked_messages = tracked_listener.drain(5s);
  ASSERT_TRUE(from_raw_messages && from_tracked_messages);
  ASSERT_GT(from_raw_messages->size(), 200u) << from_raw->stderr_text();
  ASSERT_EQ(from_tracked_messages->size(), from_raw_messages->size())
      << from_tracker->stderr_text();
  for (std::size_t i = 0; i < from_raw_messages->size(); ++i) {
    const auto& a = (*from_raw_messages)[i];
    const auto& b = (*from_tracked_messages)[i];
    ASSERT_EQ(a.t_capture(), b.t_capture());
    ASSERT_EQ(a.robots_size(), 6);
    ASSERT_EQ(b.robots_size(), 6) << b.DebugString();
    // The same formation: the same robots in the same states, at the same positions but for
    // the float rounding of metres (well under a micrometre).
    ASSERT_EQ(a.centroid_cell().x(), b.centroid_cell().x());
    ASSERT_EQ(a.centroid_cell().y(), b.centroid_cell().y());
    for (int r = 0; r < 6; ++r) {
      ASSERT_EQ(a.robots(r).robot_id(), b.robots(r).robot_id());
      ASSERT_EQ(a.robots(r).state_index(), b.robots(r).state_index()) << "message " << i;
      ASSERT_NEAR(a.robots(r).position().x(), b.robots(r).position().x(), 0.001) << i;
      ASSERT_NEAR(a.robots(r).position().y(), b.robots(r).position().y(), 0.001) << i;
    }
    // Predicted alike: the same cells for every robot and step.
    ASSERT_EQ(a.steps_size(), b.steps_size());
    for (int k = 0; k < a.steps_size(); ++k) {
      for (int r = 0; r < a.steps(k).robots_size(); ++r) {
        ASSERT_EQ(a.steps(k).robots(r).state_index(), b.steps(k).robots(r).state_index())
            << "message " << i << " step " << k;
      }
    }
  }
  EXPECT_TRUE(from_tracker->wait_for_stderr("following tracker 'tracker a' (uuid a)", 2s))
      << from_tracker->stderr_text();
  for (auto* process : {from_raw.get(), from_tracker.get()}) {
    process->signal(SIGTERM);
    EXPECT_EQ(process->wait(5s), 0) << process->stderr_text();
  }
  const testing::Status status = testing::last_status(from_tracker->stderr_text());
  EXPECT_EQ(status.at("tracker_frames"), 240u) << from_tracker->stderr_text();
  EXPECT_EQ(status.at("tracker_other_source"), 239u) << from_tracker->stderr_text();
  // The raw feed's packets arrived, but none was taken: a formation per tracked frame.
  EXPECT_EQ(status.at("packets"), 240u) << from_tracker->stderr_text();
  EXPECT_EQ(status.at("formations"), 240u) << from_tracker->stderr_text();
}

}  // namespace
}  // namespace ssl_formation
