#include "ssl_formation/pipeline/training.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace ssl_formation {
inline namespace pipeline {

FrontEndConfig Training::front_end_config(const TrainingConfig& config) {
  FrontEndConfig front;
  front.sampler = config.sampler;
  front.opponent =
      config.rules ? std::optional<OpponentChoice>(config.rules->opponent) : std::nullopt;
  front.tracked_vision = config.tracked_vision;
  const LearnDuring learn_during = config.rules ? config.rules->learn_during : LearnDuring::all;
  front.keep_commands_apart = learn_during == LearnDuring::running;
  return front;
}

namespace {

// Checks what can be checked before anything is counted.
std::unique_ptr<Learner> checked(const TrainingConfig& config, ModelKind model,
                                 std::unique_ptr<Learner> learner) {
  if (const auto problem = sampling_problem(model, config.sampler.sampling)) {
    throw std::invalid_argument(*problem);
  }
  const std::optional<TableSummary> table = learner->table_summary();
  if (table && table->grid != config.sampler.grid) {
    throw std::invalid_argument("the table's grid " + table->grid.to_string() +
                                " differs from the sampler's " + config.sampler.grid.to_string());
  }
  if (table && table->motion && std::abs(table->motion->step_s - config.sampler.step_s) > 1e-9) {
    throw std::invalid_argument("the motion table's step differs from the sampler's");
  }
  return learner;
}

}  // namespace

Training::Training(TrainingConfig config, ModelKind model, std::unique_ptr<Learner> learner,
                   std::uint64_t samples_before)
    : model_(model),
      learner_(checked(config, model, std::move(learner))),
      learn_during_(config.rules ? config.rules->learn_during : LearnDuring::all),
      own_front_end_(std::make_unique<MatchFrontEnd>(front_end_config(config), handlers())),
      front_end_(*own_front_end_),
      samples_before_(samples_before),
      saved_progress_(learner_->progress()),
      saved_samples_(samples_before) {}

Training::Training(TrainingConfig config, ModelKind model, std::unique_ptr<Learner> learner,
                   MatchFrontEnd& shared)
    : model_(model),
      learner_(checked(config, model, std::move(learner))),
      learn_during_(config.rules ? config.rules->learn_during : LearnDuring::all),
      front_end_(shared),
      samples_before_(0),
      saved_progress_(learner_->progress()),
      saved_samples_(0) {
  front_end_.join(handlers());
}

MatchFrontEnd::Handlers Training::handlers() {
  return {[this](const MatchMoment& moment) { on_sample(moment); },
          [this] { learner_->forget_match(); }};
}

namespace {
TrainingConfig table_training_config(SamplerConfig sampler, std::optional<MatchRules> rules) {
  TrainingConfig config;
  config.sampler = std::move(sampler);
  config.rules = std::move(rules);
  return config;
}
}  // namespace

Training::Training(SamplerConfig config, TransitionTable table, std::uint64_t samples_before,
                   std::optional<MotionTable> motion, std::optional<MatchRules> rules)
    : Training(table_training_config(std::move(config), std::move(rules)),
               resume_learner(StoredTable{
                   std::move(table), TableMetadata{},
                   motion ? std::make_shared<const MotionTable>(std::move(*motion)) : nullptr}),
               samples_before) {}

Training::Training(TrainingConfig config, ResumedLearner resumed, std::uint64_t samples_before)
    : Training(std::move(config), resumed.kind, std::move(resumed.learner), samples_before) {}

TableSummary Training::table_summary() const {
  std::optional<TableSummary> summary = learner_->table_summary();
  if (!summary) {
    throw std::logic_error("--model " + std::string(to_string(model_)) + " keeps no table");
  }
  return *summary;
}

StoredTable Training::stored_table(const TableMetadata& metadata) const {
  std::optional<StoredTable> stored = learner_->stored(metadata);
  if (!stored) {
    throw std::logic_error("--model " + std::string(to_string(model_)) + " keeps no table");
  }
  return std::move(*stored);
}

StoredTable Training::release_table(const TableMetadata& metadata) {
  std::optional<StoredTable> stored = learner_->release_table(metadata);
  if (!stored) {
    throw std::logic_error("--model " + std::string(to_string(model_)) + " keeps no table");
  }
  return std::move(*stored);
}

StoredTable Training::stored_table() const {
  TableMetadata metadata;
  metadata.field = sampler().field();
  metadata.step_s = sampler().config().step_s;
  metadata.samples = samples();
  return stored_table(metadata);
}

std::optional<std::string> Training::feed_problem() const {
  return ssl_formation::feed_problem(model_, front_end_.recent_frame_gap_s());
}

void Training::absorb(const Training& other) {
  learner_->absorb(*other.learner_);
  samples_before_ += other.samples();
}

void Training::on_sample(const MatchMoment& moment) {
  // Followed in every state, so that velocities are known when learning starts again.
  learner_->observe(moment);
  if (match().learning(learn_during_)) {
    learner_->learn(moment);
  } else {
    ++samples_outside_play_;
  }
}

}  // namespace pipeline
}  // namespace ssl_formation
