// One grid's held-out evaluation: every --horizons section and the chain of --step steps.
#include "evaluate_internal.hpp"

namespace ssl_formation::evaluate::detail {

namespace {

// Two-step predictions of the paper's model from the test formations, timed.
double time_predictions(const TransitionTable& table, const Streams& test,
                        const SamplerConfig& config) {
  constexpr std::size_t timed = 5000;
  std::vector<std::vector<RobotStateById>> inputs;
  FormationSampler sampler(config, [&](const FormationSample& sample) {
    if (inputs.size() < timed) inputs.push_back(robot_states(sample.formation));
  });
  struct Feed final : MatchEventSink {
    FormationSampler& sampler;
    const std::vector<std::vector<RobotStateById>>& inputs;
    Feed(FormationSampler& s, const std::vector<std::vector<RobotStateById>>& i)
        : sampler(s), inputs(i) {}
    void on_event(const MatchEvent& event) override {
      // Past the formations timed, the rest of the log is only read.
      if (event.kind == MatchEventKind::vision && inputs.size() < timed) sampler.add(*event.frame);
    }
    void start_new_stream() override { sampler.start_new_stream(); }
  } feed(sampler, inputs);
  for (const ev::EventStream& stream : test) {
    feed.start_new_stream();
    stream(feed);
  }
  Prediction prediction;
  const auto start = std::chrono::steady_clock::now();
  std::size_t runs = 0;
  for (int pass = 0; pass < 20 && !inputs.empty(); ++pass) {
    for (const auto& input : inputs) {
      predict(table, input, 2, prediction);
      ++runs;
    }
  }
  const double elapsed =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  return runs ? elapsed / static_cast<double>(runs) : 0.0;
}

}  // namespace

GridReport holdout_for_grid(const EvaluateOptions& options, const std::string& grid,
                            const Streams& train, const Streams& test,
                            const std::shared_ptr<const MotionTable>& prior, SampleFile& samples) {
  app::ModelOptions model = options.model;
  model.grid = grid;
  const SamplerConfig base = model.sampler_config();
  GridReport report;
  report.grid = base.grid;
  // A prior serves the sections of its own step (the chained steps, and the single horizon equal
  // to it): a table's rows are learned for one step.
  std::vector<ev::PositionEvaluationConfig> configs;
  const auto section = [&](double step_s, int steps, bool chain) {
    ev::PositionEvaluationConfig config;
    config.sampler = base;
    config.sampler.step_s = step_s;
    config.steps = steps;
    config.velocity_window_s = options.velocity_window_s;
    config.model = model.parsed_model();
    config.recalibration = app::recalibration_settings(options.recalibration_half_life_s);
    config.rules =
        MatchRules{model.opponent_choice(), app::parsed_learn_during(options.learn_during)};
    config.tracked_vision = options.network.tracked();
    if (prior && std::abs(prior->config().step_s - step_s) < 1e-9) config.prior_table = prior;
    config.table_budget = app::table_budget_option(options.max_table_mb);
    config.bootstrap.resamples = options.bootstrap;
    config.bootstrap.block_s = options.bootstrap_block_s;
    const bool report_this = chain && !options.report.empty();
    if (samples.enabled() || report_this) {
      config.on_sample = [&samples, chain, report_this, &report,
                          name = base.grid.to_string()](const ev::ScoredSample& s) {
        if (samples.enabled()) samples.write(name, chain, s);
        if (report_this) report.chain_samples.add(s);
      };
    }
    configs.push_back(std::move(config));
  };
  for (const double horizon_s : options.horizons) section(horizon_s, 1, false);
  section(base.step_s, options.chain_steps, true);
  // Every section over one read of each stream.
  std::vector<ev::PositionEvaluation> evaluations = ev::evaluate_positions(configs, train, test);
  for (std::size_t i = 0; i < configs.size(); ++i) {
    report.sections.push_back({configs[i].sampler.step_s, std::move(evaluations[i])});
  }
  if (const auto& table = report.sections.back().evaluation.table) {
    report.prediction_us = time_predictions(table->table, test, base);
  }
  return report;
}

}  // namespace ssl_formation::evaluate::detail
