// Tracked vision as the predictor's input, driven in-process in the order a feed gives it: the
// raw feed's geometry first, then a tracker's frames (in metres) of the positions SSL-Vision's raw
// detections report, with a second tracker interleaved. The tracked predictor takes only the
// geometry from the raw feed and predicts exactly what the raw one does.

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include "moving_robots.hpp"
#include "recorded_output.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/predictor/predictor_daemon.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "tracked_frames.hpp"

namespace ssl_formation::predictor {
namespace {

constexpr double start_s = 700.0;

VisionFrame raw_frame(int f) {
  VisionFrame frame;
  to_vision_frame(testing::raw_frame_of_six(f, start_s, 7), frame);
  return frame;
}
std::string tracked_frame(int f, const std::string& uuid, int seed) {
  return testing::tracked_frame_of_six(f, start_s, uuid, seed);
}

TEST(TrackedVisionDaemon, ATrackersFramesGiveTheRawFeedsPredictionsWithItsGeometry) {
  testing::ScratchDir dir;
  const auto table = dir.path() / "t.table";
  {
    testing::MovingRobots moving;
    moving.seed = 7;
    moving.seconds = 30.0;
    Training training(sampler_config_for(ModelKind::motion), TransitionTable(Grid(3, 2)), 0,
                      MotionTable(ModelSettings{}.motion_config()));
    for (const auto& packet : testing::moving_robots_packets(moving)) training.add(packet);
    ASSERT_TRUE(save_table(table, training.stored_table()));
  }
  PredictorOptions raw_options;
  raw_options.table = table.string();
  raw_options.quiet = true;
  PredictorOptions tracked_options = raw_options;
  tracked_options.network.vision_source = "tracked";

  boost::asio::io_context io;
  app::ManualClock clock;
  testing::RecordedOutput raw_out;
  testing::RecordedOutput tracked_out;
  PredictorDaemon raw(io, raw_options, prediction_config(raw_options), clock, raw_out);
  PredictorDaemon tracked(io, tracked_options, prediction_config(tracked_options), clock,
                          tracked_out);
  raw.start();
  tracked.start();
  VisionFrame geometry;
  to_vision_frame(make_geometry_packet(FieldSize{12000.0, 9000.0}), geometry);
  for (PredictorDaemon* daemon : {&raw, &tracked}) {
    daemon->on_event(MatchEvent::vision(geometry, clock.steady_s()));
  }
  for (int f = 0; f < 240; ++f) {
    clock.advance(1.0 / 60.0);
    const VisionFrame frame = raw_frame(f);
    raw.on_event(MatchEvent::vision(frame, clock.steady_s()));
    // The tracked predictor hears the raw feed too, and takes none of its detections.
    tracked.on_event(MatchEvent::vision(frame, clock.steady_s()));
    const std::string a = tracked_frame(f, "a", 7);
    tracked.on_event(MatchEvent::tracked_vision(a, clock.steady_s()));
    if (f > 0) {
      const std::string b = tracked_frame(f, "b", 8);
      tracked.on_event(MatchEvent::tracked_vision(b, clock.steady_s()));
    }
  }
  const auto from_raw = raw_out.messages();
  const auto from_tracked = tracked_out.messages();
  ASSERT_EQ(from_raw.size(), 240u);
  ASSERT_EQ(from_tracked.size(), from_raw.size());
  for (std::size_t i = 0; i < from_raw.size(); ++i) {
    const auto& a = from_raw[i];
    const auto& b = from_tracked[i];
    ASSERT_EQ(a.t_capture(), b.t_capture());
    ASSERT_EQ(b.robots_size(), 6);
    ASSERT_EQ(a.centroid_cell().x(), b.centroid_cell().x());
    for (int r = 0; r < 6; ++r) {
      ASSERT_EQ(a.robots(r).state_index(), b.robots(r).state_index()) << "message " << i;
      // The same positions but for the float rounding of metres (well under a micrometre).
      ASSERT_NEAR(a.robots(r).position().x(), b.robots(r).position().x(), 0.001) << i;
    }
    for (int k = 0; k < a.steps_size(); ++k) {
      for (int r = 0; r < a.steps(k).robots_size(); ++r) {
        ASSERT_EQ(a.steps(k).robots(r).state_index(), b.steps(k).robots(r).state_index());
        // The rounding of metres, through the robot's velocity: well under a millimetre.
        ASSERT_NEAR(a.steps(k).robots(r).position().x(), b.steps(k).robots(r).position().x(), 0.5);
      }
    }
  }
  const PredictionPipeline& pipeline = tracked.pipeline();
  EXPECT_EQ(pipeline.sampler().field(), (FieldSize{12000.0, 9000.0}));
  EXPECT_EQ(pipeline.front_end().tracked_vision().source_uuid(), "a");
  EXPECT_EQ(pipeline.front_end().tracked_vision().counters().frames, 240u);
  EXPECT_EQ(pipeline.front_end().tracked_vision().counters().other_source, 239u);
}

}  // namespace
}  // namespace ssl_formation::predictor
