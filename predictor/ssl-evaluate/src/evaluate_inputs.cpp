// The matches ssl-evaluate trains and tests on: logs, and the two simulations kept in memory.
#include "evaluate_internal.hpp"

namespace ssl_formation::evaluate::detail {

ev::EventStream in_memory(RecordedMatch match) {
  return [match = std::make_shared<const RecordedMatch>(std::move(match))](MatchEventSink& sink) {
    match->replay(sink);
  };
}

RecordedMatch paper_simulation(const EvaluateOptions& options, std::uint64_t seed, int formations) {
  simulation::SimulationConfig config;
  config.seed = seed;
  config.jitter_mm = options.jitter_mm;
  config.cameras = options.cameras;
  return simulation::record_paper_simulation(config, formations);
}

RecordedMatch match_simulation(const EvaluateOptions& options, std::uint64_t seed, double seconds) {
  simulation::MatchSimulationConfig config;
  config.seed = seed;
  Result<simulation::Playbook> playbook = simulation::builtin_or_file_playbook(options.playbook);
  if (!playbook) throw app::UsageError("--playbook: " + playbook.error().message);
  config.playbook = std::move(*playbook);
  config.jitter_mm = options.jitter_mm;
  config.cameras = options.cameras;
  simulation::GameControllerConfig game;
  game.seed = seed;
  game.random_stoppages = false;  // the match calls its own stoppages
  config.game = game;
  return simulation::record_match_simulation(std::move(config), seconds);
}

std::pair<Streams, Streams> holdout_streams(const EvaluateOptions& options,
                                            const std::string& simulation) {
  Streams train;
  Streams test;
  if (options.tune && !options.test_logs.empty()) {
    throw app::UsageError(
        "--tune reads only the first --split of each --train-log; --test-log "
        "files are reported data (docs/tuning.md), not tuning data");
  }
  if (options.split > 0.0) {
    if (options.train_logs.empty()) throw app::UsageError("--split needs --train-log");
    // As RecordedMatch::split cuts a match: after the first `split` of its vision packets.
    const auto cut = [&](std::uint64_t vision_events) {
      return static_cast<std::uint64_t>(std::clamp(options.split, 0.0, 1.0) *
                                        static_cast<double>(vision_events));
    };
    for (const std::string& log : options.train_logs) {
      const LogFile file(log);
      const std::uint64_t head = cut(file.vision_events());
      if (options.tune) {
        // The inner split (docs/tuning.md): the reported part, after `head`, is left unread.
        const std::uint64_t inner = cut(head);
        train.push_back(file.stream({0, inner}));
        test.push_back(file.stream({inner, head}));
      } else {
        train.push_back(file.stream({0, head}));
        test.push_back(file.stream({head}));
      }
    }
    if (options.tune) {
      std::printf(
          "Tuning split: trained on the first %.4g of each log, tested on the next %.4g; "
          "the last %.4g, which reports, is not scored.\n",
          options.split * options.split, options.split * (1.0 - options.split),
          1.0 - options.split);
    }
  } else if (options.tune) {
    throw app::UsageError(
        "--tune is for --split F: it trains on the first F of each log's first F "
        "and tests on the rest of that, leaving the reported part unread");
  } else if (!options.train_logs.empty() && options.test_logs.empty()) {
    throw app::UsageError(
        "--train-log needs --test-log (other logs to test on) or --split F (the rest of each "
        "log after its first F): a model is only judged on data it was not trained on");
  } else {
    for (const std::string& log : options.train_logs) train.push_back(LogFile(log).stream());
  }
  for (const std::string& log : options.test_logs) test.push_back(LogFile(log).stream());
  if (train.empty() != test.empty()) {
    throw app::UsageError("give both --train-log and --test-log, or neither (a simulation)");
  }
  if (train.empty()) {
    if (simulation == "paper") {
      train.push_back(in_memory(paper_simulation(options, options.seed, options.train_formations)));
      test.push_back(
          in_memory(paper_simulation(options, options.test_seed, options.test_formations)));
    } else {
      train.push_back(in_memory(match_simulation(options, options.seed, options.train_seconds)));
      test.push_back(in_memory(match_simulation(options, options.test_seed, options.test_seconds)));
    }
  }
  return {std::move(train), std::move(test)};
}

}  // namespace ssl_formation::evaluate::detail
