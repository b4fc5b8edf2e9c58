// The opponent's kick-offs remembered whole (set_play_memory.hpp): what the recorder keeps, what
// a kick-off now recalls of them, and merging.

#include "ssl_formation/motion_model/set_play_memory.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace ssl_formation {
namespace {

constexpr double frame_s = 1.0 / 60.0;
constexpr std::uint32_t runner = 2;

// Six robots at their kick-off places, `shift_mm` off along x (runs vary). After NORMAL_START
// (at `kick_s` into the kick-off) robot 2 runs from (-1000, 0) to (-1000, 1500) at 1 m/s and
// stays there; the others stand.
Formation kickoff_formation(double time_s, double kick_s, double shift_mm, double start_s) {
  Formation formation;
  formation.time_s = time_s;
  for (std::uint32_t id = 0; id < 6; ++id) {
    FormationRobot robot;
    robot.robot_id = id;
    robot.position = {-500.0 - 700.0 * id + shift_mm, 300.0 * (id % 3)};
    if (id == runner) {
      const double run_s = std::clamp(time_s - start_s - kick_s, 0.0, 1.5);
      robot.position = {-1000.0 + shift_mm, 1000.0 * run_s};
    }
    robot.feed_position = robot.position;
    formation.robots.push_back(robot);
  }
  return formation;
}

// Records one kick-off: 2 s of preparation, NORMAL_START, 3 s of its restart window, then
// running play for as long as the recorder follows it.
void record_kickoff(SetPlayRecorder& recorder, SetPlayMemory& memory, double start_s,
                    double shift_mm) {
  constexpr double kick_s = 2.0;
  for (double t = start_s; t < start_s + 10.0; t += frame_s) {
    const double into = t - start_s;
    const bool preparing = into < kick_s;
    const GamePhase phase = into < kick_s + GamePhaseTracker::restart_window_s
                                ? GamePhase::kickoff_opponent
                                : GamePhase::running;
    const double since = preparing ? into : into - kick_s;
    recorder.record(t, phase, preparing, since, kickoff_formation(t, kick_s, shift_mm, start_s),
                    memory);
  }
}

SetPlayMemory three_kickoffs() {
  SetPlayMemory memory;
  SetPlayRecorder recorder(1.0);
  record_kickoff(recorder, memory, 100.0, 0.0);
  record_kickoff(recorder, memory, 400.0, 80.0);
  record_kickoff(recorder, memory, 700.0, -60.0);
  recorder.finish(memory);
  return memory;
}

TEST(SetPlayMemory, RecordsEachKickOffWholeTenTimesASecondAndTheSecondsAfterIt) {
  const SetPlayMemory memory = three_kickoffs();
  ASSERT_EQ(memory.episodes().size(), 3u);
  for (const SetPlayEpisode& episode : memory.episodes()) {
    ASSERT_TRUE(SetPlayMemory::valid_episode(episode));
    // 2 s prepared, 3 s taken, then the trail (1 s and a snapshot's slack), 10 a second.
    const auto count = [&](SetPlayStage stage) {
      return std::count_if(episode.snapshots.begin(), episode.snapshots.end(),
                           [&](const SetPlaySnapshot& s) { return s.stage == stage; });
    };
    EXPECT_NEAR(count(SetPlayStage::preparation), 20, 1);
    EXPECT_NEAR(count(SetPlayStage::taken), 30, 1);
    EXPECT_NEAR(count(SetPlayStage::over), 11, 2);
    EXPECT_EQ(episode.snapshots.front().seen, 0x3fU);
  }
}

TEST(SetPlayMemory, AKickOffNowRecallsWhereTheRobotWentInTheNearestEarlierOnes) {
  const SetPlayMemory memory = three_kickoffs();
  // A fourth run, 0.2 s after NORMAL_START: robot 2 has just set off.
  const double start_s = 1000.0, kick_s = 2.0;
  const Formation now = kickoff_formation(start_s + kick_s + 0.2, kick_s, 30.0, start_s);
  SetPlayAdvice advice;
  memory.recall(now, SetPlayStage::taken, 0.2, 0.5, 3, advice);
  ASSERT_TRUE(advice.any);
  ASSERT_EQ(advice.robots.size(), now.robots.size());
  const SetPlayAdvice::Robot& robot = advice.robots[runner];
  // 0.5, 1 and 1.5 s on: at 0.7 s, 1.2 s and the end of its run (1.5 m), give or take how far
  // apart the runs were.
  const double expected_y[] = {700.0, 1200.0, 1500.0};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(robot.position[k].y, expected_y[k], 30.0) << k;
    EXPECT_NEAR(robot.position[k].x, -1000.0 + 30.0, 80.0) << k;
    EXPECT_GT(robot.weight[k], 0.7) << k;
  }
  // A standing robot stays where it stands.
  EXPECT_NEAR(advice.robots[4].position[1].y, now.robots[4].position.y, 1.0);

  // Another stage, or seconds since the command far from any run's, recall nothing.
  memory.recall(now, SetPlayStage::preparation, 9.0, 0.5, 3, advice);
  EXPECT_FALSE(advice.any);
  memory.recall(now, SetPlayStage::taken, 6.0, 0.5, 3, advice);
  EXPECT_FALSE(advice.any);
}

TEST(SetPlayMemory, AFormationUnlikeAnyEarlierKickOffWeighsLittle) {
  const SetPlayMemory memory = three_kickoffs();
  Formation now = kickoff_formation(1002.2, 2.0, 0.0, 1000.0);
  for (FormationRobot& robot : now.robots) robot.position.y += 1500.0;  // a team 1.5 m aside
  SetPlayAdvice advice;
  memory.recall(now, SetPlayStage::taken, 0.2, 0.5, 3, advice);
  for (const SetPlayAdvice::Robot& robot : advice.robots) EXPECT_LT(robot.weight[0], 0.01);
}

TEST(SetPlayMemory, MergingInEitherOrderEqualsRecordingBothStreams) {
  SetPlayMemory first, second, both;
  {
    SetPlayRecorder recorder(1.0);
    record_kickoff(recorder, first, 100.0, 0.0);
    record_kickoff(recorder, first, 400.0, 80.0);
    recorder.finish(first);
  }
  {
    SetPlayRecorder recorder(1.0);
    record_kickoff(recorder, second, 700.0, -60.0);
    recorder.finish(second);
  }
  SetPlayMemory a = first, b = second;
  a.merge(second);
  b.merge(first);
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, three_kickoffs());
  EXPECT_NE(first, a);
  // And they recall the same: the index follows the episodes whatever the order they came in.
  const Formation now = kickoff_formation(1002.4, 2.0, 30.0, 1000.0);
  SetPlayAdvice from_a, from_b, from_all;
  a.recall(now, SetPlayStage::taken, 0.4, 0.5, 3, from_a);
  b.recall(now, SetPlayStage::taken, 0.4, 0.5, 3, from_b);
  three_kickoffs().recall(now, SetPlayStage::taken, 0.4, 0.5, 3, from_all);
  ASSERT_TRUE(from_all.any);
  for (std::size_t r = 0; r < now.robots.size(); ++r) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(from_a.robots[r].position[k], from_all.robots[r].position[k]) << r << " " << k;
      EXPECT_EQ(from_b.robots[r].position[k], from_all.robots[r].position[k]) << r << " " << k;
      EXPECT_EQ(from_b.robots[r].weight[k], from_all.robots[r].weight[k]) << r << " " << k;
    }
  }
}

TEST(SetPlayMemory, AFullMemoryDropsTheLastInItsOrderAndRecallsOnlyWhatItKeeps) {
  SetPlayMemory memory;
  SetPlayRecorder recorder(1.0);
  for (std::size_t k = 0; k < SetPlayMemory::max_episodes + 3; ++k) {
    record_kickoff(recorder, memory, 100.0 + 20.0 * static_cast<double>(k),
                   static_cast<double>(k % 7) * 10.0 - 30.0);
  }
  recorder.finish(memory);
  EXPECT_EQ(memory.episodes().size(), SetPlayMemory::max_episodes);
  EXPECT_TRUE(std::is_sorted(memory.episodes().begin(), memory.episodes().end()));
  const Formation now = kickoff_formation(5002.2, 2.0, 0.0, 5000.0);
  SetPlayAdvice advice;
  memory.recall(now, SetPlayStage::taken, 0.2, 0.5, 2, advice);
  ASSERT_TRUE(advice.any);
  EXPECT_NEAR(advice.robots[runner].position[0].y, 700.0, 30.0);
}

TEST(SetPlayMemory, RunningPlayAloneRecordsNothing) {
  SetPlayMemory memory;
  SetPlayRecorder recorder(1.0);
  for (double t = 0.0; t < 20.0; t += frame_s) {
    recorder.record(t, GamePhase::running, false, t, kickoff_formation(t, 2.0, 0.0, 0.0), memory);
  }
  recorder.finish(memory);
  EXPECT_TRUE(memory.empty());
}

TEST(SetPlayMemory, AnEpisodeWithSnapshotsOutOfOrderIsInvalidAndNotKept) {
  SetPlayMemory memory = three_kickoffs();
  SetPlayEpisode bad = memory.episodes().front();
  std::swap(bad.snapshots[3], bad.snapshots[4]);
  EXPECT_FALSE(SetPlayMemory::valid_episode(bad));
  memory.add(bad);
  EXPECT_EQ(memory.episodes().size(), 3u);
}

}  // namespace
}  // namespace ssl_formation
