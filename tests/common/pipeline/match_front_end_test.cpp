// The front end (pipeline/src/match_front_end.cpp): samples with what is known of the game.

#include "ssl_formation/pipeline/match_front_end.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "match_logs.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper_tracked.pb.h"

namespace ssl_formation {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

// What a handler saw of a moment, copied (the moment is valid only during the call).
struct Seen {
  double time_s = 0.0;
  std::vector<FormationRobot> robots;
  Grid grid;
  FieldSize field;
  AttackDirection attacks = AttackDirection::positive_x;
  GameState game_state = GameState::unknown;
  GamePhase phase = GamePhase::running;
  double since_command_s = 0.0;
  double learn_from_s = 0.0;
  std::optional<Point> ball;
  Point ball_velocity;
  std::optional<Point> designated_position;
};

struct Recorder {
  std::vector<Seen> seen;
  int forgets = 0;
  MatchFrontEnd::Handlers handlers() {
    return {[this](const MatchMoment& m) {
              seen.push_back({m.formation().time_s, m.formation().robots, m.codec.grid(), m.field,
                              m.attacks, m.game_state, m.phase, m.since_command_s, m.learn_from_s,
                              m.ball, m.ball_velocity, m.designated_position});
            },
            [this] { ++forgets; }};
  }
};

FrontEndConfig config(Grid grid = Grid(3, 2)) {
  FrontEndConfig c;
  c.sampler.grid = grid;
  c.sampler.step_s = 0.5;
  c.sampler.sampling = Sampling::frame;
  return c;
}

// Frame `i` at 60 Hz from `start_s`: yellow robot 1 at (x, 500) and blue robot 2 at (-x, -500),
// x moving 1 m/s from 1000 mm.
SSL_WrapperPacket frame(int i, double start_s = 100.0) {
  const double t = i / 60.0;
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(i);
  spec.t_capture = start_s + t;
  spec.yellow.push_back({1, {1000.0 + 1000.0 * t, 500.0}});
  spec.blue.push_back({2, {-1000.0 - 1000.0 * t, -500.0}});
  return make_detection_packet(spec);
}

// The ball of the tests below, in feed coordinates, `t` seconds into the frames: rolling at
// (1500, -600) mm/s from (-500, 200).
constexpr Point ball_velocity{1500.0, -600.0};
Point ball_at(double t) { return {-500.0 + ball_velocity.x * t, 200.0 + ball_velocity.y * t}; }

// frame(i) with the ball where it is then (none: a frame without a ball).
SSL_WrapperPacket frame_with_ball(int i, std::optional<Point> ball, double start_s = 100.0) {
  SSL_WrapperPacket packet = frame(i, start_s);
  if (ball) {
    SSL_DetectionBall& b = *packet.mutable_detection()->add_balls();
    b.set_confidence(0.9F);
    b.set_x(static_cast<float>(ball->x));
    b.set_y(static_cast<float>(ball->y));
    b.set_pixel_x(0.0F);
    b.set_pixel_y(0.0F);
  }
  return packet;
}
SSL_WrapperPacket frame_with_ball(int i) { return frame_with_ball(i, ball_at(i / 60.0)); }

// A game controller's message (match_logs.hpp builds it as the game controller sends it).
std::string referee(Referee::Command command, std::uint32_t counter,
                    const std::string& yellow = "TIGERs Mannheim",
                    const std::string& blue = "ER-Force") {
  testing::RefereeSpec spec;
  spec.command = command;
  spec.command_counter = counter;
  spec.yellow = yellow;
  spec.blue = blue;
  spec.source = "gc";
  return testing::referee_payload(spec, 1700000000.0);
}

// The same with a ball placement's target (feed coordinates, millimetres).
std::string referee_with_target(Referee::Command command, std::uint32_t counter, Point target) {
  Referee message;
  EXPECT_TRUE(message.ParseFromString(referee(command, counter)));
  message.mutable_designated_position()->set_x(static_cast<float>(target.x));
  message.mutable_designated_position()->set_y(static_cast<float>(target.y));
  return message.SerializeAsString();
}

std::string tracked(std::uint32_t frame_number, double timestamp, float yellow_x_m) {
  TrackerWrapperPacket wrapper;
  wrapper.set_uuid("tracker-1");
  wrapper.set_source_name("test tracker");
  TrackedFrame& f = *wrapper.mutable_tracked_frame();
  f.set_frame_number(frame_number);
  f.set_timestamp(timestamp);
  TrackedRobot& robot = *f.add_robots();
  robot.mutable_robot_id()->set_id(4);
  robot.mutable_robot_id()->set_team(YELLOW);
  robot.mutable_pos()->set_x(yellow_x_m);
  robot.mutable_pos()->set_y(-1.25F);
  robot.set_orientation(0.0F);
  EXPECT_TRUE(wrapper.IsInitialized());
  return wrapper.SerializeAsString();
}

// A tracker's frame (tracked()) with its ball at (x, y) metres moving at (vx, vy) m/s.
std::string tracked_with_ball(std::uint32_t frame_number, double timestamp, Point ball_m,
                              Point velocity_m_s) {
  TrackerWrapperPacket wrapper;
  EXPECT_TRUE(wrapper.ParseFromString(tracked(frame_number, timestamp, 1.5F)));
  TrackedBall& ball = *wrapper.mutable_tracked_frame()->add_balls();
  ball.mutable_pos()->set_x(static_cast<float>(ball_m.x));
  ball.mutable_pos()->set_y(static_cast<float>(ball_m.y));
  ball.mutable_pos()->set_z(0.0F);
  ball.mutable_vel()->set_x(static_cast<float>(velocity_m_s.x));
  ball.mutable_vel()->set_y(static_cast<float>(velocity_m_s.y));
  ball.mutable_vel()->set_z(0.0F);
  return wrapper.SerializeAsString();
}

TEST(MatchFrontEnd, RawFramesGiveSamplesWithWhatIsKnownOfTheGame) {
  Recorder recorder;
  MatchFrontEnd front(config(Grid(6, 4)), recorder.handlers());
  front.add(make_geometry_packet(FieldSize{12000.0, 9000.0}));
  for (int i = 0; i < 30; ++i) front.add(frame(i));
  ASSERT_GE(recorder.seen.size(), 29u);
  const Seen& last = recorder.seen.back();
  EXPECT_EQ(last.grid, Grid(6, 4));
  EXPECT_EQ(last.field, (FieldSize{12000.0, 9000.0}));
  EXPECT_EQ(last.attacks, AttackDirection::positive_x);
  EXPECT_EQ(last.game_state, GameState::unknown);
  EXPECT_EQ(last.phase, GamePhase::running);
  EXPECT_EQ(last.since_command_s, inf);
  EXPECT_EQ(last.learn_from_s, -inf);
  // The opponent is yellow by default: robot 1 only, where the frame put it.
  ASSERT_EQ(last.robots.size(), 1u);
  EXPECT_EQ(last.robots[0].robot_id, 1u);
  const double t = last.time_s - 100.0;
  EXPECT_NEAR(last.robots[0].position.x, 1000.0 + 1000.0 * t, 1.1);
  EXPECT_NEAR(last.robots[0].position.y, 500.0, 1e-3);
  EXPECT_EQ(front.sampler().field(), (FieldSize{12000.0, 9000.0}));
}

TEST(MatchFrontEnd, SamplesAreNormalisedToTheSideTheOpponentAttacks) {
  Recorder recorder;
  FrontEndConfig c = config();
  c.sampler.opponent_color = TeamColor::blue;
  c.sampler.opponent_attacks = AttackDirection::negative_x;
  MatchFrontEnd front(c, recorder.handlers());
  for (int i = 0; i < 10; ++i) front.add(frame(i));
  ASSERT_FALSE(recorder.seen.empty());
  const Seen& last = recorder.seen.back();
  EXPECT_EQ(last.attacks, AttackDirection::negative_x);
  EXPECT_EQ(front.attacks(), AttackDirection::negative_x);
  ASSERT_EQ(last.robots.size(), 1u);
  EXPECT_EQ(last.robots[0].robot_id, 2u);
  const double t = last.time_s - 100.0;
  EXPECT_NEAR(last.robots[0].position.x, 1000.0 + 1000.0 * t, 1.1);  // -(-1000 - 1000 t)
  EXPECT_NEAR(last.robots[0].position.y, 500.0, 1e-3);
  EXPECT_NEAR(last.robots[0].feed_position.y, -500.0, 1e-3);
}

TEST(MatchFrontEnd, TrackedVisionReplacesRawDetectionsButRawGeometryStillSetsTheField) {
  Recorder recorder;
  FrontEndConfig c = config();
  c.tracked_vision = true;
  MatchFrontEnd front(c, recorder.handlers());
  VisionFrame geometry;
  to_vision_frame(make_geometry_packet(FieldSize{12000.0, 9000.0}), geometry);
  front.on_event(MatchEvent::vision(geometry, 50.0));
  for (int i = 0; i < 20; ++i) front.add(frame(i));
  EXPECT_TRUE(recorder.seen.empty());  // raw detections are ignored
  EXPECT_EQ(front.sampler().counters().detection_frames, 0u);
  EXPECT_EQ(front.sampler().field(), (FieldSize{12000.0, 9000.0}));

  for (int i = 0; i < 20; ++i) {
    const double t = 200.0 + i / 60.0;
    front.on_event(MatchEvent::tracked_vision(
        tracked(static_cast<std::uint32_t>(i), t, 1.5F + 0.01F * static_cast<float>(i)), t));
  }
  ASSERT_GE(recorder.seen.size(), 19u);
  const Seen& last = recorder.seen.back();
  EXPECT_EQ(last.field, (FieldSize{12000.0, 9000.0}));
  ASSERT_EQ(last.robots.size(), 1u);
  EXPECT_EQ(last.robots[0].robot_id, 4u);
  const int i = static_cast<int>(std::lround((last.time_s - 200.0) * 60.0));
  EXPECT_NEAR(last.robots[0].position.x, 1500.0 + 10.0 * i, 0.01);  // metres to millimetres
  EXPECT_NEAR(last.robots[0].position.y, -1250.0, 0.01);
  EXPECT_EQ(front.tracked_vision().source_uuid(), "tracker-1");
}

TEST(MatchFrontEnd, WithoutTrackedVisionTheTrackersFramesAreIgnored) {
  Recorder recorder;
  MatchFrontEnd front(config(), recorder.handlers());
  for (int i = 0; i < 10; ++i) {
    front.on_event(MatchEvent::tracked_vision(
        tracked(static_cast<std::uint32_t>(i), 200.0 + i / 60.0, 1.0F), 200.0 + i / 60.0));
  }
  EXPECT_TRUE(recorder.seen.empty());
}

TEST(MatchFrontEnd, RefereeCommandsSetTheGameStateAndTheKickoffPhase) {
  Recorder recorder;
  MatchFrontEnd front(config(), recorder.handlers());
  int i = 0;
  const auto run_until = [&](double t) {
    while (i / 60.0 < t) front.add(frame(i++));
  };
  run_until(0.5);
  EXPECT_EQ(recorder.seen.back().game_state, GameState::unknown);
  EXPECT_TRUE(front.add_referee(referee(Referee::STOP, 1), 0.0).command);
  run_until(1.0);
  EXPECT_EQ(recorder.seen.back().game_state, GameState::stop);
  EXPECT_EQ(recorder.seen.back().phase, GamePhase::stop);
  // A repeated message is no new command.
  EXPECT_FALSE(front.add_referee(referee(Referee::STOP, 1), 0.1).command);
  // Yellow (the opponent) prepares a kick-off, then the kick is allowed.
  front.add_referee(referee(Referee::PREPARE_KICKOFF_YELLOW, 2), 0.2);
  run_until(2.0);
  EXPECT_EQ(recorder.seen.back().game_state, GameState::kickoff_preparation);
  EXPECT_EQ(recorder.seen.back().phase, GamePhase::kickoff_opponent);
  front.add_referee(referee(Referee::NORMAL_START, 3), 0.3);
  const std::size_t first = recorder.seen.size();
  run_until(6.0);
  ASSERT_GT(recorder.seen.size(), first + 200);
  const double start = recorder.seen[first].time_s;
  EXPECT_NEAR(start - 100.0, 2.0, 0.02);  // the first sample under NORMAL_START
  for (std::size_t k = first; k < recorder.seen.size(); ++k) {
    const Seen& s = recorder.seen[k];
    SCOPED_TRACE(s.time_s);
    EXPECT_EQ(s.game_state, GameState::running);
    EXPECT_NEAR(s.since_command_s, s.time_s - start, 1e-9);
    EXPECT_EQ(s.phase, s.time_s - start < 3.0 ? GamePhase::kickoff_opponent : GamePhase::running);
  }
  EXPECT_EQ(recorder.seen.back().phase, GamePhase::running);
  EXPECT_EQ(recorder.seen.back().learn_from_s, -inf);  // commands are not kept apart
  EXPECT_EQ(recorder.forgets, 0);
}

TEST(MatchFrontEnd, AKickoffPreparedAndStartedBetweenTwoSamplesIsStillAKickoff) {
  // Step sampling: a formation every 2 s, the kick-off prepared and started between two.
  FrontEndConfig c = config();
  c.sampler.step_s = 2.0;
  c.sampler.sampling = Sampling::step;
  Recorder recorder;
  MatchFrontEnd front(c, recorder.handlers());
  int i = 0;
  const auto run_until = [&](double t) {
    while (i / 60.0 < t) front.add(frame(i++));
  };
  run_until(2.1);
  front.add_referee(referee(Referee::PREPARE_KICKOFF_YELLOW, 1), 0.0);
  run_until(2.5);
  front.add_referee(referee(Referee::NORMAL_START, 2), 0.5);
  const std::size_t first = recorder.seen.size();
  run_until(4.5);
  ASSERT_GT(recorder.seen.size(), first);
  EXPECT_EQ(recorder.seen[first].game_state, GameState::running);
  EXPECT_EQ(recorder.seen[first].phase, GamePhase::kickoff_opponent);
}

TEST(MatchFrontEnd, KeepingCommandsApartLearnsFromTheFirstSampleUnderTheCommand) {
  Recorder recorder;
  FrontEndConfig c = config();
  c.keep_commands_apart = true;
  MatchFrontEnd front(c, recorder.handlers());
  int i = 0;
  for (; i < 30; ++i) front.add(frame(i));
  EXPECT_EQ(recorder.seen.back().learn_from_s, -inf);
  const std::uint64_t breaks = front.sampler().counters().chain_breaks;
  front.add_referee(referee(Referee::NORMAL_START, 1), 0.0);
  EXPECT_EQ(front.sampler().counters().chain_breaks, breaks + 1);
  const std::size_t first = recorder.seen.size();
  for (; i < 90; ++i) front.add(frame(i));
  ASSERT_GT(recorder.seen.size(), first + 50);
  const double start = recorder.seen[first].time_s;
  EXPECT_NEAR(start, 100.5, 0.02);
  for (std::size_t k = first; k < recorder.seen.size(); ++k) {
    EXPECT_EQ(recorder.seen[k].learn_from_s, start);
  }
  front.add_referee(referee(Referee::STOP, 2), 0.1);
  const std::size_t second = recorder.seen.size();
  for (; i < 120; ++i) front.add(frame(i));
  ASSERT_GT(recorder.seen.size(), second);
  EXPECT_EQ(recorder.seen.back().learn_from_s, recorder.seen[second].time_s);
  EXPECT_GT(recorder.seen[second].time_s, start + 0.9);
}

TEST(MatchFrontEnd, AnOpponentOfAnotherColourForgetsTheMatch) {
  Recorder recorder;
  FrontEndConfig c = config();
  OpponentChoice choice;
  choice.our_team = "ER-Force";
  c.opponent = choice;
  MatchFrontEnd front(c, recorder.handlers());
  EXPECT_EQ(recorder.forgets, 0);
  int i = 0;
  // Yellow is the opponent, as the sampler already had it.
  front.add_referee(referee(Referee::NORMAL_START, 1, "TIGERs Mannheim", "ER-Force"), 0.0);
  EXPECT_EQ(recorder.forgets, 0);
  for (; i < 20; ++i) front.add(frame(i));
  EXPECT_EQ(recorder.seen.back().robots.at(0).robot_id, 1u);  // the yellow robot
  // The teams swap colours: the opponent is blue once the new names have held for a second.
  front.add_referee(referee(Referee::NORMAL_START, 1, "ER-Force", "TIGERs Mannheim"), 0.1);
  EXPECT_EQ(recorder.forgets, 0);
  front.add_referee(referee(Referee::NORMAL_START, 1, "ER-Force", "TIGERs Mannheim"), 1.2);
  EXPECT_EQ(recorder.forgets, 1);
  EXPECT_EQ(front.sampler().config().opponent_color, TeamColor::blue);
  EXPECT_EQ(front.match().opponent().name, "TIGERs Mannheim");
  for (; i < 40; ++i) front.add(frame(i));
  ASSERT_EQ(recorder.seen.back().robots.size(), 1u);
  EXPECT_EQ(recorder.seen.back().robots[0].robot_id, 2u);  // the blue robot
  // The same teams again change nothing.
  front.add_referee(referee(Referee::STOP, 2, "ER-Force", "TIGERs Mannheim"), 1.3);
  EXPECT_EQ(recorder.forgets, 1);
}

TEST(MatchFrontEnd, ANewStreamForgetsTheMatchAndItsPhase) {
  Recorder recorder;
  FrontEndConfig c = config();
  c.keep_commands_apart = true;
  MatchFrontEnd front(c, recorder.handlers());
  front.add_referee(referee(Referee::HALT, 1), 0.0);
  for (int i = 0; i < 30; ++i) front.add(frame(i));
  EXPECT_EQ(recorder.seen.back().phase, GamePhase::halt);
  EXPECT_EQ(recorder.seen.back().game_state, GameState::halt);
  EXPECT_GT(recorder.seen.back().learn_from_s, 0.0);
  front.start_new_stream();
  EXPECT_EQ(recorder.forgets, 1);
  EXPECT_FALSE(front.match().referee().heard());
  const std::size_t first = recorder.seen.size();
  for (int i = 0; i < 30; ++i) front.add(frame(i, 500.0));
  ASSERT_GT(recorder.seen.size(), first);
  const Seen& last = recorder.seen.back();
  EXPECT_EQ(last.phase, GamePhase::running);
  EXPECT_EQ(last.game_state, GameState::unknown);
  EXPECT_EQ(last.since_command_s, inf);
  EXPECT_EQ(last.learn_from_s, -inf);
}

TEST(MatchFrontEnd, TheFeedsPaceIsTheSmallestOfTheLastThreeGaps) {
  Recorder recorder;
  MatchFrontEnd front(config(), recorder.handlers());
  EXPECT_EQ(front.recent_frame_gap_s(), 0.0);
  for (int i = 0; i < 3; ++i) front.add(frame(i));
  EXPECT_EQ(front.recent_frame_gap_s(), 0.0);  // two gaps only
  front.add(frame(3));
  EXPECT_NEAR(front.recent_frame_gap_s(), 1.0 / 60.0, 1e-9);
  for (int i = 4; i < 60; ++i) front.add(frame(i));
  EXPECT_NEAR(front.recent_frame_gap_s(), 1.0 / 60.0, 1e-9);
  // One pause of a second in the 60 Hz feed does not count.
  front.add(frame(120));
  EXPECT_NEAR(front.recent_frame_gap_s(), 1.0 / 60.0, 1e-9);
  front.add(frame(121));
  EXPECT_NEAR(front.recent_frame_gap_s(), 1.0 / 60.0, 1e-9);

  // A feed of one frame every 2 s (the paper's), in a new stream.
  front.start_new_stream();
  EXPECT_EQ(front.recent_frame_gap_s(), 0.0);
  for (int k = 0; k < 4; ++k) front.add(frame(120 * k, 1000.0));
  EXPECT_NEAR(front.recent_frame_gap_s(), 2.0, 1e-9);
}

TEST(MatchFrontEnd, CamerasOfOneInstantAreOneFrameForThePace) {
  MatchFrontEnd front(config(), {});
  for (int i = 0; i < 10; ++i) {
    for (std::uint32_t camera = 0; camera < 2; ++camera) {
      SSL_WrapperPacket packet = frame(i);
      packet.mutable_detection()->set_camera_id(camera);
      front.add(packet);
    }
  }
  EXPECT_NEAR(front.recent_frame_gap_s(), 1.0 / 60.0, 1e-9);
}

// ---- The ball and the ball placement's target

TEST(MatchFrontEnd, TheBallIsNormalisedLikeTheRobotsWithItsVelocity) {
  for (const AttackDirection attacks : {AttackDirection::positive_x, AttackDirection::negative_x}) {
    SCOPED_TRACE(attacks == AttackDirection::positive_x ? "attacks +x" : "attacks -x");
    Recorder recorder;
    FrontEndConfig c = config();
    c.sampler.opponent_attacks = attacks;
    MatchFrontEnd front(c, recorder.handlers());
    for (int i = 0; i < 60; ++i) front.add(frame_with_ball(i));
    ASSERT_GE(recorder.seen.size(), 50u);
    const double turn = attacks == AttackDirection::positive_x ? 1.0 : -1.0;
    // From the second moment on: the first instant waits for the next frame to find every
    // camera, and its moment has that frame's ball (the newest seen when it is handed on).
    for (std::size_t k = 1; k < recorder.seen.size(); ++k) {
      const Seen& s = recorder.seen[k];
      SCOPED_TRACE(s.time_s);
      ASSERT_TRUE(s.ball.has_value());
      // The sample's robots and the ball turned alike: the robot's feed position to its
      // normalised one is the ball's.
      EXPECT_EQ(s.robots.at(0).position.x, turn * s.robots.at(0).feed_position.x);
      // The ball of the frame that completed the sample (instants lie on a 1 ms grid).
      const long frame_index = std::lround((s.time_s - 100.0) * 60.0);
      const Point feed = ball_at(static_cast<double>(frame_index) / 60.0);
      EXPECT_NEAR(s.ball->x, turn * feed.x, 0.01);
      EXPECT_NEAR(s.ball->y, turn * feed.y, 0.01);
      // Exact motion: the velocity is exact from the second frame on, but for floats' rounding.
      EXPECT_NEAR(s.ball_velocity.x, turn * ball_velocity.x, 2.0);
      EXPECT_NEAR(s.ball_velocity.y, turn * ball_velocity.y, 2.0);
      EXPECT_EQ(s.designated_position, std::nullopt);
    }
    ASSERT_TRUE(front.ball().state().has_value());
    EXPECT_NEAR(front.ball().state()->position.x, ball_at(59 / 60.0).x, 0.01);  // feed coordinates
  }
}

TEST(MatchFrontEnd, TheBallLeavesTheMomentsHalfASecondAfterItWasLastSeen) {
  Recorder recorder;
  MatchFrontEnd front(config(), recorder.handlers());
  int i = 0;
  for (; i < 60; ++i) front.add(frame_with_ball(i));
  const double last_seen = 100.0 + 59 / 60.0;
  for (; i < 180; ++i) front.add(frame_with_ball(i, std::nullopt));
  std::size_t with_ball = 0, without_ball = 0;
  for (const Seen& s : recorder.seen) {
    if (s.time_s <= last_seen + 0.49) {
      EXPECT_TRUE(s.ball.has_value()) << s.time_s;
      ++with_ball;
    } else if (s.time_s >= last_seen + 0.51) {
      EXPECT_FALSE(s.ball.has_value()) << s.time_s;
      EXPECT_EQ(s.ball_velocity, (Point{})) << s.time_s;
      ++without_ball;
    }
  }
  EXPECT_GT(with_ball, 80u);
  EXPECT_GT(without_ball, 50u);
  // Seen again: back in the moments, with no velocity from before.
  front.add(frame_with_ball(i, Point{0.0, 0.0}));
  ASSERT_TRUE(recorder.seen.back().ball.has_value());
  EXPECT_EQ(*recorder.seen.back().ball, (Point{0.0, 0.0}));
  EXPECT_EQ(recorder.seen.back().ball_velocity, (Point{}));
}

TEST(MatchFrontEnd, ANewStreamForgetsTheBall) {
  Recorder recorder;
  MatchFrontEnd front(config(), recorder.handlers());
  for (int i = 0; i < 30; ++i) front.add(frame_with_ball(i));
  ASSERT_TRUE(recorder.seen.back().ball.has_value());
  front.start_new_stream();
  EXPECT_FALSE(front.ball().state().has_value());
  // The next file's frames, on the same clock, without a ball: none in its moments.
  const std::size_t first = recorder.seen.size();
  for (int i = 0; i < 30; ++i) front.add(frame_with_ball(i, std::nullopt));
  ASSERT_GT(recorder.seen.size(), first);
  for (std::size_t k = first; k < recorder.seen.size(); ++k) {
    EXPECT_FALSE(recorder.seen[k].ball.has_value());
  }
}

TEST(MatchFrontEnd, TheDesignatedPositionIsGivenDuringABallPlacementOnly) {
  for (const AttackDirection attacks : {AttackDirection::positive_x, AttackDirection::negative_x}) {
    SCOPED_TRACE(attacks == AttackDirection::positive_x ? "attacks +x" : "attacks -x");
    Recorder recorder;
    FrontEndConfig c = config();
    c.sampler.opponent_attacks = attacks;
    MatchFrontEnd front(c, recorder.handlers());
    int i = 0;
    const auto run_until = [&](double t) {
      while (i / 60.0 < t) front.add(frame_with_ball(i++));
    };
    const Point target{1000.0, -2000.0};
    // A target in another state's message is no placement's (the game controller sends none
    // then, but says nothing of it either way).
    front.add_referee(referee_with_target(Referee::STOP, 1, target), 0.0);
    run_until(0.5);
    EXPECT_EQ(recorder.seen.back().game_state, GameState::stop);
    EXPECT_EQ(recorder.seen.back().designated_position, std::nullopt);

    front.add_referee(referee_with_target(Referee::BALL_PLACEMENT_BLUE, 2, target), 0.1);
    const std::size_t placing = recorder.seen.size();
    run_until(1.0);
    ASSERT_GT(recorder.seen.size(), placing);
    const double turn = attacks == AttackDirection::positive_x ? 1.0 : -1.0;
    for (std::size_t k = placing; k < recorder.seen.size(); ++k) {
      const Seen& s = recorder.seen[k];
      EXPECT_EQ(s.game_state, GameState::ball_placement);
      ASSERT_TRUE(s.designated_position.has_value());
      EXPECT_EQ(*s.designated_position, (Point{turn * target.x, turn * target.y}));
    }
    // A placement message without a target: none.
    front.add_referee(referee(Referee::BALL_PLACEMENT_BLUE, 2), 0.2);
    run_until(1.2);
    EXPECT_EQ(recorder.seen.back().game_state, GameState::ball_placement);
    EXPECT_EQ(recorder.seen.back().designated_position, std::nullopt);

    front.add_referee(referee_with_target(Referee::BALL_PLACEMENT_BLUE, 2, target), 0.3);
    run_until(1.4);
    EXPECT_TRUE(recorder.seen.back().designated_position.has_value());
    // Play resumes: no target, even if the message still carried one.
    front.add_referee(referee_with_target(Referee::NORMAL_START, 3, target), 0.4);
    run_until(2.0);
    EXPECT_EQ(recorder.seen.back().game_state, GameState::running);
    EXPECT_EQ(recorder.seen.back().designated_position, std::nullopt);
  }
}

TEST(MatchFrontEnd, TrackedVisionTakesTheTrackersBallAsItIs) {
  Recorder recorder;
  FrontEndConfig c = config();
  c.tracked_vision = true;
  c.sampler.opponent_attacks = AttackDirection::negative_x;
  MatchFrontEnd front(c, recorder.handlers());
  // Raw frames with a ball are ignored in this mode, their ball too.
  for (int i = 0; i < 10; ++i) front.add(frame_with_ball(i));
  EXPECT_FALSE(front.ball().state().has_value());
  // The tracker's ball stands still at (1.25, -0.5) m but says it moves at (2, 1) m/s: its
  // velocity is taken, not one made from its positions.
  for (int i = 0; i < 20; ++i) {
    const double t = 200.0 + i / 60.0;
    front.on_event(MatchEvent::tracked_vision(
        tracked_with_ball(static_cast<std::uint32_t>(i), t, {1.25, -0.5}, {2.0, 1.0}), t));
  }
  ASSERT_GE(recorder.seen.size(), 19u);
  for (const Seen& s : recorder.seen) {
    SCOPED_TRACE(s.time_s);
    ASSERT_TRUE(s.ball.has_value());
    EXPECT_NEAR(s.ball->x, -1250.0, 1e-3);  // millimetres, turned: the opponent attacks -x
    EXPECT_NEAR(s.ball->y, 500.0, 1e-3);
    EXPECT_NEAR(s.ball_velocity.x, -2000.0, 1e-3);
    EXPECT_NEAR(s.ball_velocity.y, -1000.0, 1e-3);
  }
  // Tracker frames without a ball: it leaves the moments half a second after the last one.
  for (int i = 20; i < 80; ++i) {
    const double t = 200.0 + i / 60.0;
    front.on_event(MatchEvent::tracked_vision(tracked(static_cast<std::uint32_t>(i), t, 1.5F), t));
  }
  EXPECT_FALSE(recorder.seen.back().ball.has_value());
}

}  // namespace
}  // namespace ssl_formation
