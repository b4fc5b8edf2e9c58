// The baselines (models/src/baselines.cpp) through the factory, pipeline and Training.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/robot_tracker.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation {
namespace {

constexpr double start_s = 100.0;
constexpr double step_s = 0.5;

// A robot's position (mm, feed coordinates) `tau` seconds into the stream.
using Path = std::function<Point(double tau)>;

// Frames at 60 Hz, stamped to the millisecond as the data clock's instants are (frame sampling
// takes instants 1 ms apart), so that every sample's time is its frame's capture time.
double frame_time(int i) { return start_s + std::round(i * 1000.0 / 60.0) * 0.001; }

std::vector<SSL_WrapperPacket> stream(double seconds, const std::vector<Path>& robots,
                                      TeamColor color = TeamColor::yellow) {
  std::vector<SSL_WrapperPacket> packets;
  for (int i = 0; i <= static_cast<int>(std::lround(seconds * 60.0)); ++i) {
    DetectionFrameSpec spec;
    spec.frame_number = static_cast<std::uint32_t>(i);
    spec.t_capture = frame_time(i);
    for (std::size_t id = 0; id < robots.size(); ++id) {
      (color == TeamColor::yellow ? spec.yellow : spec.blue)
          .push_back({static_cast<std::uint32_t>(id), robots[id](frame_time(i) - start_s)});
    }
    packets.push_back(make_detection_packet(spec));
  }
  return packets;
}

SamplerConfig sampler(TeamColor color = TeamColor::yellow,
                      AttackDirection attacks = AttackDirection::positive_x) {
  SamplerConfig config = sampler_config_for(ModelKind::constant_velocity);
  config.opponent_color = color;
  config.opponent_attacks = attacks;
  return config;  // a 9 x 6 m field, 3 x 2 cells, frame sampling, 0.5 s step
}

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// The last prediction a pipeline made, copied.
struct Last {
  Formation formation;
  Prediction prediction;
  std::uint64_t predictions = 0;
};

void feed(PredictionPipeline& pipeline, const std::vector<SSL_WrapperPacket>& packets, Last& last) {
  for (const SSL_WrapperPacket& packet : packets) pipeline.add(packet);
  last.predictions = pipeline.predictions();
}

Last run(ModelKind kind, const std::vector<SSL_WrapperPacket>& packets,
         const SamplerConfig& config = sampler(),
         std::unique_ptr<Forecaster> forecaster = nullptr) {
  Last last;
  const auto keep = [&](const PredictedFormation& p) {
    last.formation = p.formation();
    last.prediction = p.prediction;
  };
  const PredictionConfig pc{config, 2, kind};
  if (forecaster) {
    PredictionPipeline pipeline(pc, std::move(forecaster), keep);
    feed(pipeline, packets, last);
  } else {
    PredictionPipeline pipeline(pc, keep);
    feed(pipeline, packets, last);
  }
  return last;
}

const RobotPrediction& robot(const Last& last, int step, std::uint32_t id) {
  for (const RobotPrediction& r : last.prediction.steps.at(static_cast<std::size_t>(step)).robots) {
    if (r.robot_id == id) return r;
  }
  throw std::runtime_error("no prediction of robot " + std::to_string(id));
}

// Robot 0 drives at a constant velocity, robot 1 accelerates constantly, robot 2 stands.
constexpr Point velocity{600.0, -300.0};
constexpr Point acceleration{400.0, -100.0};
const Point still{2500.0, 2000.0};
const std::vector<Path> known_motion{
    [](double t) {
      return Point{-3000.0 + velocity.x * t, 1500.0 + velocity.y * t};
    },
    [](double t) {
      return Point{-3500.0 + 200.0 * t + 0.5 * acceleration.x * t * t,
                   -1500.0 + 0.5 * acceleration.y * t * t};
    },
    [](double) { return still; }};

// The predicted cells and states say what the predicted positions do.
void expect_consistent(const Last& last, AttackDirection attacks) {
  const Grid grid(3, 2);
  const StateCodec codec(grid);
  const FieldSize field;
  for (const PredictedStep& step : last.prediction.steps) {
    ASSERT_EQ(step.robots.size(), last.formation.robots.size());
    Point sum{};
    for (const RobotPrediction& r : step.robots) {
      sum.x += r.normalised_position.x;
      sum.y += r.normalised_position.y;
    }
    const double n = static_cast<double>(step.robots.size());
    EXPECT_EQ(step.centroid, grid.cell_of(Point{sum.x / n, sum.y / n}, field));
    for (const RobotPrediction& r : step.robots) {
      SCOPED_TRACE(r.robot_id);
      EXPECT_EQ(r.feed_position, normalise(r.normalised_position, attacks));
      EXPECT_EQ(r.position, grid.cell_of(r.normalised_position, field));
      const FormationRobot* now = last.formation.find(r.robot_id);
      ASSERT_NE(now, nullptr);
      EXPECT_EQ(r.previous, now->cell);
      EXPECT_EQ(r.state, codec.encode(RobotState{step.centroid, r.position, now->cell}));
    }
  }
}

TEST(Baselines, PersistencePredictsWhereEveryRobotIsNow) {
  const Last last = run(ModelKind::persistence, stream(4.0, known_motion));
  ASSERT_GT(last.predictions, 200u);
  ASSERT_EQ(last.prediction.steps.size(), 2u);
  const double tau = last.formation.time_s - start_s;
  for (int step = 0; step < 2; ++step) {
    for (std::uint32_t id = 0; id < 3; ++id) {
      EXPECT_LT(distance(robot(last, step, id).feed_position, known_motion[id](tau)), 1e-3);
    }
  }
  expect_consistent(last, AttackDirection::positive_x);
}

TEST(Baselines, ConstantVelocityFollowsTheRobotAtConstantVelocityButMissesTheAcceleration) {
  const Last last = run(ModelKind::constant_velocity, stream(4.0, known_motion));
  const double tau = last.formation.time_s - start_s;
  for (int step = 0; step < 2; ++step) {
    SCOPED_TRACE(step);
    const double h = step_s * (step + 1);
    EXPECT_LT(distance(robot(last, step, 0).feed_position, known_motion[0](tau + h)), 0.1);
    EXPECT_LT(distance(robot(last, step, 2).feed_position, still), 1e-3);
    // Where the accelerating robot will be, less a h^2 / 2.
    const Point truth = known_motion[1](tau + h);
    const Point missed{truth.x - 0.5 * acceleration.x * h * h,
                       truth.y - 0.5 * acceleration.y * h * h};
    EXPECT_LT(distance(robot(last, step, 1).feed_position, missed), 0.1);
    EXPECT_NEAR(distance(robot(last, step, 1).feed_position, truth),
                0.5 * std::hypot(acceleration.x, acceleration.y) * h * h, 0.1);
  }
  expect_consistent(last, AttackDirection::positive_x);
}

TEST(Baselines, ConstantAccelerationFollowsBothMovingRobots) {
  const Last last = run(ModelKind::constant_acceleration, stream(4.0, known_motion));
  const double tau = last.formation.time_s - start_s;
  for (int step = 0; step < 2; ++step) {
    SCOPED_TRACE(step);
    const double h = step_s * (step + 1);
    EXPECT_LT(distance(robot(last, step, 0).feed_position, known_motion[0](tau + h)), 0.1);
    EXPECT_LT(distance(robot(last, step, 1).feed_position, known_motion[1](tau + h)), 0.1);
    EXPECT_LT(distance(robot(last, step, 2).feed_position, still), 1e-3);
  }
  expect_consistent(last, AttackDirection::positive_x);
}

TEST(Baselines, PositionsAreInTheFeedsCoordinatesWhenTheOpponentAttacksMinusX) {
  const SamplerConfig config = sampler(TeamColor::blue, AttackDirection::negative_x);
  const Last last =
      run(ModelKind::constant_velocity, stream(4.0, known_motion, TeamColor::blue), config);
  const double tau = last.formation.time_s - start_s;
  const Point truth = known_motion[0](tau + 1.0);
  EXPECT_LT(distance(robot(last, 1, 0).feed_position, truth), 0.1);
  EXPECT_LT(distance(robot(last, 1, 0).normalised_position, Point{-truth.x, -truth.y}), 0.1);
  expect_consistent(last, AttackDirection::negative_x);
}

TEST(Baselines, DampedOnesExtrapolateUndampedBeforeAnyTraining) {
  const auto packets = stream(4.0, known_motion);
  const Last plain = run(ModelKind::constant_velocity, packets);
  const Last damped = run(ModelKind::damped_constant_velocity, packets);
  for (std::uint32_t id = 0; id < 3; ++id) {
    EXPECT_EQ(robot(damped, 1, id).feed_position, robot(plain, 1, id).feed_position);
  }
}

// ---- The damped baselines, trained ------------------------------------------------------------

// Robot 0 circles at an angular speed that makes it travel, over one step, half as far along its
// velocity as the velocity says: sin(w h) / (w h) = 1/2. Robot 1 stands.
constexpr double half_chord = 1.8954942670339809;  // x with sin(x) / x = 1/2
constexpr double omega = half_chord / step_s;
std::vector<Path> circling(double phase, double w = omega) {
  return {
      [phase, w](double t) {
        return Point{-1500.0 + 1000.0 * std::cos(w * t + phase), 1000.0 * std::sin(w * t + phase)};
      },
      [](double) { return still; }};
}

ModelSettings settings() {
  ModelSettings s;
  s.step_s = step_s;
  s.horizons = 2;
  return s;
}

std::unique_ptr<Training> train(ModelKind kind,
                                const std::vector<std::vector<SSL_WrapperPacket>>& streams) {
  auto training = std::make_unique<Training>(TrainingConfig{sampler(), std::nullopt, false}, kind,
                                             make_learner(kind, settings()));
  for (const auto& packets : streams) {
    training->start_new_stream();
    for (const SSL_WrapperPacket& packet : packets) training->add(packet);
  }
  return training;
}

// Each sample's robots with what the baselines' tracker says of them then (RobotTracker, once
// its track has run half the 0.1 s velocity window), by hand.
struct Known {
  double time_s;
  Point position;
  bool moving;
  Point velocity;
  Point acceleration;
};
std::vector<std::vector<Known>> by_hand(const std::vector<SSL_WrapperPacket>& packets) {
  std::vector<Formation> formations;
  FormationSampler s(sampler(),
                     [&](const FormationSample& f) { formations.push_back(f.formation); });
  for (const SSL_WrapperPacket& packet : packets) s.add(packet);
  std::vector<std::vector<Known>> robots(2);
  std::vector<RobotTracker> trackers(2);
  for (const Formation& f : formations) {
    for (const FormationRobot& r : f.robots) {
      RobotTracker& tracker = trackers[r.robot_id];
      tracker.observe(f.time_s, r.position);
      const bool moving = tracker.observations() >= 2 && f.time_s - tracker.first_s() > 0.05;
      robots[r.robot_id].push_back(
          {f.time_s, r.position, moving, tracker.velocity(), tracker.acceleration()});
    }
  }
  return robots;
}

// The least-squares factors of step k by hand, over every robot and sample with a record of it
// k steps before; `pairs` counts them.
struct Factors {
  double velocity = 1.0;
  double acceleration = 0.0;
};
Factors fit(const std::vector<std::vector<Known>>& robots, int k, bool with_acceleration,
            std::uint64_t& pairs) {
  const double h = step_s * k;
  double vv = 0, va = 0, aa = 0, dv = 0, da = 0;
  for (const auto& seen : robots) {
    for (std::size_t j = 0; j < seen.size(); ++j) {
      for (std::size_t i = 0; i < j; ++i) {
        if (std::abs(seen[i].time_s - (seen[j].time_s - h)) > 1e-6 || !seen[i].moving) continue;
        const Point d{seen[j].position.x - seen[i].position.x,
                      seen[j].position.y - seen[i].position.y};
        const Point v{seen[i].velocity.x * h, seen[i].velocity.y * h};
        const Point a{seen[i].acceleration.x * h * h / 2, seen[i].acceleration.y * h * h / 2};
        vv += v.x * v.x + v.y * v.y;
        va += v.x * a.x + v.y * a.y;
        aa += a.x * a.x + a.y * a.y;
        dv += d.x * v.x + d.y * v.y;
        da += d.x * a.x + d.y * a.y;
        ++pairs;
      }
    }
  }
  if (!with_acceleration) return {dv / vv, 0.0};
  const double det = vv * aa - va * va;
  return {(dv * aa - da * va) / det, (da * vv - dv * va) / det};
}

TEST(DampedBaselines, FactorsAreFittedByLeastSquaresAndExtrapolatedWith) {
  const auto training_stream = stream(8.0, circling(0.0));
  const auto known = by_hand(training_stream);
  const auto test_stream = stream(3.0, circling(1.0));
  const auto test = by_hand(test_stream);
  for (const ModelKind kind :
       {ModelKind::damped_constant_velocity, ModelKind::damped_constant_acceleration}) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const bool with_acceleration = kind == ModelKind::damped_constant_acceleration;
    const auto training = train(kind, {training_stream});
    std::uint64_t pairs = 0;
    const Factors one = fit(known, 1, with_acceleration, pairs);
    const Factors two = fit(known, 2, with_acceleration, pairs);
    EXPECT_EQ(training->learner().progress(), pairs);
    EXPECT_GT(pairs, 2u * 400u);
    // Velocity alone, the circle's own factor: sin(w h) / (w h) = 1/2 (the tracker's lag moves
    // it a little). With the acceleration, the tracker's acceleration lags the turning robot's
    // enough to shift the velocity's factor too: only the fit by hand says what they are.
    if (!with_acceleration) {
      EXPECT_NEAR(one.velocity, 0.5, 0.05);
    }

    TableMetadata metadata;
    metadata.step_s = step_s;
    const Last last = run(kind, test_stream, sampler(), training->learner().forecaster(metadata));
    ASSERT_GT(last.predictions, 100u);
    const Known& now = test[0].back();
    ASSERT_EQ(now.time_s, last.formation.time_s);
    ASSERT_TRUE(now.moving);
    for (int step = 0; step < 2; ++step) {
      SCOPED_TRACE(step);
      const double h = step_s * (step + 1);
      const Factors f = step == 0 ? one : two;
      const Point expected{
          now.position.x + f.velocity * now.velocity.x * h +
              (with_acceleration ? f.acceleration * now.acceleration.x * h * h / 2 : 0.0),
          now.position.y + f.velocity * now.velocity.y * h +
              (with_acceleration ? f.acceleration * now.acceleration.y * h * h / 2 : 0.0)};
      EXPECT_LT(distance(robot(last, step, 0).feed_position, expected), 1e-6);
      EXPECT_LT(distance(robot(last, step, 1).feed_position, still), 1e-3);
    }
    // Damped to about half, the prediction one step ahead lands near the chord's projection.
    const Point undamped{now.position.x + now.velocity.x * step_s,
                         now.position.y + now.velocity.y * step_s};
    EXPECT_GT(distance(robot(last, 0, 0).feed_position, undamped), 700.0);
  }
}

TEST(DampedBaselines, TheUndampedOnesLearnNothing) {
  const auto training_stream = stream(4.0, circling(0.0));
  const auto training = train(ModelKind::constant_velocity, {training_stream});
  EXPECT_EQ(training->learner().progress(), 0u);
  const auto test_stream = stream(2.0, circling(1.0));
  const Last trained = run(ModelKind::constant_velocity, test_stream, sampler(),
                           training->learner().forecaster(TableMetadata{}));
  const Last fresh = run(ModelKind::constant_velocity, test_stream);
  EXPECT_EQ(robot(trained, 1, 0).feed_position, robot(fresh, 1, 0).feed_position);
}

TEST(DampedBaselines, TwoHalvesAbsorbedAreOneLearnerOverBoth) {
  const auto first = stream(4.0, circling(0.0));
  const auto second = stream(4.0, circling(2.0, omega / 2));  // fits of its own
  const auto test_stream = stream(2.0, circling(1.0));
  for (const ModelKind kind :
       {ModelKind::damped_constant_velocity, ModelKind::damped_constant_acceleration}) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const auto both = train(kind, {first, second});
    const auto a = train(kind, {first});
    const auto b = train(kind, {second});
    const std::uint64_t progress_a = a->learner().progress();
    ASSERT_GT(progress_a, 0u);
    a->absorb(*b);
    EXPECT_EQ(a->learner().progress(), progress_a + b->learner().progress());
    EXPECT_EQ(a->learner().progress(), both->learner().progress());
    EXPECT_EQ(a->samples(), both->samples());

    const Last joined = run(kind, test_stream, sampler(), a->learner().forecaster(TableMetadata{}));
    const Last whole =
        run(kind, test_stream, sampler(), both->learner().forecaster(TableMetadata{}));
    const Last half = run(kind, test_stream, sampler(), b->learner().forecaster(TableMetadata{}));
    for (int step = 0; step < 2; ++step) {
      SCOPED_TRACE(step);
      EXPECT_LT(distance(robot(joined, step, 0).feed_position, robot(whole, step, 0).feed_position),
                1e-9);
    }
    // What the other half learned changed the prediction: it circled more slowly.
    EXPECT_GT(distance(robot(joined, 0, 0).feed_position, robot(half, 0, 0).feed_position), 10.0);
  }
}

}  // namespace
}  // namespace ssl_formation
