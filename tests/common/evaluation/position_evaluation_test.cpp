// The held-out evaluation in millimetres on hand-built streams with known motion: every
// baseline's error to 1e-5 against the formulas (the damped one's factor by least squares), the
// model's against its own predicted cells, the rows by phase of the game, percentiles, and the
// expected calibration error of a worked example.

#include "ssl_formation/evaluation/position_evaluation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/robot_tracker.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::evaluation {
namespace {

constexpr double frame_s = 0.05;      // 20 frames a second, one camera
constexpr double acceleration = 200;  // mm/s², robot 0 along +x
constexpr double start_x = -4000;

// Positions as the packets carry them (floats), so the expectations use the very same values.
double rounded(double mm) { return static_cast<double>(static_cast<float>(mm)); }
double accelerating_x(double t) { return rounded(start_x + 0.5 * acceleration * t * t); }
double circling_x(double t) { return rounded(1000.0 * std::cos(0.8 * t)); }
double circling_y(double t) { return rounded(1000.0 * std::sin(0.8 * t)); }
constexpr double still_x = 3000;
constexpr double still_y = -2000;

// Robot 0 accelerates along x, robot 1 circles, robot 2 stands still.
std::vector<SSL_WrapperPacket> packets_of(double seconds) {
  std::vector<SSL_WrapperPacket> packets;
  const int frames = static_cast<int>(std::lround(seconds / frame_s));
  for (int i = 0; i <= frames; ++i) {
    const double t = frame_s * i;
    DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = t;
    spec.yellow = {{0, {accelerating_x(t), 0.0}},
                   {1, {circling_x(t), circling_y(t)}},
                   {2, {still_x, still_y}}};
    packets.push_back(make_detection_packet(spec));
  }
  return packets;
}

RecordedMatch recorded(const std::vector<SSL_WrapperPacket>& packets) {
  RecordedMatch match;
  for (const SSL_WrapperPacket& packet : packets) {
    match.add_vision(packet, packet.detection().t_capture());
  }
  return match;
}

RecordedMatch stream(double seconds) { return recorded(packets_of(seconds)); }

Point position_of(std::uint32_t id, double t) {
  switch (id) {
    case 0:
      return {accelerating_x(t), 0.0};
    case 1:
      return {circling_x(t), circling_y(t)};
    default:
      return {still_x, still_y};
  }
}

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// The velocity as the evaluation takes it: a RobotTracker fed with every frame's position from
// the stream's start up to t, once its track has gone on for more than half the window.
std::optional<RobotTracker> tracker_at(std::uint32_t id, double t, double window) {
  RobotTracker tracker;
  for (int i = 0; frame_s * i <= t + 1e-9; ++i)
    tracker.observe(frame_s * i, position_of(id, frame_s * i));
  if (tracker.observations() < 2 || !(t - tracker.first_s() > window / 2.0)) return std::nullopt;
  return tracker;
}
std::optional<Point> velocity_at(std::uint32_t id, double t, double window) {
  const auto tracker = tracker_at(id, t, window);
  return tracker ? std::optional<Point>(tracker->velocity()) : std::nullopt;
}
std::optional<Point> acceleration_at(std::uint32_t id, double t, double window) {
  const auto tracker = tracker_at(id, t, window);
  return tracker ? std::optional<Point>(tracker->acceleration()) : std::nullopt;
}

TEST(PositionEvaluation, BaselineErrorsInMillimetresMatchTheKnownMotion) {
  PositionEvaluationConfig config;
  config.sampler.grid = Grid(6, 4);
  config.sampler.step_s = 0.5;
  config.sampler.sampling = Sampling::frame;
  config.steps = 2;  // 0.5 s and 1 s
  config.velocity_window_s = 0.1;
  const PositionEvaluation result = evaluate_positions(config, {stream(20.0)}, {stream(10.0)});
  ASSERT_EQ(result.all().size(), 2u);
  // The model, five baselines, then the model's pooled ablation.
  ASSERT_EQ(result.methods.size(), 7u);
  EXPECT_EQ(result.baselines_end, 6u);
  EXPECT_EQ(result.methods[6], ModelKind::motion);
  EXPECT_EQ(result.labels[0], "model");
  EXPECT_EQ(result.labels[3], "damped constant velocity");
  EXPECT_EQ(result.labels[6], "pooled model");
  EXPECT_EQ(result.methods[1], ModelKind::persistence);
  EXPECT_EQ(result.methods[2], ModelKind::constant_velocity);
  EXPECT_EQ(result.methods[3], ModelKind::damped_constant_velocity);
  EXPECT_EQ(result.methods[4], ModelKind::constant_acceleration);
  EXPECT_FALSE(result.test_has_referee);
  EXPECT_EQ(result.test_formations, 201u);

  for (int k = 1; k <= 2; ++k) {
    SCOPED_TRACE(k);
    const double h = 0.5 * k;
    const double w = config.velocity_window_s;
    // The damping factor by least squares over training instants that have a velocity and a
    // position h later: the training stream is the same motion over 20 s.
    double dot = 0;
    double norm = 0;
    for (int i = 0; frame_s * i + h <= 20.0 + 1e-9; ++i) {
      const double t = frame_s * i;
      for (std::uint32_t id = 0; id < 3; ++id) {
        const std::optional<Point> v = velocity_at(id, t, w);
        if (!v) continue;
        const Point now = position_of(id, t);
        const Point later = position_of(id, t + h);
        const Point extrapolated{v->x * h, v->y * h};
        dot += (later.x - now.x) * extrapolated.x + (later.y - now.y) * extrapolated.y;
        norm += extrapolated.x * extrapolated.x + extrapolated.y * extrapolated.y;
      }
    }
    const double damping = dot / norm;

    // Every test instant with a truth h later; robots without a velocity yet (the first
    // window) extrapolate nothing.
    std::array<double, 5> sum{};
    std::size_t robots = 0;
    for (int i = 0; frame_s * i + h <= 10.0 + 1e-9; ++i) {
      const double t = frame_s * i;
      for (std::uint32_t id = 0; id < 3; ++id) {
        const Point now = position_of(id, t);
        const Point later = position_of(id, t + h);
        const Point velocity = velocity_at(id, t, w).value_or(Point{});
        sum[1] += distance(now, later);
        sum[2] += distance({now.x + velocity.x * h, now.y + velocity.y * h}, later);
        sum[3] +=
            distance({now.x + damping * velocity.x * h, now.y + damping * velocity.y * h}, later);
        const Point a = acceleration_at(id, t, w).value_or(Point{});
        sum[4] += distance({now.x + velocity.x * h + 0.5 * a.x * h * h,
                            now.y + velocity.y * h + 0.5 * a.y * h * h},
                           later);
        ++robots;
      }
    }
    const HorizonScore& score = result.all()[static_cast<std::size_t>(k - 1)];
    EXPECT_DOUBLE_EQ(score.horizon_s, h);
    for (std::size_t m = 1; m < 5; ++m) {
      SCOPED_TRACE(std::string(describe(result.methods[m]).label));
      ASSERT_EQ(score.methods[m].error.count(), robots);
      // The tracker runs on the data clock's times, which differ from frame_s * i by a rounding.
      // Constant acceleration scales that rounding by h^2.
      EXPECT_NEAR(score.methods[m].error.mean(), sum[m] / static_cast<double>(robots),
                  m == 4 ? 1e-4 : 1e-5);
    }
    // Constant velocity misses the accelerating robot's a * h^2 / 2; persistence misses more.
    EXPECT_GT(score.methods[1].error.mean(), score.methods[2].error.mean());
    ASSERT_EQ(score.methods[0].error.count(), robots);
    // Without a referee every instant is running play: the row "running" is the row "all".
    const HorizonScore& running =
        result.rows[state_row_of(GamePhase::running)][static_cast<std::size_t>(k - 1)];
    EXPECT_EQ(running.methods[2].error.count(), robots);
    EXPECT_DOUBLE_EQ(running.methods[2].error.mean(), score.methods[2].error.mean());
    EXPECT_EQ(result.rows[state_row_of(GamePhase::halt)][0].methods[0].error.count(), 0u);
  }
}

TEST(PositionEvaluation, TheModelIsScoredAtTheCentreOfItsPredictedCell) {
  PositionEvaluationConfig config;
  config.model = ModelKind::paper;
  config.sampler.grid = Grid(3, 2);
  config.sampler.step_s = 1.0;
  config.sampler.sampling = Sampling::frame;
  const std::vector<SSL_WrapperPacket> data = packets_of(12.0);
  const PositionEvaluation result = evaluate_positions(config, {recorded(data)}, {recorded(data)});

  // The same table and predictions by hand.
  Training training(config.sampler, TransitionTable(config.sampler.grid));
  for (const auto& packet : data) training.add(packet);
  std::vector<Formation> formations;
  FormationSampler sampler(config.sampler,
                           [&](const FormationSample& s) { formations.push_back(s.formation); });
  for (const auto& packet : data) sampler.add(packet);
  const Grid& grid = config.sampler.grid;
  const FieldSize field;
  double sum = 0;
  std::size_t robots = 0;
  std::uint64_t right = 0;
  for (const Formation& now : formations) {
    const Formation* truth = formation_near(formations, now.time_s + 1.0, 0.05);
    if (!truth) continue;
    const Prediction prediction = predict(training.stored_table().table, now, 1);
    for (const RobotPrediction& robot : prediction.steps[0].robots) {
      const FormationRobot* actual = truth->find(robot.robot_id);
      sum += distance(grid.centre_of(robot.position, field), actual->feed_position);
      right += robot.position == actual->cell;
      ++robots;
    }
  }
  const HorizonScore& score = result.all()[0];
  ASSERT_EQ(score.methods[0].error.count(), robots);
  EXPECT_NEAR(score.methods[0].error.mean(), sum / static_cast<double>(robots), 1e-6);
  EXPECT_EQ(score.methods[0].cells.exact_cells, right);
  EXPECT_EQ(score.robot.n, robots);
}

TEST(PositionEvaluation, StepSamplingStillTakesVelocitiesFromEveryObservedFrame) {
  // One formation a step for the paper's model, but the baselines run as they would live, on
  // every frame: their velocities come from the robots' own positions frame by frame.
  PositionEvaluationConfig config;
  config.model = ModelKind::paper;
  config.sampler.grid = Grid(6, 4);
  config.sampler.step_s = 0.5;
  config.sampler.sampling = Sampling::step;
  const PositionEvaluation step = evaluate_positions(config, {stream(20.0)}, {stream(10.0)});
  const HorizonScore& score = step.all()[0];
  ASSERT_GT(score.methods[1].error.count(), 0u);
  EXPECT_EQ(step.test_formations, 21u);
  // Constant velocity beats persistence on this motion only if it had velocities.
  EXPECT_LT(score.methods[2].error.mean(), 0.5 * score.methods[1].error.mean());
}

TEST(PositionEvaluation, EveryMeanHasAnIntervalFromBlocksThatAddUpToIt) {
  PositionEvaluationConfig config;
  config.sampler.grid = Grid(6, 4);
  config.sampler.step_s = 0.5;
  config.sampler.sampling = Sampling::frame;
  config.steps = 2;
  config.bootstrap.block_s = 1.0;  // ten blocks in the 10 s test stream
  const PositionEvaluation result = evaluate_positions(config, {stream(20.0)}, {stream(10.0)});
  for (const std::size_t row : {std::size_t{0}, state_row_of(GamePhase::running)}) {
    for (const HorizonScore& score : result.rows[row]) {
      SCOPED_TRACE(score.horizon_s);
      // The blocks hold every scored robot once, and their sums make each method's mean.
      std::uint64_t robots = 0;
      std::vector<double> sums(score.methods.size(), 0.0);
      for (const auto& [block, block_sums] : score.blocks) {
        EXPECT_EQ(block.stream, 0u);
        robots += block_sums.robots;
        for (std::size_t m = 0; m < sums.size(); ++m) sums[m] += block_sums.error_sums[m];
      }
      EXPECT_EQ(score.blocks.size(), 10u);
      ASSERT_EQ(robots, score.methods[0].error.count());
      ASSERT_EQ(score.intervals.mean.size(), score.methods.size());
      for (std::size_t m = 0; m < sums.size(); ++m) {
        const double mean = score.methods[m].error.mean();
        EXPECT_NEAR(sums[m] / static_cast<double>(robots), mean, 1e-9);
        EXPECT_LE(score.intervals.mean[m].low, mean);
        EXPECT_GE(score.intervals.mean[m].high, mean);
        EXPECT_LT(score.intervals.mean[m].low, score.intervals.mean[m].high);
      }
      // The ratios are to the baseline of lowest mean, which is 1 against itself.
      const std::optional<std::size_t> best = result.best_baseline(score);
      ASSERT_TRUE(best.has_value());
      for (std::size_t m = 1; m < score.methods.size(); ++m) {
        EXPECT_LE(score.methods[*best].error.mean(), score.methods[m].error.mean());
      }
      EXPECT_LT(*best, result.baselines_end);  // never the pooled model
      ASSERT_EQ(score.intervals.ratio.size(), score.methods.size());
      EXPECT_DOUBLE_EQ(score.intervals.ratio[*best].low, 1.0);
      EXPECT_DOUBLE_EQ(score.intervals.ratio[*best].high, 1.0);
      // The model over every other method, drawn from the same resamples: over the best
      // baseline it is the same interval as the ratios'.
      ASSERT_EQ(score.intervals.model_ratio.size(), score.methods.size() - 1);
      EXPECT_DOUBLE_EQ(score.intervals.model_ratio[*best - 1].low, score.intervals.ratio[0].low);
      EXPECT_DOUBLE_EQ(score.intervals.model_ratio[*best - 1].high, score.intervals.ratio[0].high);
    }
  }
  // Without the bootstrap nothing is kept or drawn.
  config.bootstrap.resamples = 0;
  const PositionEvaluation plain = evaluate_positions(config, {stream(20.0)}, {stream(10.0)});
  EXPECT_TRUE(plain.all()[0].blocks.empty());
  EXPECT_TRUE(plain.all()[0].intervals.mean.empty());
  EXPECT_DOUBLE_EQ(plain.all()[0].methods[0].error.mean(), result.all()[0].methods[0].error.mean());
}

TEST(PositionEvaluation, PercentilesInterpolateBetweenOrderStatistics) {
  ErrorStats stats;
  for (const double e : {40.0, 10.0, 30.0, 20.0, 50.0}) stats.add(e);
  EXPECT_DOUBLE_EQ(stats.mean(), 30.0);
  EXPECT_DOUBLE_EQ(stats.median(), 30.0);
  EXPECT_DOUBLE_EQ(stats.percentile(90), 46.0);
  EXPECT_DOUBLE_EQ(stats.percentile(0), 10.0);
  EXPECT_DOUBLE_EQ(stats.percentile(100), 50.0);
  EXPECT_DOUBLE_EQ(ErrorStats{}.median(), 0.0);
}

TEST(PositionEvaluation, ExpectedCalibrationErrorOfAWorkedExample) {
  // Ten predictions: four at 0.15 (one right), six at 0.85 (three right).
  // Bin 1: 4 predictions, confidence 0.15, observed 0.25: |0.1| x 4/10 = 0.04.
  // Bin 8: 6 predictions, confidence 0.85, observed 0.5: |0.35| x 6/10 = 0.21. ECE = 0.25.
  Calibration calibration;
  for (int i = 0; i < 4; ++i) calibration.add(0.15, i == 0);
  for (int i = 0; i < 6; ++i) calibration.add(0.85, i < 3);
  EXPECT_NEAR(expected_calibration_error(calibration), 0.25, 1e-12);
  // Brier: (4 x ... ) : 1 x 0.85² + 3 x 0.15² + 3 x 0.15² + 3 x 0.85², over 10.
  EXPECT_NEAR(calibration.brier(), (0.7225 + 3 * 0.0225 + 3 * 0.0225 + 3 * 0.7225) / 10, 1e-12);
  // A perfectly calibrated one.
  Calibration perfect;
  for (int i = 0; i < 10; ++i) perfect.add(0.35, i < 3);
  EXPECT_NEAR(expected_calibration_error(perfect), 0.05, 1e-12);  // 0.35 stated, 0.30 seen
  EXPECT_EQ(expected_calibration_error(Calibration{}), 0.0);
}

}  // namespace
}  // namespace ssl_formation::evaluation
