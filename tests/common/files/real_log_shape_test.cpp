// A clean recording rewritten as real match logs come (common/files/src/real_log_shape.cpp): the
// shape of every packet, and each part of the mess where it was asked for and nowhere else.

#include "ssl_formation/files/real_log_shape.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "match_logs.hpp"
#include "moving_robots.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_gc_referee_message.pb.h"
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

TEST(RealLogShapeBall, TheRecordingsBallGoesInThePacketOfItsHalf) {
  // 10 s of one robot and a ball rolling from x = -3 m to +3 m at 600 mm/s, with a second, less
  // confident candidate far away (a reflection) that must not win.
  st::ScratchDir dir;
  std::vector<SSL_WrapperPacket> recording;
  for (int f = 0; f < 600; ++f) {
    sf::DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(f);
    spec.t_capture = 100.0 + f / 60.0;
    spec.yellow.push_back({0, {-1000.0, 0.0}});
    spec.balls.push_back({-3000.0 + 600.0 * f / 60.0, 500.0});
    SSL_WrapperPacket packet = sf::make_detection_packet(spec);
    SSL_DetectionBall& reflection = *packet.mutable_detection()->add_balls();
    reflection.set_confidence(0.1F);
    reflection.set_x(4000.0F);
    reflection.set_y(-2500.0F);
    reflection.set_pixel_x(0.0F);
    reflection.set_pixel_y(0.0F);
    packet.mutable_detection()->mutable_balls(0)->set_confidence(0.9F);
    recording.push_back(packet);
  }
  ASSERT_EQ(st::write_vision_log(dir.path() / "clean.log", recording), "");
  sf::RealLogMess mess;
  mess.change_of_ends = true;  // from 5 s on, the ball mirrored too
  ASSERT_TRUE(sf::write_as_real_log(dir.path() / "clean.log", dir.path() / "real.log", mess));
  const auto log = sf::read_vision_log(dir.path() / "real.log");
  ASSERT_TRUE(log.has_value());
  int with_ball = 0;
  for (std::size_t i = 0; i < log->packets.size(); ++i) {
    const auto& detection = log->packets[i].detection();
    const bool left = i % 2 == 0;
    ASSERT_LE(detection.balls_size(), 1);
    if (detection.balls_size() == 0) continue;
    ++with_ball;
    const auto& ball = detection.balls(0);
    EXPECT_EQ(ball.x() < 0.0F, left) << i;
    // The rolling ball (at y = 500, or -500 once the ends changed), never the reflection.
    EXPECT_NEAR(std::abs(ball.y()), 500.0F, 1.0F) << i;
  }
  // One packet of each pair has it: the half it is in.
  EXPECT_NEAR(with_ball, static_cast<int>(log->packets.size()) / 2, 2);
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

// A reshaped log read back in the file's order: each vision packet with the referee message in
// force when it came (none before the first).
struct ReadBack {
  struct Packet {
    SSL_WrapperPacket packet;
    double receive_s = 0.0;
    std::optional<Referee> referee;
  };
  std::vector<Packet> packets;
  std::vector<std::pair<Referee, double>> referee;  // every message, with its receive time
};

ReadBack read_back(const std::filesystem::path& path) {
  ReadBack out;
  auto reader = sf::LogReader::open(path);
  EXPECT_TRUE(reader.has_value());
  if (!reader) return out;
  sf::LogReader::MatchInput kind = sf::LogReader::MatchInput::vision;
  SSL_WrapperPacket packet;
  std::string_view payload;
  std::int64_t receive_ns = 0;
  std::optional<Referee> last;
  while (reader->next_match_input(kind, packet, payload, &receive_ns)) {
    const double receive_s = static_cast<double>(receive_ns) / 1e9;
    if (kind == sf::LogReader::MatchInput::referee) {
      Referee message;
      EXPECT_TRUE(message.ParseFromArray(payload.data(), static_cast<int>(payload.size())));
      out.referee.emplace_back(message, receive_s);
      last = message;
    } else if (kind == sf::LogReader::MatchInput::vision) {
      out.packets.push_back({packet, receive_s, last});
    }
  }
  EXPECT_TRUE(reader->error().empty()) << reader->error();
  return out;
}

bool same_robots(const SSL_WrapperPacket& a, const SSL_WrapperPacket& b) {
  const auto& x = a.detection();
  const auto& y = b.detection();
  if (x.robots_yellow_size() != y.robots_yellow_size() ||
      x.robots_blue_size() != y.robots_blue_size()) {
    return false;
  }
  for (int r = 0; r < x.robots_yellow_size(); ++r) {
    if (x.robots_yellow(r).x() != y.robots_yellow(r).x() ||
        x.robots_yellow(r).y() != y.robots_yellow(r).y()) {
      return false;
    }
  }
  for (int r = 0; r < x.robots_blue_size(); ++r) {
    if (x.robots_blue(r).x() != y.robots_blue(r).x() ||
        x.robots_blue(r).y() != y.robots_blue(r).y()) {
      return false;
    }
  }
  return true;
}

// The inserted stoppages come with a referee, as a game controller sends one: HALT through each,
// running play everywhere else, so the evaluation and the daemons see the states real logs have.
TEST_F(RealLogShape, StoppagesComeWithTheRefereesHaltAndRunningPlayElsewhere) {
  sf::RealLogMess stoppages;
  stoppages.stoppages = true;
  const auto counts = sf::write_as_real_log(recording_, out_, stoppages);
  ASSERT_TRUE(counts.has_value()) << counts.error().message;
  const ReadBack log = read_back(out_);
  ASSERT_GT(log.packets.size(), 10000U);
  EXPECT_EQ(counts->referee_messages, log.referee.size());
  // The recording has no referee: nothing says which half a team defends, and the count says so.
  EXPECT_FALSE(counts->sides_given);
  for (const auto& [message, at_s] : log.referee)
    EXPECT_FALSE(message.has_blue_team_on_positive_half());

  // About ten messages a second, over the whole log, each whole; the counter counts commands.
  const double log_s = log.packets.back().receive_s - log.packets.front().receive_s;
  EXPECT_NEAR(static_cast<double>(log.referee.size()), 10.0 * log_s, 0.1 * 10.0 * log_s);
  std::vector<Referee::Command> commands;
  for (std::size_t i = 0; i < log.referee.size(); ++i) {
    const auto& [message, at_s] = log.referee[i];
    ASSERT_TRUE(message.IsInitialized()) << message.InitializationErrorString();
    EXPECT_EQ(message.source_identifier(), "ssl-evaluate as-real-log");
    EXPECT_EQ(message.stage(), Referee::NORMAL_FIRST_HALF);
    EXPECT_EQ(message.yellow().name(), "Yellow") << "the recording has no referee to name them";
    EXPECT_EQ(message.blue().name(), "Blue");
    EXPECT_FALSE(message.has_blue_team_on_positive_half()) << "nobody said which half";
    EXPECT_EQ(message.packet_timestamp(), static_cast<std::uint64_t>(std::llround(at_s * 1e6)));
    if (i == 0) {
      EXPECT_EQ(message.command_counter(), 1U);
      EXPECT_LE(at_s, log.packets.front().receive_s) << "the referee speaks before the vision";
      commands.push_back(message.command());
      continue;
    }
    const Referee& before = log.referee[i - 1].first;
    EXPECT_LE(at_s - log.referee[i - 1].second, 0.12);
    if (message.command() != before.command()) {
      EXPECT_EQ(message.command_counter(), before.command_counter() + 1);
      EXPECT_EQ(message.command_timestamp(), message.packet_timestamp());
      commands.push_back(message.command());
    } else {
      EXPECT_EQ(message.command_counter(), before.command_counter());
      EXPECT_EQ(message.command_timestamp(), before.command_timestamp());
    }
  }
  EXPECT_EQ(commands, (std::vector<Referee::Command>{
                          Referee::NORMAL_START, Referee::HALT, Referee::FORCE_START, Referee::HALT,
                          Referee::FORCE_START, Referee::HALT, Referee::FORCE_START}));

  // The HALTs cover the stoppages exactly: every packet in one shows the robots where the
  // stoppage's first pair has them, 25 s of them; every packet outside is in running play, and
  // the robots move from pair to pair (but for the first pair after a stoppage, where the
  // recording goes on from where it stopped). The game phase reads the same.
  sf::RefereeFollower follower;
  sf::GamePhaseTracker phases;
  std::size_t next_message = 0;
  std::vector<double> halts_s;
  std::vector<int> halt_packets;
  const SSL_WrapperPacket* first_still[2] = {nullptr, nullptr};
  int moving_pairs = 0;
  int standing_outside = 0;
  for (std::size_t i = 0; i < log.packets.size(); ++i) {
    const auto& [packet, at_s, referee] = log.packets[i];
    while (next_message < log.referee.size() && log.referee[next_message].second <= at_s) {
      const sf::RefereeChange change =
          follower.add(log.referee[next_message].first, log.referee[next_message].second);
      if (change.command) phases.on_command(follower.view(), log.referee[next_message].second);
      ++next_message;
    }
    ASSERT_TRUE(referee.has_value());
    const sf::GamePhase phase = phases.phase(at_s, sf::TeamColor::yellow);
    if (referee->command() == Referee::HALT) {
      EXPECT_EQ(phase, sf::GamePhase::halt);
      EXPECT_EQ(follower.view().state, sf::GameState::halt);
      if (halts_s.empty() || at_s - halts_s.back() > 26.0) {
        halts_s.push_back(at_s);
        halt_packets.push_back(0);
        first_still[0] = first_still[1] = nullptr;
      }
      ++halt_packets.back();
      const SSL_WrapperPacket*& first = first_still[i % 2];
      if (first == nullptr) first = &packet;
      EXPECT_TRUE(same_robots(packet, *first)) << "a robot moved in HALT at " << at_s;
      EXPECT_LT(at_s - halts_s.back(), 25.0);
      continue;
    }
    EXPECT_TRUE(referee->command() == Referee::NORMAL_START ||
                referee->command() == Referee::FORCE_START);
    EXPECT_EQ(phase, sf::GamePhase::running);
    if (i >= 2 && log.packets[i - 2].referee &&
        log.packets[i - 2].referee->command() != Referee::HALT) {
      const bool standing = same_robots(packet, log.packets[i - 2].packet);
      moving_pairs += standing ? 0 : 1;
      standing_outside += standing ? 1 : 0;
    }
  }
  ASSERT_EQ(halts_s.size(), 3U);
  for (const int packets : halt_packets) EXPECT_NEAR(packets, 25 * 90, 2);
  EXPECT_GT(moving_pairs, 10000);
  EXPECT_EQ(standing_outside, 0);
  EXPECT_EQ(follower.counters().undecodable, 0U);
  EXPECT_EQ(follower.counters().commands, 7U);
}

// A recording with a referee lends the reshaped log its team names and sides; the teams change
// ends at half time, the break halted, and the recording's own messages are not copied.
TEST(RealLogShapeReferee, TheRecordingsTeamsAndSidesAreKeptAndTurnAtTheChangeOfEnds) {
  st::ScratchDir dir;
  const auto recording = dir.path() / "refereed.log";
  st::MatchScript script;
  script.seconds = 120.0;
  script.frame = [](double t) {
    sf::DetectionFrameSpec spec;
    for (std::uint32_t id = 0; id < 6; ++id) {
      spec.yellow.push_back({id, {-2000.0 + 300.0 * id + 100.0 * std::sin(t), -1000.0}});
      spec.blue.push_back({id, {2000.0 - 300.0 * id, 1000.0 + 100.0 * std::cos(t)}});
    }
    return std::optional<sf::DetectionFrameSpec>(spec);
  };
  script.referee = [](double) {
    st::RefereeSpec spec;
    spec.yellow = "RobôCIn";
    spec.blue = "TIGERs Mannheim";
    spec.blue_on_positive_half = true;
    spec.command = Referee::STOP;
    return std::optional<st::RefereeSpec>(spec);
  };
  ASSERT_EQ(st::write_match_log(recording, script), "");
  sf::RealLogMess mess;
  mess.stoppages = true;
  mess.change_of_ends = true;
  const auto out = dir.path() / "real.log.gz";
  const auto counts = sf::write_as_real_log(recording, out, mess);
  ASSERT_TRUE(counts.has_value());
  EXPECT_TRUE(counts->sides_given);
  const ReadBack log = read_back(out);
  ASSERT_FALSE(log.referee.empty());
  std::vector<Referee::Stage> stages;
  double break_s = 0.0;
  for (const auto& [message, at_s] : log.referee) {
    EXPECT_EQ(message.source_identifier(), "ssl-evaluate as-real-log");
    EXPECT_NE(message.command(), Referee::STOP) << "the recording's own commands are not copied";
    EXPECT_EQ(message.yellow().name(), "RobôCIn");
    EXPECT_EQ(message.blue().name(), "TIGERs Mannheim");
    ASSERT_TRUE(message.has_blue_team_on_positive_half());
    // Blue defends +x, as the recording says, until the teams change ends for the second half.
    EXPECT_EQ(message.blue_team_on_positive_half(), message.stage() != Referee::NORMAL_SECOND_HALF);
    if (message.stage() == Referee::NORMAL_HALF_TIME) {
      EXPECT_EQ(message.command(), Referee::HALT);
      break_s += 0.1;
    }
    if (stages.empty() || stages.back() != message.stage()) stages.push_back(message.stage());
  }
  EXPECT_EQ(stages,
            (std::vector<Referee::Stage>{Referee::NORMAL_FIRST_HALF, Referee::NORMAL_HALF_TIME,
                                         Referee::NORMAL_SECOND_HALF}));
  EXPECT_NEAR(break_s, 60.0, 0.5);
  // Each vision packet after the break sees the teams on their new ends.
  for (const auto& packet : log.packets) {
    ASSERT_TRUE(packet.referee.has_value());
    const bool second_half = packet.referee->stage() == Referee::NORMAL_SECOND_HALF;
    EXPECT_EQ(packet.referee->blue_team_on_positive_half(), !second_half);
  }
}

TEST(RealLogMess, ParsesNamesAllAndNone) {
  EXPECT_EQ(sf::parse_real_log_mess("none"), sf::RealLogMess{});
  const auto all = sf::parse_real_log_mess("all");
  ASSERT_TRUE(all);
  EXPECT_TRUE(all->ghosts && all->substitutions && all->stoppages && all->cuts &&
              all->change_of_ends);
  EXPECT_DOUBLE_EQ(all->noise_mm, 0.3);  // the real logs' (docs/simulation.md)
  EXPECT_DOUBLE_EQ(sf::parse_real_log_mess("noise")->noise_mm, 0.3);
  EXPECT_DOUBLE_EQ(sf::parse_real_log_mess("cuts,noise=3")->noise_mm, 3.0);
  EXPECT_FALSE(sf::parse_real_log_mess("noise=-1"));
  EXPECT_FALSE(sf::parse_real_log_mess("noise=3mm"));
  EXPECT_FALSE(sf::parse_real_log_mess("noise="));
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
