// The sampler on real grSim vision: 4 cameras with overlap, geometry inside the detection
// wrappers, the simulator's clock (tests/data/README.md).

#include <gtest/gtest.h>

#include <map>
#include <set>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation {
namespace {

const std::filesystem::path grsim_log =
    std::filesystem::path(SSLF_TEST_DATA_DIR) / "grsim-4cam-11v11-idle.log.gz";

class GrsimSampling : public ::testing::TestWithParam<TeamColor> {};

TEST_P(GrsimSampling, EverySampleHoldsElevenRobotsAtTheirReportedPositions) {
  const TeamColor color = GetParam();
  const auto read = read_vision_log(grsim_log);
  ASSERT_TRUE(read) << read.error().message;
  const LogVisionPackets& log = *read;
  ASSERT_FALSE(log.stopped_early) << log.stopped_early->message;
  ASSERT_EQ(log.packets.size(), 2353u);

  // Where grSim puts each robot (they stand still; a robot in an overlap is in two cameras).
  std::map<std::uint32_t, Point> reported;
  std::set<std::uint32_t> cameras;
  for (const SSL_WrapperPacket& packet : log.packets) {
    if (!packet.has_detection()) continue;
    cameras.insert(packet.detection().camera_id());
    const auto& robots = color == TeamColor::yellow ? packet.detection().robots_yellow()
                                                    : packet.detection().robots_blue();
    for (const auto& robot : robots)
      reported.emplace(robot.robot_id(), Point{robot.x(), robot.y()});
  }
  ASSERT_EQ(cameras.size(), 4u);
  ASSERT_EQ(reported.size(), 11u);

  SamplerConfig config;
  config.opponent_color = color;
  config.grid = Grid(12, 9);
  std::vector<FormationSample> samples;
  FormationSampler sampler(config, [&](const FormationSample& s) { samples.push_back(s); });
  for (const SSL_WrapperPacket& packet : log.packets) sampler.add(packet);

  EXPECT_EQ(sampler.field(), (FieldSize{12000, 9000}));
  // 10 s of simulator time (3.65 to 13.45) at a 2 s step: instants 3.65, 5.65, ..., 11.65.
  ASSERT_EQ(samples.size(), 5u);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Formation& f = samples[i].formation;
    ASSERT_EQ(f.robots.size(), 11u) << "sample " << i;
    for (std::size_t r = 0; r < f.robots.size(); ++r) {
      const FormationRobot& robot = f.robots[r];
      EXPECT_EQ(robot.robot_id, r);  // ids 0-10, each once
      EXPECT_NEAR(robot.feed_position.x, reported[robot.robot_id].x, 1.0);
      EXPECT_NEAR(robot.feed_position.y, reported[robot.robot_id].y, 1.0);
      EXPECT_EQ(robot.cell, config.grid.cell_of(robot.position, FieldSize{12000, 9000}));
    }
    if (i > 0) {
      EXPECT_EQ(samples[i].transitions.size(), 11u);
      EXPECT_NEAR(f.time_s - samples[i - 1].formation.time_s, 2.0, 1e-9);
    }
  }
  const SamplerCounters& c = sampler.counters();
  EXPECT_EQ(c.samples_forced, 0u);
  EXPECT_EQ(c.frames_late, 0u);
  EXPECT_EQ(c.robots_non_finite + c.robots_bad_id + c.robots_out_of_range, 0u);
  EXPECT_GT(c.geometry_packets, 0u);
}

INSTANTIATE_TEST_SUITE_P(BothColours, GrsimSampling,
                         ::testing::Values(TeamColor::yellow, TeamColor::blue));

}  // namespace
}  // namespace ssl_formation
