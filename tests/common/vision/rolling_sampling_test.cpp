// Frame (rolling) sampling: a formation at every frame instant, each robot's previous cell taken
// from the sample step_s earlier, no previous across a gap; and real logs' single camera id whose
// packets each cover half the field.

#include <gtest/gtest.h>

#include <cmath>

#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
namespace {

struct Collector {
  std::vector<FormationSample> samples;
  FormationSampler::SampleHandler handler() {
    return [this](const FormationSample& sample) { samples.push_back(sample); };
  }
  const FormationSample* at(double time_s) const {
    for (const auto& s : samples) {
      if (std::abs(s.formation.time_s - time_s) < 1e-6) return &s;
    }
    return nullptr;
  }
};

SamplerConfig rolling(double step_s) {
  SamplerConfig config;
  config.grid = Grid(3, 2);
  config.step_s = step_s;
  config.sampling = Sampling::frame;
  return config;
}

SSL_WrapperPacket frame_at(std::uint32_t number, double t, std::vector<RobotDetection> yellow,
                           std::uint32_t camera = 0) {
  DetectionFrameSpec spec;
  spec.camera_id = camera;
  spec.frame_number = number;
  spec.t_capture = t;
  spec.yellow = std::move(yellow);
  return make_detection_packet(spec);
}

// Robot 1 walks along x at 1 m/s through the three columns of a 9 m field; robot 2 stays put.
double walker_x(double t) { return -4350.0 + 1000.0 * t; }  // never on a cell boundary

TEST(RollingSampling, AFormationAtEveryFrameWithThePreviousCellFromAStepEarlier) {
  Collector out;
  FormationSampler sampler(rolling(1.0), out.handler());
  const double t0 = 50.0;
  // 10 frames a second for 9 s.
  for (std::uint32_t i = 0; i <= 90; ++i) {
    const double t = 0.1 * i;
    sampler.add(frame_at(i, t0 + t, {{1, {walker_x(t), -1000}}, {2, {0, 1000}}}));
  }
  // Every frame is an instant handed on (one camera: each frame completes its own).
  ASSERT_EQ(out.samples.size(), 91u);
  EXPECT_EQ(sampler.counters().samples, 91u);
  const Grid& grid = sampler.codec().grid();
  const FieldSize field;
  for (const FormationSample& sample : out.samples) {
    const double t = sample.formation.time_s - t0;
    const FormationRobot* walker = sample.formation.find(1);
    ASSERT_NE(walker, nullptr);
    EXPECT_EQ(walker->cell, grid.cell_of({walker_x(t), -1000}, field)) << t;
    if (t < 1.0 - 0.05) {
      // Nothing a step earlier yet: velocity 0, no transition.
      EXPECT_FALSE(sample.formation.continues_previous) << t;
      EXPECT_EQ(walker->previous_cell, walker->cell) << t;
      EXPECT_TRUE(sample.transitions.empty()) << t;
      continue;
    }
    // The previous cell is the cell one step (1 s) earlier, and each robot's transition starts
    // at its state in that sample.
    EXPECT_TRUE(sample.formation.continues_previous) << t;
    EXPECT_EQ(walker->previous_cell, grid.cell_of({walker_x(t - 1.0), -1000}, field)) << t;
    const FormationSample* before = out.at(sample.formation.time_s - 1.0);
    ASSERT_NE(before, nullptr) << t;
    ASSERT_EQ(sample.transitions.size(), 2u) << t;
    for (const Transition& transition : sample.transitions) {
      EXPECT_EQ(transition.from, before->formation.find(transition.robot_id)->state) << t;
      EXPECT_EQ(transition.to, sample.formation.find(transition.robot_id)->state) << t;
    }
  }
  // 81 instants (1.0 to 9.0 s) with a sample a step before, two robots each.
  EXPECT_EQ(sampler.counters().transitions, 162u);
}

TEST(RollingSampling, NoPreviousAcrossAGapNorForARobotNotSeenAStepEarlier) {
  Collector out;
  FormationSampler sampler(rolling(1.0), out.handler());
  std::uint32_t number = 0;
  // 3 s of frames, then nothing for 1.5 s (more than a step), then 3 s more. Robot 3 appears at
  // 1.5 s.
  std::vector<double> times;
  for (int i = 0; i <= 30; ++i) times.push_back(0.1 * i);
  for (int i = 0; i <= 30; ++i) times.push_back(4.5 + 0.1 * i);
  for (const double t : times) {
    std::vector<RobotDetection> robots{{1, {walker_x(t), -1000}}};
    if (t >= 1.5 - 1e-9) robots.push_back({3, {2000, 2000}});
    sampler.add(frame_at(number++, 100.0 + t, robots));
  }
  ASSERT_EQ(out.samples.size(), times.size());
  for (const FormationSample& sample : out.samples) {
    const double t = sample.formation.time_s - 100.0;
    // A step earlier there is a sample only 1-3 s into each part: never across the gap.
    const double since_start = t > 3.5 ? t - 4.5 : t;
    const bool has_previous = since_start > 1.0 - 0.05;
    EXPECT_EQ(sample.formation.continues_previous, has_previous) << t;
    const FormationRobot* late = sample.formation.find(3);
    std::size_t transitions_of_3 = 0;
    for (const Transition& tr : sample.transitions) transitions_of_3 += tr.robot_id == 3;
    if (late && has_previous) {
      // Robot 3 was not seen a step before 1.5-2.4 s: it starts with velocity 0, unchained.
      const bool seen_a_step_before = t > 3.5 || t - 1.0 >= 1.5 - 0.05;
      EXPECT_EQ(transitions_of_3, seen_a_step_before ? 1u : 0u) << t;
      if (!seen_a_step_before) {
        EXPECT_EQ(late->previous_cell, late->cell) << t;
      }
    } else {
      EXPECT_EQ(transitions_of_3, 0u) << t;
    }
  }
  EXPECT_EQ(sampler.counters().chain_breaks, 1u);  // the gap
}

TEST(RollingSampling, AFeedOfOneFrameAStepChainsLikeStepSampling) {
  // The paper's simulated opponent sends one frame per formation, a step apart: frame sampling
  // then counts the same transitions as step sampling.
  for (const Sampling sampling : {Sampling::frame, Sampling::step}) {
    SamplerConfig config = rolling(2.0);
    config.sampling = sampling;
    Collector out;
    FormationSampler sampler(config, out.handler());
    for (std::uint32_t i = 0; i < 20; ++i) {
      sampler.add(frame_at(i, 2.0 * i, {{1, {walker_x(0.2 * i), -1000}}, {2, {0, 1000}}}));
    }
    EXPECT_EQ(sampler.counters().transitions, 2u * 19u) << to_string(sampling);
  }
}

TEST(RollingSampling, AStepSamplerOfTheSameStreamIsTheStepSamplingOfOld) {
  // --sampling step is the default and samples exactly as before: one per step.
  SamplerConfig config = rolling(1.0);
  config.sampling = Sampling::step;
  Collector out;
  FormationSampler sampler(config, out.handler());
  for (std::uint32_t i = 0; i <= 50; ++i) {
    sampler.add(frame_at(i, 0.1 * i, {{1, {walker_x(0.1 * i), -1000}}}));
  }
  ASSERT_EQ(out.samples.size(), 6u);
  for (std::size_t k = 0; k < out.samples.size(); ++k) {
    EXPECT_NEAR(out.samples[k].formation.time_s, static_cast<double>(k), 1e-9);
    EXPECT_EQ(out.samples[k].transitions.size(), k == 0 ? 0u : 1u);
  }
  EXPECT_EQ(SamplerConfig{}.sampling, Sampling::step);
}

// Real Division A logs: every packet has camera id 0, but each covers only half the field.
std::vector<SSL_WrapperPacket> half_field_packets(double seconds) {
  std::vector<SSL_WrapperPacket> packets;
  std::uint32_t number = 0;
  for (double t = 0.0; t < seconds; t += 1.0 / 45.0) {
    std::vector<RobotDetection> left;
    std::vector<RobotDetection> right;
    for (std::uint32_t id = 0; id < 11; ++id) {
      const Point p{-5000.0 + 1000.0 * id, 500.0 * std::sin(t + id)};
      (p.x < 0 ? left : right).push_back({id, p});
    }
    packets.push_back(frame_at(number++, 10.0 + t, left));
    packets.push_back(frame_at(number++, 10.0 + t + 0.011, right));
  }
  return packets;
}

TEST(RollingSampling, OneCameraIdWhosePacketsEachCoverHalfTheFieldSamplesEveryRobot) {
  for (const Sampling sampling : {Sampling::frame, Sampling::step}) {
    SCOPED_TRACE(std::string(to_string(sampling)));
    SamplerConfig config = rolling(0.5);
    config.sampling = sampling;
    config.field = FieldSize{12000, 9000};
    Collector out;
    FormationSampler sampler(config, out.handler());
    for (const auto& packet : half_field_packets(4.0)) sampler.add(packet);
    ASSERT_GT(out.samples.size(), sampling == Sampling::frame ? 300u : 6u);
    // The very first sample holds only the half seen before the second packet; from then on
    // every sample holds all 11 robots.
    for (const FormationSample& sample : out.samples) {
      if (sample.formation.time_s < 10.0 + 0.005) continue;
      ASSERT_EQ(sample.formation.robots.size(), 11u) << sample.formation.time_s;
    }
  }
}

TEST(RollingSampling, ARobotCarriedOverFromTheOtherHalfIsNotObservedAndCountsNoTransition) {
  Collector out;
  SamplerConfig config = rolling(0.5);
  config.field = FieldSize{12000, 9000};
  FormationSampler sampler(config, out.handler());
  for (const auto& packet : half_field_packets(4.0)) sampler.add(packet);
  std::size_t checked = 0;
  for (const FormationSample& sample : out.samples) {
    if (sample.formation.time_s < 11.0) continue;  // a step of history for every robot
    // A packet of the left half (ids 0-4 stand at x < 0) is observed there, the right half
    // is carried over from the packet before, and the other way round.
    const bool left_packet = sample.formation.frame_number % 2 == 0;
    std::vector<std::uint32_t> observed;
    for (const FormationRobot& robot : sample.formation.robots) {
      EXPECT_EQ(robot.observed, (robot.robot_id < 5) == left_packet)
          << robot.robot_id << " at " << sample.formation.time_s;
      if (robot.observed) observed.push_back(robot.robot_id);
    }
    // The paper's counts come from the observed robots only: the others' transition was
    // counted at the instant of their own packet.
    std::vector<std::uint32_t> counted;
    for (const Transition& t : sample.transitions) counted.push_back(t.robot_id);
    EXPECT_EQ(counted, observed) << sample.formation.time_s;
    ++checked;
  }
  EXPECT_GT(checked, 200u);
}

// Half of every instant's robots are carried over from the packet before, and keep the cell they
// had there; a new field size in between must not leave them with a cell of the old field.
TEST(RollingSampling, ACarriedOverRobotsCellIsItsPositionsOnTheFieldOfItsInstant) {
  for (const Sampling sampling : {Sampling::frame, Sampling::step}) {
    SCOPED_TRACE(std::string(to_string(sampling)));
    SamplerConfig config = rolling(0.5);
    config.sampling = sampling;
    config.grid = Grid(12, 9);
    config.field = FieldSize{12000, 9000};
    const FormationSampler* sampler_seen = nullptr;
    std::size_t robots_checked = 0;
    std::size_t carried_checked = 0;
    FormationSampler sampler(config, [&](const FormationSample& sample) {
      for (const FormationRobot& robot : sample.formation.robots) {
        EXPECT_EQ(robot.cell, config.grid.cell_of(robot.position, sampler_seen->field()))
            << robot.robot_id << " at " << sample.formation.time_s;
        ++robots_checked;
        if (!robot.observed) ++carried_checked;
      }
    });
    sampler_seen = &sampler;
    const std::vector<SSL_WrapperPacket> packets = half_field_packets(4.0);
    for (std::size_t i = 0; i < packets.size(); ++i) {
      // A smaller field from the middle on, between a left packet and a right one: the right
      // half's robots are carried over into the left packet's instant after it.
      if (i == packets.size() / 4 * 2) {  // a left packet: they come first of each pair
        SSL_WrapperPacket geometry;
        fill_geometry(*geometry.mutable_geometry(), FieldSize{9000, 6000});
        sampler.add(geometry);
      }
      sampler.add(packets[i]);
    }
    EXPECT_EQ(sampler.field(), (FieldSize{9000, 6000}));
    EXPECT_GT(robots_checked, sampling == Sampling::frame ? 2000u : 50u);
    EXPECT_GT(carried_checked, sampling == Sampling::frame ? 1000u : 0u);
  }
}

TEST(RollingSampling, ParsesAndNamesTheModes) {
  EXPECT_EQ(parse_sampling("frame"), Sampling::frame);
  EXPECT_EQ(parse_sampling("step"), Sampling::step);
  EXPECT_FALSE(parse_sampling("every"));
  EXPECT_EQ(to_string(Sampling::frame), "frame");
  SamplerConfig config;
  config.sampling = Sampling::frame;
  EXPECT_DOUBLE_EQ(config.robot_fresh_window_s(), 0.1);
  EXPECT_DOUBLE_EQ(config.clock_config().interval_s(), 0.001);
  EXPECT_DOUBLE_EQ(config.clock_config().clock_reset_window_s(), 4.0);
}

}  // namespace
}  // namespace ssl_formation
