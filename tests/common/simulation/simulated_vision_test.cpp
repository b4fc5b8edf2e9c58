#include "ssl_formation/simulation/simulated_vision.hpp"

#include <gtest/gtest.h>

#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation::simulation {
namespace {

TEST(SimulatedVision, NinetyPercentOfFormationsComeFromPlays) {
  SimulationConfig config;
  config.seed = 2024;
  SimulatedVision vision(config);
  int cycles = 0;
  int random_formations = 0;
  int play_formations = 0;
  std::array<int, play_count> plays_started{};
  while (cycles < 10000) {
    const SimulatedFormation f = vision.next();
    if (f.source == FormationSource::random) {
      ++random_formations;
      ++cycles;
    } else {
      ++play_formations;
      if (f.play_step == 0) {
        ++plays_started[static_cast<std::size_t>(f.play)];
      }
      if (f.play_step == formations_per_play - 1) ++cycles;
    }
  }
  const double total = random_formations + play_formations;
  EXPECT_NEAR(play_formations / total, 0.90, 0.02);
  EXPECT_NEAR(random_formations / total, 0.10, 0.02);
  for (const int started : plays_started) EXPECT_NEAR(started / 10000.0, 0.25, 0.02);
}

TEST(SimulatedVision, PlaysRunTheirThreeFormationsInOrder) {
  SimulatedVision vision(SimulationConfig{});
  for (int i = 0; i < 300; ++i) {
    const SimulatedFormation f = vision.next();
    if (f.source != FormationSource::play || f.play_step != 0) continue;
    const SimulatedFormation second = vision.next();
    const SimulatedFormation third = vision.next();
    EXPECT_EQ(second.play, f.play);
    EXPECT_EQ(second.play_step, 1);
    EXPECT_EQ(third.play_step, 2);
    EXPECT_EQ(third.opponent[5].x, play_formation(f.play, 2)[5].x);
  }
}

TEST(SimulatedVision, PacketsAreValidAndRoundTripThroughTheSchema) {
  SimulationConfig config;
  config.cameras = 4;
  config.jitter_mm = 10.0;
  config.opponent_color = TeamColor::blue;
  SimulatedVision vision(config);
  int geometry = 0;
  for (int i = 0; i < 50; ++i) {
    const SimulatedFormation f = vision.next();
    for (const SSL_WrapperPacket& packet : f.packets) {
      ASSERT_TRUE(packet.IsInitialized()) << packet.InitializationErrorString();
      std::string bytes;
      ASSERT_TRUE(packet.SerializeToString(&bytes));
      SSL_WrapperPacket decoded;
      ASSERT_TRUE(decoded.ParseFromString(bytes));
      EXPECT_EQ(decoded.SerializeAsString(), bytes);
      if (decoded.has_geometry()) {
        ++geometry;
        EXPECT_EQ(decoded.geometry().field().field_length(), 9000);
      }
      if (decoded.has_detection()) {
        EXPECT_DOUBLE_EQ(decoded.detection().t_capture(), f.t_capture);
        EXPECT_LT(decoded.detection().camera_id(), 4u);
      }
    }
  }
  EXPECT_EQ(geometry, 25);  // one every 3 s of data time at a 2 s step: every other formation
}

TEST(SimulatedVision, OurTeamAndTheBallAreInTheFrames) {
  SimulatedVision vision(SimulationConfig{});
  const SimulatedFormation f = vision.next();
  const SSL_DetectionFrame& frame = f.packets.back().detection();
  EXPECT_EQ(frame.robots_yellow_size(), robots_per_team);
  EXPECT_EQ(frame.robots_blue_size(), robots_per_team);
  EXPECT_EQ(frame.balls_size(), 1);
}

// Four cameras with overlap sample back to exactly the formations of one camera.
TEST(SimulatedVision, FourCamerasSampleBackToTheSameFormationsAsOne) {
  std::vector<std::vector<Transition>> one_camera;
  std::vector<std::vector<Transition>> four_cameras;
  std::vector<std::size_t> robots_seen;
  for (const int cameras : {1, 4}) {
    SimulationConfig config;
    config.seed = 77;
    config.cameras = cameras;
    config.camera_overlap_mm = 400.0;
    SimulatedVision vision(config);
    SamplerConfig sampler_config;
    auto& out = cameras == 1 ? one_camera : four_cameras;
    FormationSampler sampler(sampler_config, [&](const FormationSample& s) {
      out.push_back(s.transitions);
      if (cameras == 4) robots_seen.push_back(s.formation.robots.size());
    });
    int overlap_reports = 0;
    for (int i = 0; i < 400; ++i) {
      const SimulatedFormation f = vision.next();
      int detections = 0;
      for (const auto& packet : f.packets) {
        if (packet.has_detection()) detections += packet.detection().robots_yellow_size();
        sampler.add(packet);
      }
      overlap_reports += detections - robots_per_team;
    }
    if (cameras == 4) {
      EXPECT_GT(overlap_reports, 0) << "no robot ever stood in an overlap";
    }
  }
  EXPECT_EQ(one_camera.size(), 400u);
  EXPECT_EQ(one_camera, four_cameras);
  for (const std::size_t n : robots_seen) EXPECT_EQ(n, 6u);
}

TEST(SimulatedVision, SameSeedSamePackets) {
  SimulationConfig config;
  config.seed = 5;
  config.jitter_mm = 20;
  config.cameras = 2;
  config.drop_rate = 0.1;
  SimulatedVision a(config);
  SimulatedVision b(config);
  for (int i = 0; i < 100; ++i) {
    const auto fa = a.next();
    const auto fb = b.next();
    ASSERT_EQ(fa.packets.size(), fb.packets.size());
    for (std::size_t p = 0; p < fa.packets.size(); ++p) {
      ASSERT_EQ(fa.packets[p].SerializeAsString(), fb.packets[p].SerializeAsString());
    }
  }
}

}  // namespace
}  // namespace ssl_formation::simulation
