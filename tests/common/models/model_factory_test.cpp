// The models by name (models/src/model_factory.cpp): names, checks, and what it makes.

#include "ssl_formation/models/model_factory.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/models/table_file.hpp"

namespace ssl_formation {
namespace {

bool contains(const std::optional<std::string>& text, const std::string& part) {
  return text && text->find(part) != std::string::npos;
}

TEST(ModelNames, EveryKindRoundTripsThroughItsName) {
  for (const ModelKind kind : all_model_kinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    EXPECT_EQ(to_string(kind), describe(kind).name);
    EXPECT_EQ(parse_model(to_string(kind)), kind);
  }
  EXPECT_EQ(to_string(ModelKind::paper), "paper");
  EXPECT_EQ(to_string(ModelKind::motion), "motion");
  EXPECT_EQ(to_string(ModelKind::persistence), "persistence");
  EXPECT_EQ(to_string(ModelKind::constant_velocity), "constant-velocity");
  EXPECT_EQ(to_string(ModelKind::damped_constant_velocity), "damped-constant-velocity");
  EXPECT_EQ(to_string(ModelKind::constant_acceleration), "constant-acceleration");
  EXPECT_EQ(to_string(ModelKind::damped_constant_acceleration), "damped-constant-acceleration");
}

TEST(ModelNames, UnknownNamesAndLabelsAreRejected) {
  EXPECT_EQ(parse_model("markov"), std::nullopt);
  EXPECT_EQ(parse_model(""), std::nullopt);
  EXPECT_EQ(parse_model("constant velocity"), std::nullopt);  // the label, not the name
  EXPECT_EQ(parse_model("damped"), std::nullopt);
  EXPECT_EQ(parse_model("paper-model"), std::nullopt);
}

TEST(ModelNames, TheListNamesAllSevenInOrder) {
  EXPECT_EQ(model_names(),
            "paper, motion, persistence, constant-velocity, damped-constant-velocity, "
            "constant-acceleration, damped-constant-acceleration");
}

TEST(ModelSampling, TheDefaultIsTheMotionModelSamplingEveryFrameWithHalfSecondSteps) {
  EXPECT_EQ(default_model, ModelKind::motion);
  const SamplerConfig config = sampler_config_for(default_model);
  EXPECT_EQ(config.sampling, Sampling::frame);
  EXPECT_DOUBLE_EQ(config.step_s, 0.5);
  const SamplerConfig paper = sampler_config_for(ModelKind::paper);
  EXPECT_EQ(paper.sampling, Sampling::step);
  EXPECT_DOUBLE_EQ(paper.step_s, 2.0);
  for (const ModelKind kind : baseline_kinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    EXPECT_EQ(sampler_config_for(kind).sampling, Sampling::frame);
    EXPECT_DOUBLE_EQ(sampler_config_for(kind).step_s, 0.5);
  }
}

TEST(ModelSampling, ModelsThatReadVelocitiesNeedFrameSampling) {
  for (const ModelKind kind : all_model_kinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    EXPECT_EQ(sampling_problem(kind, Sampling::frame), std::nullopt);
    if (kind == ModelKind::paper) {
      EXPECT_EQ(sampling_problem(kind, Sampling::step), std::nullopt);
    } else {
      const auto problem = sampling_problem(kind, Sampling::step);
      EXPECT_TRUE(contains(problem, "--sampling frame")) << problem.value_or("(none)");
      EXPECT_TRUE(contains(problem, "--model " + std::string(to_string(kind))));
    }
  }
}

TEST(ModelSampling, AFeedOfFramesSecondsApartSendsTheMotionModelToThePaper) {
  const auto slow = feed_problem(ModelKind::motion, 2.0);
  EXPECT_TRUE(contains(slow, "--model paper")) << slow.value_or("(none)");
  EXPECT_TRUE(contains(slow, "2 s apart")) << slow.value_or("(none)");
  EXPECT_EQ(feed_problem(ModelKind::motion, 0.0167), std::nullopt);
  EXPECT_EQ(feed_problem(ModelKind::paper, 2.0), std::nullopt);
  EXPECT_EQ(feed_problem(ModelKind::paper, 0.0167), std::nullopt);
  EXPECT_TRUE(contains(feed_problem(ModelKind::constant_velocity, 2.0), "--model paper"));
  EXPECT_EQ(feed_problem(ModelKind::constant_velocity, 0.0167), std::nullopt);
}

TEST(ModelDescription, OnlyTheTableModelsKeepATableAndTheDampedOnesLearnToo) {
  for (const ModelKind kind : all_model_kinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const ModelDescription& d = describe(kind);
    const bool table = kind == ModelKind::paper || kind == ModelKind::motion;
    const bool damped = kind == ModelKind::damped_constant_velocity ||
                        kind == ModelKind::damped_constant_acceleration;
    EXPECT_EQ(d.keeps_table, table);
    EXPECT_EQ(d.learns, table || damped);
    EXPECT_EQ(d.states_positions, kind != ModelKind::paper);
    EXPECT_EQ(d.needs_every_frame, kind != ModelKind::paper);
    EXPECT_DOUBLE_EQ(d.default_step_s, kind == ModelKind::paper ? 2.0 : 0.5);
    EXPECT_FALSE(d.label.empty());
  }
  EXPECT_EQ(describe(ModelKind::damped_constant_velocity).label, "damped constant velocity");
}

std::shared_ptr<const StoredTable> paper_table(Grid grid = Grid(3, 2)) {
  TableMetadata metadata;
  metadata.step_s = 2.0;
  return std::make_shared<const StoredTable>(StoredTable{TransitionTable(grid), metadata});
}

std::shared_ptr<const StoredTable> motion_table(double step_s) {
  MotionConfig config;
  config.step_s = step_s;
  TableMetadata metadata;
  metadata.step_s = step_s;
  return std::make_shared<const StoredTable>(StoredTable{
      TransitionTable(Grid(3, 2)), metadata, std::make_shared<const MotionTable>(config)});
}

TEST(ModelForecaster, BaselinesAreReadyWithoutATable) {
  const ModelSettings settings;
  for (const ModelKind kind : baseline_kinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const auto forecaster = make_forecaster(kind, settings);
    ASSERT_NE(forecaster, nullptr);
    EXPECT_TRUE(forecaster->ready());
    forecaster->set_table(paper_table());  // needs none, takes any
    EXPECT_TRUE(forecaster->ready());
  }
}

TEST(ModelForecaster, TheTableModelsAreReadyOnlyWithATable) {
  const ModelSettings settings;  // step 0.5
  const auto paper = make_forecaster(ModelKind::paper, settings);
  EXPECT_FALSE(paper->ready());
  paper->set_table(paper_table());
  EXPECT_TRUE(paper->ready());
  paper->set_table(nullptr);
  EXPECT_FALSE(paper->ready());

  const auto motion = make_forecaster(ModelKind::motion, settings);
  EXPECT_FALSE(motion->ready());
  motion->set_table(motion_table(0.5));
  EXPECT_TRUE(motion->ready());
  motion->set_table(nullptr);
  EXPECT_FALSE(motion->ready());
}

TEST(ModelForecaster, TheMotionModelRefusesAVersionOneTableAndKeepsItsOwn) {
  const auto motion = make_forecaster(ModelKind::motion, ModelSettings{});
  EXPECT_THROW(motion->set_table(paper_table()), std::invalid_argument);
  EXPECT_FALSE(motion->ready());
  motion->set_table(motion_table(0.5));
  EXPECT_THROW(motion->set_table(paper_table()), std::invalid_argument);
  EXPECT_TRUE(motion->ready());  // the previous table stays
  // A motion table trained with another step is refused too.
  EXPECT_THROW(motion->set_table(motion_table(1.0)), std::invalid_argument);
  EXPECT_TRUE(motion->ready());
}

TEST(ModelForecaster, APreparedTableChangesNothingUntilInstalledAndTheReplacedOneComesBack) {
  const auto motion = make_forecaster(ModelKind::motion, ModelSettings{});
  const auto first = motion_table(0.5);
  motion->set_table(first);
  // Prepared apart (a daemon's loader thread does this while the forecaster predicts).
  auto second = motion_table(0.5);
  PreparedTable prepared = motion->prepare_table(second);
  EXPECT_EQ(prepared.table, second);
  EXPECT_NE(prepared.built, nullptr);  // the motion model, built already
  EXPECT_THROW(motion->prepare_table(paper_table()), std::invalid_argument);
  EXPECT_TRUE(motion->ready());
  // Installed: what was built of the replaced table comes back, for the caller to free. The
  // forecaster keeps no copy of the stored table: its rows are no longer read, and a season's
  // are tens of megabytes.
  const std::weak_ptr<const StoredTable> second_stored = second;
  const PreparedTable old = motion->install_table(std::move(prepared));
  EXPECT_EQ(old.table, nullptr);
  EXPECT_NE(old.built, nullptr);
  EXPECT_TRUE(motion->ready());
  second.reset();
  EXPECT_TRUE(second_stored.expired());
  EXPECT_TRUE(motion->ready());
  const PreparedTable last = motion->install_table(motion->prepare_table(nullptr));
  EXPECT_NE(last.built, nullptr);
  EXPECT_FALSE(motion->ready());
}

TEST(ModelFactory, BadSettingsAreRefused) {
  ModelSettings no_step;
  no_step.step_s = 0.0;
  ModelSettings no_horizon;
  no_horizon.horizons = 0;
  for (const ModelKind kind :
       {ModelKind::motion, ModelKind::persistence, ModelKind::damped_constant_velocity}) {
    SCOPED_TRACE(std::string(to_string(kind)));
    EXPECT_THROW(make_learner(kind, no_step), std::invalid_argument);
    EXPECT_THROW(make_learner(kind, no_horizon), std::invalid_argument);
  }
  EXPECT_THROW(make_forecaster(ModelKind::constant_velocity, no_step), std::invalid_argument);
}

TEST(ModelLearner, NewLearnersKeepWhatTheirModelKeeps) {
  const ModelSettings settings;
  for (const ModelKind kind : all_model_kinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const auto learner = make_learner(kind, settings);
    EXPECT_EQ(learner->progress(), 0u);
    EXPECT_EQ(learner->table_summary().has_value(), describe(kind).keeps_table);
    EXPECT_EQ(learner->stored(TableMetadata{}).has_value(), describe(kind).keeps_table);
    EXPECT_EQ(learner->table_summary() && learner->table_summary()->motion,
              describe(kind).keeps_motion_rows);
  }
  const auto motion = make_learner(ModelKind::motion, settings);
  const auto stored = motion->stored(TableMetadata{});
  ASSERT_TRUE(stored && stored->motion);
  EXPECT_DOUBLE_EQ(stored->motion->config().step_s, 0.5);
  EXPECT_EQ(stored->motion->config().horizons, 3);
}

TEST(ModelLearner, AResumedTableIsTheMotionModelsOnlyWithMotionRows) {
  MotionConfig config;
  config.step_s = 0.5;
  TransitionTable counts(Grid(3, 2));
  counts.add(5, 7);
  ResumedLearner with_motion = resume_learner(
      StoredTable{counts, TableMetadata{}, std::make_shared<const MotionTable>(config)});
  EXPECT_EQ(with_motion.kind, ModelKind::motion);
  const auto resumed = with_motion.learner->table_summary();
  ASSERT_TRUE(resumed && resumed->motion);
  EXPECT_DOUBLE_EQ(resumed->motion->step_s, 0.5);
  EXPECT_EQ(resumed->transitions, 1u);

  ResumedLearner paper = resume_learner(StoredTable{counts, TableMetadata{}, nullptr});
  EXPECT_EQ(paper.kind, ModelKind::paper);
  const auto paper_table = paper.learner->table_summary();
  ASSERT_TRUE(paper_table);
  EXPECT_FALSE(paper_table->motion);
  EXPECT_EQ(paper_table->transitions, 1u);
  EXPECT_EQ(paper.learner->progress(), 1u);
}

TEST(ModelLearner, ALearnerAbsorbsOnlyItsOwnKind) {
  const ModelSettings settings;
  for (const ModelKind kind : all_model_kinds) {
    for (const ModelKind other : all_model_kinds) {
      if (kind == other) continue;
      SCOPED_TRACE(std::string(to_string(kind)) + " absorbing " + std::string(to_string(other)));
      const auto learner = make_learner(kind, settings);
      EXPECT_THROW(learner->absorb(*make_learner(other, settings)), std::invalid_argument);
    }
    const auto learner = make_learner(kind, settings);
    EXPECT_NO_THROW(learner->absorb(*make_learner(kind, settings)));
  }
}

TEST(ModelLearner, ALearnerOfOtherSettingsCannotBeAbsorbed) {
  ModelSettings two;
  two.horizons = 2;
  const auto damped = make_learner(ModelKind::damped_constant_velocity, ModelSettings{});
  EXPECT_THROW(damped->absorb(*make_learner(ModelKind::damped_constant_velocity, two)),
               std::invalid_argument);
  const auto motion = make_learner(ModelKind::motion, ModelSettings{});
  EXPECT_THROW(motion->absorb(*make_learner(ModelKind::motion, two)), std::invalid_argument);
  ModelSettings other_grid;
  other_grid.grid = Grid(6, 4);
  const auto paper = make_learner(ModelKind::paper, ModelSettings{});
  EXPECT_THROW(paper->absorb(*make_learner(ModelKind::paper, other_grid)), std::invalid_argument);
}

}  // namespace
}  // namespace ssl_formation
