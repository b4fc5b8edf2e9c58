#include "ssl_formation/pipeline/prediction_pipeline.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ssl_formation/paper_model/predictor.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
namespace {

struct Robot {
  std::uint32_t id;
  double x;
  double y;
};

// One camera's detection frame with `robots` in the given team colour.
SSL_WrapperPacket detection(double t_capture, const std::vector<Robot>& robots,
                            TeamColor color = TeamColor::yellow) {
  DetectionFrameSpec spec;
  spec.frame_number = static_cast<std::uint32_t>(t_capture * 10);
  spec.t_capture = t_capture;
  for (const Robot& robot : robots) {
    (color == TeamColor::yellow ? spec.yellow : spec.blue)
        .push_back({robot.id, {robot.x, robot.y}});
  }
  return make_detection_packet(spec);
}

SSL_WrapperPacket geometry(int length_mm, int width_mm) {
  return make_geometry_packet(
      FieldSize{static_cast<double>(length_mm), static_cast<double>(width_mm)});
}

// Frame k of a play that repeats every 4 frames, with a variation every third round so that the
// table holds competing successors (probabilities below 1). Positions are on a 12 x 9 m field.
std::vector<Robot> play(int k) {
  static const double xs[4] = {-5000.0, -1000.0, 3000.0, 5000.0};
  const int phase = k % 4;
  const bool variation = (k / 4) % 3 == 2;
  return {{0, xs[phase], -3000.0},
          {1, xs[(phase + 1) % 4], 3000.0},
          {3, variation ? xs[phase] : -5000.0, variation ? 3000.0 : -500.0}};
}

SamplerConfig sampler_config(Grid grid = Grid(3, 2)) {
  SamplerConfig config;
  config.grid = grid;
  config.step_s = 2.0;
  return config;  // field 9000 x 6000 until the geometry packet
}

// A table trained on `frames` frames of the play through the real Training.
std::shared_ptr<const StoredTable> trained_table(const SamplerConfig& config, int frames,
                                                 int first = 0) {
  Training training(config, TransitionTable(config.grid));
  training.add(geometry(12000, 9000));
  for (int k = first; k < first + frames; ++k) {
    training.add(detection(1000.0 + 2.0 * k, play(k), config.opponent_color));
  }
  TableMetadata metadata;
  metadata.step_s = config.step_s;
  metadata.samples = training.samples();
  return std::make_shared<const StoredTable>(StoredTable{training.stored_table().table, metadata});
}

// What a handler saw, copied: PredictedFormation is valid only during the call.
struct Seen {
  FormationSample sample;
  Prediction prediction;
  PredictionContext context;
};

struct Recorder {
  std::vector<Seen> seen;
  PredictionPipeline::Handler handler() {
    return [this](const PredictedFormation& p) {
      seen.push_back(Seen{p.sample, p.prediction, p.context});
    };
  }
};

void expect_same_prediction(const Prediction& actual, const Prediction& expected) {
  ASSERT_EQ(actual.steps.size(), expected.steps.size());
  for (std::size_t k = 0; k < expected.steps.size(); ++k) {
    const PredictedStep& a = actual.steps[k];
    const PredictedStep& e = expected.steps[k];
    EXPECT_EQ(a.centroid, e.centroid) << "step " << k;
    EXPECT_EQ(a.centroid_probability, e.centroid_probability) << "step " << k;
    EXPECT_EQ(a.centroid_unseen, e.centroid_unseen) << "step " << k;
    EXPECT_EQ(a.formation_probability, e.formation_probability) << "step " << k;
    EXPECT_EQ(a.confidence, e.confidence) << "step " << k;
    ASSERT_EQ(a.robots.size(), e.robots.size()) << "step " << k;
    for (std::size_t i = 0; i < e.robots.size(); ++i) {
      EXPECT_EQ(a.robots[i].robot_id, e.robots[i].robot_id) << "step " << k << " robot " << i;
      EXPECT_EQ(a.robots[i].state, e.robots[i].state) << "step " << k << " robot " << i;
      EXPECT_EQ(a.robots[i].position, e.robots[i].position) << "step " << k << " robot " << i;
      EXPECT_EQ(a.robots[i].previous, e.robots[i].previous) << "step " << k << " robot " << i;
      EXPECT_EQ(a.robots[i].probability, e.robots[i].probability) << "step " << k << " robot " << i;
      EXPECT_EQ(a.robots[i].unseen, e.robots[i].unseen) << "step " << k << " robot " << i;
    }
  }
}

TEST(PredictionPipeline, WithoutATableNothingIsPredictedButSamplesAreCounted) {
  int calls = 0;
  PredictionPipeline pipeline(PredictionConfig{sampler_config(), 2, ModelKind::paper},
                              [&](const PredictedFormation&) { ++calls; });
  EXPECT_EQ(pipeline.table(), nullptr);
  pipeline.add(geometry(12000, 9000));
  for (int k = 0; k < 10; ++k) pipeline.add(detection(2.0 * k, play(k)));
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(pipeline.predictions(), 0u);
  EXPECT_GE(pipeline.samples_without_table(), 9u);
  EXPECT_EQ(pipeline.samples_without_table(), pipeline.sampler().counters().samples);
  // The chains ran on meanwhile: the sampler counted transitions.
  EXPECT_GT(pipeline.sampler().counters().transitions, 0u);
}

TEST(PredictionPipeline, EachPredictionIsThePredictorsOnTheSampledFormation) {
  const SamplerConfig config = sampler_config();
  const auto table = trained_table(config, 60);
  ASSERT_GT(table->table.transitions(), 0u);

  Recorder out;
  PredictionPipeline pipeline(PredictionConfig{config, 3, ModelKind::paper}, out.handler());
  pipeline.set_table(table);
  EXPECT_EQ(pipeline.table(), table);
  pipeline.add(geometry(12000, 9000));
  // Another stretch of the same play: the states seen in training, and some that were not.
  for (int k = 0; k < 16; ++k) pipeline.add(detection(5000.0 + 2.0 * k, play(k + 1)));
  pipeline.add(detection(5032.0, {{0, 0.0, 0.0}, {1, 5500.0, -4400.0}, {3, -5900.0, 4400.0}}));
  pipeline.add(detection(5034.0, {{0, 0.0, 0.0}}));

  ASSERT_GE(out.seen.size(), 16u);
  EXPECT_EQ(pipeline.predictions(), out.seen.size());
  EXPECT_EQ(pipeline.samples_without_table(), 0u);
  bool some_seen_centroid = false;
  bool some_seen_robot = false;
  bool some_unseen_robot = false;
  bool some_uncertain = false;
  for (const Seen& seen : out.seen) {
    SCOPED_TRACE("sample at " + std::to_string(seen.sample.formation.time_s));
    ASSERT_EQ(seen.prediction.steps.size(), 3u);
    expect_same_prediction(seen.prediction, predict(table->table, seen.sample.formation, 3));
    // Robots predicted for the robots of the formation, by id.
    ASSERT_EQ(seen.prediction.steps[0].robots.size(), seen.sample.formation.robots.size());
    for (std::size_t i = 0; i < seen.sample.formation.robots.size(); ++i) {
      EXPECT_EQ(seen.prediction.steps[0].robots[i].robot_id,
                seen.sample.formation.robots[i].robot_id);
    }
    // The context: this table, the field from geometry, the step and the options.
    EXPECT_EQ(seen.context.codec->grid(), table->table.grid());
    EXPECT_EQ(seen.context.table_transitions, table->table.transitions());
    EXPECT_EQ(seen.context.field, (FieldSize{12000.0, 9000.0}));
    EXPECT_EQ(seen.context.step_s, 2.0);
    EXPECT_EQ(seen.context.opponent_attacks, AttackDirection::positive_x);
    EXPECT_EQ(seen.context.opponent_color, TeamColor::yellow);
    for (const PredictedStep& step : seen.prediction.steps) {
      some_seen_centroid |= !step.centroid_unseen;
      some_uncertain |= !step.centroid_unseen && step.formation_probability < 1.0;
      for (const RobotPrediction& robot : step.robots) {
        some_seen_robot |= !robot.unseen;
        some_unseen_robot |= robot.unseen;
      }
    }
  }
  // The stream exercised the interesting cases, not only unseen rows.
  EXPECT_TRUE(some_seen_centroid);
  EXPECT_TRUE(some_seen_robot);
  EXPECT_TRUE(some_unseen_robot);
  EXPECT_TRUE(some_uncertain);
}

TEST(PredictionPipeline, TheContextCarriesTheOptionsAndTheFieldOfTheOptionsWithoutGeometry) {
  SamplerConfig config = sampler_config();
  config.opponent_color = TeamColor::blue;
  config.opponent_attacks = AttackDirection::negative_x;
  config.field = FieldSize{10400.0, 7400.0};
  config.step_s = 1.5;
  const auto table = trained_table(config, 30);
  Recorder out;
  PredictionPipeline pipeline(PredictionConfig{config, 1, ModelKind::paper}, out.handler());
  pipeline.set_table(table);
  // Yellow robots are not the opponent: nothing.
  for (int k = 0; k < 4; ++k) pipeline.add(detection(1.5 * k, play(k), TeamColor::yellow));
  EXPECT_TRUE(out.seen.empty());
  for (int k = 4; k < 10; ++k) pipeline.add(detection(1.5 * k, play(k), TeamColor::blue));
  ASSERT_FALSE(out.seen.empty());
  for (const Seen& seen : out.seen) {
    EXPECT_EQ(seen.context.field, (FieldSize{10400.0, 7400.0}));
    EXPECT_EQ(seen.context.step_s, 1.5);
    EXPECT_EQ(seen.context.opponent_attacks, AttackDirection::negative_x);
    EXPECT_EQ(seen.context.opponent_color, TeamColor::blue);
    ASSERT_EQ(seen.prediction.steps.size(), 1u);
    expect_same_prediction(seen.prediction, predict(table->table, seen.sample.formation, 1));
  }
}

TEST(PredictionPipeline, ATableOfAnotherGridIsRefused) {
  Recorder out;
  PredictionPipeline pipeline(PredictionConfig{sampler_config(Grid(3, 2)), 2, ModelKind::paper},
                              out.handler());
  const auto wrong = trained_table(sampler_config(Grid(4, 3)), 10);
  EXPECT_THROW(pipeline.set_table(wrong), std::invalid_argument);
  EXPECT_EQ(pipeline.table(), nullptr);

  const auto right = trained_table(sampler_config(Grid(3, 2)), 10);
  pipeline.set_table(right);
  EXPECT_THROW(pipeline.set_table(wrong), std::invalid_argument);
  EXPECT_EQ(pipeline.table(), right) << "a refused table leaves the one in use";

  // No table again: samples are counted, not predicted.
  pipeline.set_table(nullptr);
  EXPECT_EQ(pipeline.table(), nullptr);
  for (int k = 0; k < 5; ++k) pipeline.add(detection(2.0 * k, play(k)));
  EXPECT_TRUE(out.seen.empty());
  EXPECT_GT(pipeline.samples_without_table(), 0u);
}

TEST(PredictionPipeline, ATablePreparedApartIsUsedFromTheSampleAfterItIsInstalled) {
  Recorder out;
  PredictionPipeline pipeline(PredictionConfig{sampler_config(), 1, ModelKind::paper},
                              out.handler());
  const auto first = trained_table(sampler_config(), 10);
  const auto second = trained_table(sampler_config(), 30);
  ASSERT_NE(first->table.transitions(), second->table.transitions());
  pipeline.set_table(first);
  PreparedTable prepared = pipeline.prepare_table(second);
  EXPECT_THROW(pipeline.prepare_table(trained_table(sampler_config(Grid(4, 3)), 10)),
               std::invalid_argument);
  for (int k = 0; k < 4; ++k) pipeline.add(detection(2.0 * k, play(k)));
  ASSERT_FALSE(out.seen.empty());
  for (const Seen& seen : out.seen) {
    EXPECT_EQ(seen.context.table_transitions, first->table.transitions());
  }
  const std::size_t before = out.seen.size();
  const PreparedTable old = pipeline.install_table(std::move(prepared));
  EXPECT_EQ(old.table, first);
  EXPECT_EQ(pipeline.table(), second);
  for (int k = 4; k < 8; ++k) pipeline.add(detection(2.0 * k, play(k)));
  ASSERT_GT(out.seen.size(), before);
  for (std::size_t i = before; i < out.seen.size(); ++i) {
    EXPECT_EQ(out.seen[i].context.table_transitions, second->table.transitions());
  }
}

TEST(PredictionPipeline, HorizonBounds) {
  const auto ignore = [](const PredictedFormation&) {};
  EXPECT_THROW(PredictionPipeline(PredictionConfig{sampler_config(), 0, ModelKind::paper}, ignore),
               std::invalid_argument);
  EXPECT_THROW(PredictionPipeline(PredictionConfig{sampler_config(), -1, ModelKind::paper}, ignore),
               std::invalid_argument);
  EXPECT_THROW(
      PredictionPipeline(
          PredictionConfig{sampler_config(), PredictionConfig::max_horizon + 1, ModelKind::paper},
          ignore),
      std::invalid_argument);
  SamplerConfig bad_step = sampler_config();
  bad_step.step_s = 0.0;
  EXPECT_THROW(PredictionPipeline(PredictionConfig{bad_step, 2, ModelKind::paper}, ignore),
               std::invalid_argument);

  const auto table = trained_table(sampler_config(), 20);
  for (int horizon : {1, PredictionConfig::max_horizon}) {
    Recorder out;
    PredictionPipeline pipeline(PredictionConfig{sampler_config(), horizon, ModelKind::paper},
                                out.handler());
    EXPECT_EQ(pipeline.config().horizon, horizon);
    pipeline.set_table(table);
    for (int k = 0; k < 4; ++k) pipeline.add(detection(2.0 * k, play(k)));
    ASSERT_FALSE(out.seen.empty());
    for (const Seen& seen : out.seen) {
      ASSERT_EQ(seen.prediction.steps.size(), static_cast<std::size_t>(horizon));
      expect_same_prediction(seen.prediction,
                             predict(table->table, seen.sample.formation, horizon));
    }
  }
}

// The samples at instants 0, 2, 4, 6, 8 of the play, with start_new_stream() before instant 6
// if `break_at_6`.
std::vector<Seen> run_with_break(const std::shared_ptr<const StoredTable>& table, bool break_at_6) {
  Recorder out;
  PredictionPipeline pipeline(PredictionConfig{sampler_config(), 2, ModelKind::paper},
                              out.handler());
  pipeline.set_table(table);
  pipeline.add(geometry(12000, 9000));
  for (int k = 0; k < 5; ++k) {
    if (break_at_6 && k == 3) pipeline.start_new_stream();
    pipeline.add(detection(2.0 * k, play(k)));
  }
  pipeline.add(detection(10.0, play(5)));
  return out.seen;
}

const Seen* at(const std::vector<Seen>& seen, double time_s) {
  for (const Seen& s : seen) {
    if (s.sample.formation.time_s == time_s) return &s;
  }
  return nullptr;
}

TEST(PredictionPipeline, StartNewStreamBreaksTheChain) {
  const auto table = trained_table(sampler_config(), 60);
  const std::vector<Seen> chained = run_with_break(table, false);
  const std::vector<Seen> broken = run_with_break(table, true);

  const Seen* continuing = at(chained, 6.0);
  const Seen* restarted = at(broken, 6.0);
  ASSERT_NE(continuing, nullptr);
  ASSERT_NE(restarted, nullptr);
  // Without the break, the formation at 6 s follows the one at 4 s: robots that moved have a
  // velocity and transitions were counted.
  EXPECT_TRUE(continuing->sample.formation.continues_previous);
  EXPECT_FALSE(continuing->sample.transitions.empty());
  bool someone_moved = false;
  for (const FormationRobot& robot : continuing->sample.formation.robots) {
    someone_moved |= robot.previous_cell != robot.cell;
  }
  ASSERT_TRUE(someone_moved) << "the play must move a robot across cells from 4 s to 6 s";

  // With it, the formation at 6 s follows nothing: velocity 0 for every robot, no transition.
  EXPECT_FALSE(restarted->sample.formation.continues_previous);
  EXPECT_TRUE(restarted->sample.transitions.empty());
  for (const FormationRobot& robot : restarted->sample.formation.robots) {
    EXPECT_EQ(robot.previous_cell, robot.cell) << "robot " << robot.robot_id;
  }
  expect_same_prediction(restarted->prediction,
                         predict(table->table, restarted->sample.formation, 2));
  // The next one continues the new stream.
  const Seen* next = at(broken, 8.0);
  ASSERT_NE(next, nullptr);
  EXPECT_TRUE(next->sample.formation.continues_previous);
}

TEST(PredictionPipeline, SetTableFromInsideTheHandlerIsSafe) {
  const SamplerConfig config = sampler_config();
  bool first_destroyed = false;
  const auto trained = trained_table(config, 60);
  const std::uint64_t first_transitions = trained->table.transitions();
  // The pipeline holds the only reference to the first table; the deleter tells when it goes.
  std::shared_ptr<const StoredTable> first(new StoredTable(*trained),
                                           [&first_destroyed](const StoredTable* stored) {
                                             first_destroyed = true;
                                             delete stored;
                                           });
  const auto second = trained_table(config, 24, 7);
  ASSERT_NE(second->table.transitions(), first_transitions);

  PredictionPipeline* self = nullptr;
  std::vector<Seen> seen;
  std::vector<Prediction> expected;
  bool alive_during_call = false;
  PredictionPipeline pipeline(PredictionConfig{config, 2, ModelKind::paper},
                              [&](const PredictedFormation& p) {
                                if (seen.empty()) {
                                  self->set_table(second);
                                  // What this call was handed still refers to the first table,
                                  // which must still exist.
                                  alive_during_call = !first_destroyed;
                                  EXPECT_EQ(p.context.table_transitions, first_transitions);
                                  EXPECT_EQ(p.context.codec->grid(), config.grid);
                                } else if (seen.size() == 3) {
                                  self->set_table(nullptr);
                                }
                                seen.push_back(Seen{p.sample, p.prediction, p.context});
                              });
  self = &pipeline;
  pipeline.set_table(std::move(first));
  pipeline.add(geometry(12000, 9000));
  for (int k = 0; k < 8; ++k) pipeline.add(detection(2.0 * k, play(k)));

  EXPECT_TRUE(alive_during_call) << "the table in use was freed during the handler's call";
  EXPECT_TRUE(first_destroyed) << "the pipeline let go of the first table afterwards";
  ASSERT_EQ(seen.size(), 4u) << "then no table: the rest are counted, not predicted";
  EXPECT_GT(pipeline.samples_without_table(), 0u);
  EXPECT_EQ(pipeline.predictions(), 4u);
  expect_same_prediction(seen[0].prediction, predict(trained->table, seen[0].sample.formation, 2));
  for (std::size_t i = 1; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].context.table_transitions, second->table.transitions());
    expect_same_prediction(seen[i].prediction, predict(second->table, seen[i].sample.formation, 2));
  }
}

}  // namespace
}  // namespace ssl_formation
