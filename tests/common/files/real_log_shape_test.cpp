// A clean recording rewritten as real match logs come (common/files/src/real_log_shape.cpp): the shape
// of every packet, and each part of the mess where it was asked for and nowhere else.

#include "ssl_formation/files/real_log_shape.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "moving_robots.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace sf = ssl_formation;
namespace st = ssl_formation::testing;

namespace {

// 120 s of six yellow and six blue robots at 60 Hz (recording time 100-220 s).
class RealLogShape : public ::testing::Test {
 protected:
  void SetUp() override {
    st::MovingRobots config;
    config.seconds = 120.0;
    ASSERT_EQ(st::write_vision_log(recording_, st::moving_robots_packets(config)), "");
  }
  std::vector<SSL_WrapperPacket> reshape(const sf::RealLogMess& mess) {
    const auto counts = sf::write_as_real_log(recording_, out_, mess);
    EXPECT_TRUE(counts.has_value()) << (counts ? "" : counts.error().message);
    auto log = sf::read_vision_log(out_);
    EXPECT_TRUE(log.has_value());
    std::vector<SSL_WrapperPacket> packets;
    for (const auto& packet : log->packets) packets.push_back(packet);
    return packets;
  }
  st::ScratchDir dir_;
  std::filesystem::path recording_ = dir_.path() / "clean.log";
  std::filesystem::path out_ = dir_.path() / "real.log";
};

TEST_F(RealLogShape, EveryPacketIsOneHalfOfTheFieldFromCameraZeroNinetyASecond) {
  const std::vector<SSL_WrapperPacket> packets = reshape(sf::RealLogMess{});
  ASSERT_GT(packets.size(), 10000U);
  // 45 pairs a second over 120 s.
  EXPECT_NEAR(static_cast<double>(packets.size()), 90.0 * 120.0, 10.0);
  std::set<std::uint32_t> ids;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    ASSERT_FALSE(packets[i].has_geometry());
    const auto& detection = packets[i].detection();
    EXPECT_EQ(detection.camera_id(), 0U);
    const bool left = i % 2 == 0;  // the left half first, the right one 11 ms later
    for (const auto& robot : detection.robots_yellow()) {
      EXPECT_EQ(robot.x() < 0.0F, left);
      ids.insert(robot.robot_id());
    }
    for (const auto& robot : detection.robots_blue()) EXPECT_EQ(robot.x() < 0.0F, left);
    if (i > 0) {
      EXPECT_GT(detection.t_capture(), packets[i - 1].detection().t_capture());
    }
  }
  EXPECT_EQ(ids, (std::set<std::uint32_t>{0, 1, 2, 3, 4, 5}));
}

TEST_F(RealLogShape, EachPartOfTheMessIsWhereItWasAsked) {
  const std::vector<SSL_WrapperPacket> clean = reshape(sf::RealLogMess{});
  const auto yellow_ids = [](const std::vector<SSL_WrapperPacket>& packets) {
    std::map<std::uint32_t, int> seen;
    for (const auto& packet : packets) {
      for (const auto& robot : packet.detection().robots_yellow()) ++seen[robot.robot_id()];
    }
    return seen;
  };
  // The largest step between two packets' capture times.
  const auto longest_gap = [](const std::vector<SSL_WrapperPacket>& packets) {
    double gap = 0.0;
    for (std::size_t i = 1; i < packets.size(); ++i) {
      gap = std::max(gap,
                     packets[i].detection().t_capture() - packets[i - 1].detection().t_capture());
    }
    return gap;
  };
  EXPECT_LT(longest_gap(clean), 0.05);

  sf::RealLogMess ghosts;
  ghosts.ghosts = true;
  const std::vector<SSL_WrapperPacket> with_ghosts = reshape(ghosts);
  std::map<std::uint32_t, int> seen = yellow_ids(with_ghosts);
  std::map<std::uint32_t, int> blue_seen;
  for (const auto& packet : with_ghosts) {
    for (const auto& robot : packet.detection().robots_blue()) ++blue_seen[robot.robot_id()];
  }
  // New ids (11-15) for a few packets each, on either team.
  int ghost_ids = 0;
  for (const auto& [id, n] : seen) ghost_ids += id >= 11 ? n : 0;
  for (const auto& [id, n] : blue_seen) ghost_ids += id >= 11 ? n : 0;
  EXPECT_GT(ghost_ids, 3);
  EXPECT_LT(ghost_ids, 200);
  // The same seed gives the same log; another seed other ghosts.
  EXPECT_EQ(yellow_ids(reshape(ghosts)), seen);

  sf::RealLogMess substitutions;
  substitutions.substitutions = true;
  seen = yellow_ids(reshape(substitutions));
  EXPECT_GT(seen[12], 0);  // robot 4 plays on as 12 from a third of the recording
  EXPECT_LT(seen[4], yellow_ids(clean)[4]);
  EXPECT_EQ(seen.count(14), 0U);  // robot 7 is not in this team

  sf::RealLogMess cuts;
  cuts.cuts = true;
  EXPECT_GT(longest_gap(reshape(cuts)), 14.0);

  sf::RealLogMess stoppages;
  stoppages.stoppages = true;
  const std::vector<SSL_WrapperPacket> stopped = reshape(stoppages);
  // Three stoppages of 25 s: the log is 75 s longer, and in each everyone stands still.
  EXPECT_NEAR(static_cast<double>(stopped.size() - clean.size()), 3 * 25 * 90.0, 10.0);
  int standing_pairs = 0;
  for (std::size_t i = 2; i < stopped.size(); ++i) {
    const auto& now = stopped[i].detection();
    const auto& before = stopped[i - 2].detection();  // the same half a pair earlier
    if (now.robots_yellow_size() == 0 || now.robots_yellow_size() != before.robots_yellow_size()) {
      continue;
    }
    bool still = true;
    for (int r = 0; r < now.robots_yellow_size(); ++r) {
      still = still && now.robots_yellow(r).x() == before.robots_yellow(r).x() &&
              now.robots_yellow(r).y() == before.robots_yellow(r).y();
    }
    standing_pairs += still ? 1 : 0;
  }
  EXPECT_GT(standing_pairs, 3 * 25 * 45 * 9 / 10);

  sf::RealLogMess ends;
  ends.change_of_ends = true;
  const std::vector<SSL_WrapperPacket> changed = reshape(ends);
  // A half-time break of 60 s, after which robot 0 is where the clean log has it, mirrored.
  EXPECT_GT(longest_gap(changed), 59.0);
  const auto robot_0 = [](const SSL_WrapperPacket& packet) -> std::optional<sf::Point> {
    for (const auto& robot : packet.detection().robots_yellow()) {
      if (robot.robot_id() == 0) return sf::Point{robot.x(), robot.y()};
    }
    return std::nullopt;
  };
  int mirrored = 0;
  for (std::size_t i = clean.size() * 3 / 4; i < clean.size(); ++i) {
    // Mirrored, robot 0 is in the other half's packet of the same pair.
    const auto was = robot_0(clean[i]);
    const auto is = robot_0(changed[i ^ 1]);
    if (!was || !is) continue;
    EXPECT_FLOAT_EQ(static_cast<float>(is->x), static_cast<float>(-was->x));
    EXPECT_FLOAT_EQ(static_cast<float>(is->y), static_cast<float>(-was->y));
    ++mirrored;
  }
  EXPECT_GT(mirrored, 100);

  sf::RealLogMess noise;
  noise.noise_mm = 3.0;
  const std::vector<SSL_WrapperPacket> noisy = reshape(noise);
  ASSERT_EQ(noisy.size(), clean.size());
  double sum_square = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    const auto& a = clean[i].detection();
    const auto& b = noisy[i].detection();
    if (a.robots_blue_size() != b.robots_blue_size()) continue;  // a robot near the midline
    for (int r = 0; r < a.robots_blue_size(); ++r) {
      const double d = b.robots_blue(r).x() - a.robots_blue(r).x();
      sum_square += d * d;
      ++n;
    }
  }
  ASSERT_GT(n, 1000);
  EXPECT_NEAR(std::sqrt(sum_square / n), 3.0, 0.2);
}

TEST(RealLogMess, ParsesNamesAllAndNone) {
  EXPECT_EQ(sf::parse_real_log_mess("none"), sf::RealLogMess{});
  const auto all = sf::parse_real_log_mess("all");
  ASSERT_TRUE(all);
  EXPECT_TRUE(all->ghosts && all->substitutions && all->stoppages && all->cuts &&
              all->change_of_ends);
  EXPECT_DOUBLE_EQ(all->noise_mm, 3.0);
  const auto some = sf::parse_real_log_mess("ghosts,ends");
  ASSERT_TRUE(some);
  EXPECT_TRUE(some->ghosts && some->change_of_ends && !some->stoppages);
  EXPECT_FALSE(sf::parse_real_log_mess("ghost"));
  EXPECT_FALSE(sf::parse_real_log_mess(""));
  EXPECT_FALSE(sf::parse_real_log_mess("ghosts,,cuts"));
}

TEST_F(RealLogShape, WritingOverTheRecordingIsRefusedAndLosesNothing) {
  const auto before = std::filesystem::file_size(recording_);
  const auto counts = sf::write_as_real_log(recording_, recording_, sf::RealLogMess{});
  ASSERT_FALSE(counts);
  EXPECT_NE(counts.error().message.find("recording itself"), std::string::npos);
  EXPECT_EQ(std::filesystem::file_size(recording_), before);
  EXPECT_TRUE(sf::read_vision_log(recording_).has_value());
}

TEST(RealLogShapeErrors, AMissingRecordingIsAnErrorNamingIt) {
  st::ScratchDir dir;
  const auto counts =
      sf::write_as_real_log(dir.path() / "missing.log", dir.path() / "out.log", sf::RealLogMess{});
  ASSERT_FALSE(counts);
  EXPECT_NE(counts.error().message.find("missing.log"), std::string::npos);
}

}  // namespace
