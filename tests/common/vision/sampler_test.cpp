#include "ssl_formation/vision/sampler.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
namespace {

// Collects what the sampler hands on.
struct Collector {
  std::vector<FormationSample> samples;
  FormationSampler::SampleHandler handler() {
    return [this](const FormationSample& sample) { samples.push_back(sample); };
  }
  std::size_t transitions() const {
    std::size_t n = 0;
    for (const auto& s : samples) n += s.transitions.size();
    return n;
  }
};

SamplerConfig config_3x2() {
  SamplerConfig config;
  config.grid = Grid(3, 2);
  config.step_s = 2.0;
  return config;
}

DetectionFrameSpec frame(std::uint32_t camera, double t, std::vector<RobotDetection> yellow,
                         std::vector<RobotDetection> blue = {}) {
  DetectionFrameSpec spec;
  spec.camera_id = camera;
  spec.frame_number = static_cast<std::uint32_t>(t * 10);
  spec.t_capture = t;
  spec.yellow = std::move(yellow);
  spec.blue = std::move(blue);
  return spec;
}

TEST(Sampler, OneCameraOneSamplePerStepWithTransitions) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  // Robot 1 walks from cell (0,0) to (1,0) to (2,1); robot 2 stays in (1,1).
  sampler.add(make_detection_packet(frame(0, 100.0, {{1, {-4000, -2000}}, {2, {0, 1000}}})));
  sampler.add(make_detection_packet(frame(0, 102.0, {{1, {0, -2000}}, {2, {0, 1000}}})));
  sampler.add(make_detection_packet(frame(0, 104.0, {{1, {4000, 2000}}, {2, {0, 1000}}})));
  ASSERT_EQ(out.samples.size(), 3u);
  EXPECT_FALSE(out.samples[0].formation.continues_previous);
  EXPECT_TRUE(out.samples[0].transitions.empty());
  EXPECT_DOUBLE_EQ(out.samples[1].formation.time_s, 102.0);
  ASSERT_EQ(out.samples[2].transitions.size(), 2u);
  const Formation& last = out.samples[2].formation;
  const FormationRobot& walker = last.robots[0];
  EXPECT_EQ(walker.robot_id, 1u);
  EXPECT_EQ(walker.cell, (Cell{2, 1}));
  EXPECT_EQ(walker.previous_cell, (Cell{1, 0}));
  EXPECT_EQ(last.centroid_cell, (Cell{2, 1}));  // mean (2000, 1500)
  const StateCodec& codec = sampler.codec();
  EXPECT_EQ(out.samples[2].transitions[0].from, out.samples[1].formation.robots[0].state);
  EXPECT_EQ(codec.decode(out.samples[2].transitions[0].to), (RobotState{{2, 1}, {2, 1}, {1, 0}}));
  EXPECT_EQ(sampler.counters().transitions, 4u);
}

// The handler may start a new stream (the trainer does between log files): the sample it was
// handed then belongs to the old stream, and the next one follows nothing.
TEST(Sampler, ANewStreamStartedByTheHandlerForgetsTheSampleBeingHandled) {
  std::vector<FormationSample> samples;
  FormationSampler* sampler_ptr = nullptr;
  FormationSampler sampler(config_3x2(), [&](const FormationSample& sample) {
    samples.push_back(sample);
    if (samples.size() == 2) sampler_ptr->start_new_stream();
  });
  sampler_ptr = &sampler;
  for (int i = 0; i < 4; ++i) {
    sampler.add(make_detection_packet(frame(0, 100.0 + 2.0 * i, {{1, {-4000.0 + 2000 * i, 0}}})));
  }
  ASSERT_EQ(samples.size(), 4u);
  EXPECT_TRUE(samples[1].formation.continues_previous);
  EXPECT_FALSE(samples[2].formation.continues_previous);
  EXPECT_TRUE(samples[2].transitions.empty());
  EXPECT_TRUE(samples[3].formation.continues_previous);
  EXPECT_EQ(sampler.counters().chain_breaks, 1u);  // the restart, and nothing else
  EXPECT_EQ(sampler.counters().transitions, 2u);
}

TEST(Sampler, TwoCamerasReportingTheSameRobotCountItOnce) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  for (int k = 0; k < 3; ++k) {
    const double t = 10.0 + 2.0 * k;
    // Robot 3 stands in the overlap and both cameras see it, 2 mm apart.
    sampler.add(make_detection_packet(frame(0, t, {{1, {-3000, 0}}, {3, {-10, 500}}})));
    sampler.add(make_detection_packet(frame(1, t, {{2, {3000, 0}}, {3, {-12, 500}}})));
  }
  ASSERT_EQ(out.samples.size(), 3u);
  for (const auto& sample : out.samples) {
    ASSERT_EQ(sample.formation.robots.size(), 3u);
    EXPECT_NEAR(sample.formation.robots[2].feed_position.x, -11.0, 1e-9);
  }
  EXPECT_EQ(out.transitions(), 6u);  // 3 robots x 2 transitions, none counted twice
}

TEST(Sampler, ARobotThatVanishesRestartsWithVelocityZero) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  sampler.add(make_detection_packet(frame(0, 0.0, {{1, {-4000, -2000}}, {2, {0, 1000}}})));
  sampler.add(make_detection_packet(frame(0, 2.0, {{2, {0, 1000}}})));  // robot 1 gone
  sampler.add(make_detection_packet(frame(0, 4.0, {{1, {4000, 2000}}, {2, {0, 1000}}})));
  ASSERT_EQ(out.samples.size(), 3u);
  ASSERT_EQ(out.samples[2].transitions.size(), 1u);
  EXPECT_EQ(out.samples[2].transitions[0].robot_id, 2u);
  const FormationRobot* back = out.samples[2].formation.find(1);
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->previous_cell, back->cell);
}

TEST(Sampler, AGapOverOneAndAHalfStepsCountsNoTransitions) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  sampler.add(make_detection_packet(frame(0, 0.0, {{1, {-4000, -2000}}})));
  sampler.add(make_detection_packet(frame(0, 2.0, {{1, {-4000, -2000}}})));
  sampler.add(make_detection_packet(frame(0, 6.0, {{1, {0, 0}}})));  // 4 s later
  sampler.add(make_detection_packet(frame(0, 8.0, {{1, {4000, 0}}})));
  ASSERT_EQ(out.samples.size(), 4u);
  EXPECT_EQ(out.samples[1].transitions.size(), 1u);
  EXPECT_TRUE(out.samples[2].transitions.empty());
  EXPECT_FALSE(out.samples[2].formation.continues_previous);
  EXPECT_EQ(out.samples[2].formation.robots[0].previous_cell, (Cell{1, 1}));
  EXPECT_EQ(out.samples[3].transitions.size(), 1u);
  EXPECT_EQ(sampler.counters().chain_breaks, 1u);
}

TEST(Sampler, AGeometryPacketChangesTheFieldSize) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  // x = 1800 mm is in the last third of a 9 m field (thirds end at +-1500) and in the middle
  // third of a 12 m field (thirds end at +-2000).
  sampler.add(make_detection_packet(frame(0, 0.0, {{1, {1800, 0}}})));
  sampler.add(make_detection_packet(frame(0, 2.0, {{1, {1800, 0}}})));
  sampler.add(make_geometry_packet(FieldSize{12000, 9000}));
  EXPECT_EQ(sampler.field(), (FieldSize{12000, 9000}));
  sampler.add(make_detection_packet(frame(0, 4.0, {{1, {1800, 0}}})));
  sampler.add(make_detection_packet(frame(0, 6.0, {{1, {1800, 0}}})));
  ASSERT_EQ(out.samples.size(), 4u);
  EXPECT_EQ(out.samples[1].formation.robots[0].cell, (Cell{2, 1}));
  EXPECT_EQ(out.samples[1].transitions.size(), 1u);
  EXPECT_EQ(out.samples[2].formation.robots[0].cell, (Cell{1, 1}));
  EXPECT_TRUE(out.samples[2].transitions.empty());  // no transition across a field change
  EXPECT_EQ(out.samples[2].formation.robots[0].previous_cell, (Cell{1, 1}));
  EXPECT_EQ(out.samples[3].transitions.size(), 1u);
  EXPECT_EQ(sampler.counters().field_changes, 1u);
}

TEST(Sampler, FieldChangeWithGeometryInsideTheDetectionWrapper) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  SSL_WrapperPacket packet = make_detection_packet(frame(0, 0.0, {{1, {1800, 0}}}));
  fill_geometry(*packet.mutable_geometry(), FieldSize{12000, 9000});
  sampler.add(packet);
  sampler.add(make_detection_packet(frame(0, 2.0, {{1, {1800, 0}}})));
  ASSERT_EQ(out.samples.size(), 2u);
  EXPECT_EQ(out.samples[0].formation.robots[0].cell, (Cell{1, 1}));
  EXPECT_EQ(out.samples[1].transitions.size(), 1u);
}

TEST(Sampler, OpponentColourSelectsTheTeam) {
  for (const TeamColor color : {TeamColor::yellow, TeamColor::blue}) {
    Collector out;
    SamplerConfig config = config_3x2();
    config.opponent_color = color;
    FormationSampler sampler(config, out.handler());
    for (double t : {0.0, 2.0}) {
      sampler.add(
          make_detection_packet(frame(0, t, {{1, {-4000, 0}}, {2, {-3000, 0}}}, {{7, {4000, 0}}})));
    }
    ASSERT_EQ(out.samples.size(), 2u);
    const auto& robots = out.samples[1].formation.robots;
    if (color == TeamColor::yellow) {
      ASSERT_EQ(robots.size(), 2u);
      EXPECT_EQ(robots[0].robot_id, 1u);
    } else {
      ASSERT_EQ(robots.size(), 1u);
      EXPECT_EQ(robots[0].robot_id, 7u);
    }
  }
}

TEST(Sampler, OpponentAttackingMinusXIsRotated) {
  Collector out;
  SamplerConfig config = config_3x2();
  config.opponent_attacks = AttackDirection::negative_x;
  FormationSampler sampler(config, out.handler());
  sampler.add(make_detection_packet(frame(0, 0.0, {{1, {-4000, -2000}}})));
  sampler.add(make_detection_packet(frame(0, 2.0, {{1, {-4000, -2000}}})));
  ASSERT_EQ(out.samples.size(), 2u);
  const FormationRobot& robot = out.samples[1].formation.robots[0];
  EXPECT_EQ(robot.cell, (Cell{2, 1}));  // deep in the -x half = deep in attack
  EXPECT_EQ(robot.feed_position, (Point{-4000, -2000}));
  EXPECT_EQ(robot.position, (Point{4000, 2000}));
}

TEST(Sampler, OutOfOrderPacketsNeitherDuplicateNorReorderSamples) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  sampler.add(make_detection_packet(frame(0, 0.0, {{1, {-4000, 0}}})));
  sampler.add(make_detection_packet(frame(0, 4.0, {{1, {4000, 0}}})));
  sampler.add(make_detection_packet(frame(0, 2.0, {{1, {0, 0}}})));  // arrives late
  sampler.add(make_detection_packet(frame(0, 6.0, {{1, {4000, 0}}})));
  ASSERT_EQ(out.samples.size(), 3u);
  EXPECT_DOUBLE_EQ(out.samples[0].formation.time_s, 0.0);
  EXPECT_DOUBLE_EQ(out.samples[1].formation.time_s, 4.0);
  EXPECT_DOUBLE_EQ(out.samples[2].formation.time_s, 6.0);
  EXPECT_TRUE(out.samples[1].transitions.empty());  // 0 -> 4 is a gap
  EXPECT_EQ(out.samples[2].transitions.size(), 1u);
  EXPECT_EQ(sampler.counters().frames_late, 1u);
}

TEST(Sampler, CamerasSlightlyOutOfOrderWithinAStep) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  for (int k = 0; k < 4; ++k) {
    const double t = 2.0 * k;
    // Camera 1's frame of each instant arrives before camera 0's.
    sampler.add(make_detection_packet(frame(1, t, {{2, {3000, 0}}})));
    sampler.add(make_detection_packet(frame(0, t, {{1, {-3000, 0}}})));
  }
  ASSERT_GE(out.samples.size(), 3u);
  for (const auto& sample : out.samples) EXPECT_EQ(sample.formation.robots.size(), 2u);
  EXPECT_EQ(sampler.counters().frames_late, 0u);
}

TEST(Sampler, ADroppedCameraFrameHandsTheSampleOnWithoutThatCamerasRobots) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  for (int k = 0; k < 4; ++k) {
    const double t = 2.0 * k;
    sampler.add(make_detection_packet(frame(0, t, {{1, {-3000, 0}}})));
    if (k != 2) sampler.add(make_detection_packet(frame(1, t, {{2, {3000, 0}}})));
  }
  ASSERT_GE(out.samples.size(), 3u);
  EXPECT_EQ(out.samples[2].formation.robots.size(), 1u);  // robot 2 was not seen at t = 4
  EXPECT_EQ(sampler.counters().samples_forced, 1u);
}

TEST(Sampler, BadInputIsRejectedWithACountedReason) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  TransitionTable table(Grid(3, 2));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  sampler.add(make_detection_packet(
      frame(0, 0.0, {{1, {nan, 0}}, {2, {0, inf}}, {1001, {0, 0}}, {3, {1e30, 0}}})));
  sampler.add(make_detection_packet(frame(0, 1.0, {})));  // an empty frame
  sampler.add(make_geometry_packet(FieldSize{0, 6000}));
  sampler.add(make_geometry_packet(FieldSize{9000, -6000}));
  SSL_WrapperPacket bad_time = make_detection_packet(frame(0, 0.0, {{1, {0, 0}}}));
  bad_time.mutable_detection()->set_t_capture(nan);
  sampler.add(bad_time);
  SSL_WrapperPacket no_id = make_detection_packet(frame(0, 1.5, {{4, {0, 0}}}));
  no_id.mutable_detection()->mutable_robots_yellow(0)->clear_robot_id();
  sampler.add(no_id);
  SSL_WrapperPacket bad_camera = make_detection_packet(frame(0, 1.5, {{5, {0, 0}}}));
  bad_camera.mutable_detection()->set_camera_id(4000000000u);
  sampler.add(bad_camera);
  for (const auto& sample : out.samples) {
    for (const auto& t : sample.transitions) table.add(t.from, t.to);
  }

  const SamplerCounters& c = sampler.counters();
  EXPECT_EQ(c.robots_non_finite, 2u);
  EXPECT_EQ(c.robots_bad_id, 2u);  // id 1001 and the missing id
  EXPECT_EQ(c.robots_out_of_range, 1u);
  // The empty frame, the frame whose robots were all rejected, the frame of the id-less robot.
  EXPECT_EQ(c.frames_without_opponent, 3u);
  EXPECT_EQ(c.geometry_invalid, 2u);
  EXPECT_EQ(c.frames_bad_time, 1u);
  EXPECT_EQ(c.frames_bad_camera, 1u);
  EXPECT_EQ(c.robots_accepted, 0u);
  EXPECT_EQ(sampler.field(), (FieldSize{9000, 6000}));
  EXPECT_EQ(c.transitions, 0u);
  EXPECT_EQ(table.transitions(), 0u);
  EXPECT_TRUE(out.samples.empty());
}

TEST(Sampler, BadRobotsDoNotDisturbGoodOnes) {
  Collector clean_out;
  Collector dirty_out;
  FormationSampler clean(config_3x2(), clean_out.handler());
  FormationSampler dirty(config_3x2(), dirty_out.handler());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 5; ++k) {
    const double t = 2.0 * k;
    std::vector<RobotDetection> good{{1, {-4000.0 + 2000 * k, 0}}, {2, {0, 1000}}};
    clean.add(make_detection_packet(frame(0, t, good)));
    auto noisy = good;
    noisy.push_back({3, {nan, nan}});
    noisy.push_back({5000, {0, 0}});
    dirty.add(make_detection_packet(frame(0, t, noisy)));
  }
  ASSERT_EQ(clean_out.samples.size(), dirty_out.samples.size());
  for (std::size_t i = 0; i < clean_out.samples.size(); ++i) {
    EXPECT_EQ(clean_out.samples[i].transitions, dirty_out.samples[i].transitions);
  }
}

TEST(Sampler, ClockJumpingBackwardsStartsOver) {
  Collector out;
  FormationSampler sampler(config_3x2(), out.handler());
  sampler.add(make_detection_packet(frame(0, 1000.0, {{1, {0, 0}}})));
  sampler.add(make_detection_packet(frame(0, 1002.0, {{1, {0, 0}}})));
  sampler.add(make_detection_packet(frame(0, 3.0, {{1, {0, 0}}})));  // simulator restarted
  sampler.add(make_detection_packet(frame(0, 5.0, {{1, {0, 0}}})));
  sampler.add(make_detection_packet(frame(0, 7.0, {{1, {0, 0}}})));
  EXPECT_EQ(sampler.counters().clock_resets, 1u);
  ASSERT_EQ(out.samples.size(), 5u);
  EXPECT_DOUBLE_EQ(out.samples[2].formation.time_s, 3.0);
  EXPECT_TRUE(out.samples[2].transitions.empty());
  EXPECT_EQ(out.samples[3].transitions.size(), 1u);
}

TEST(Sampler, RejectsANonPositiveStep) {
  SamplerConfig config = config_3x2();
  config.step_s = 0.0;
  EXPECT_THROW(FormationSampler(config, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace ssl_formation
