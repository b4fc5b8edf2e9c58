#include "ssl_formation/producer/simulation_source.hpp"

#include <fmt/format.h>

#include <cmath>

namespace ssl_formation::producer {

namespace {

// The paper's simulated opponent: a formation every --step seconds, sent every --period.
class PaperSource final : public SimulationSource {
 public:
  PaperSource(const ProducerOptions& options, std::optional<simulation::GameControllerConfig> game)
      : simulation_(simulation_config(options), std::move(game)), period_s_(options.period_s) {}

  SimulatedStep next() override {
    simulation::RefereedFormation step = simulation_.next();
    SimulatedStep out;
    out.index = step.formation.index;
    out.t_capture = step.formation.t_capture;
    out.referee = std::move(step.referee);
    out.packets = std::move(step.formation.packets);
    out.dropped_packets = step.formation.dropped_packets;
    if (step.formation.source == simulation::FormationSource::play) ++play_formations_;
    return out;
  }
  const char* steps_name() const override { return "formations"; }
  double step_s() const override { return simulation_.vision().config().step_s; }
  double live_period_s() const override { return period_s_; }
  void describe(std::uint64_t steps, app::StatusLine& line) const override {
    const double total = static_cast<double>(steps ? steps : 1);
    const std::uint64_t random = steps - play_formations_;
    line.figure("formations", steps);
    if (play_formations_ != 0) {
      line.detail("from_plays",
                  fmt::format("{} ({:.1f}%)", play_formations_, 100.0 * play_formations_ / total));
    }
    if (random != 0) {
      line.detail("random", fmt::format("{} ({:.1f}%)", random, 100.0 * random / total));
    }
  }
  const simulation::SimulatedGameController* game_controller() const override {
    return simulation_.game_controller();
  }

 private:
  simulation::RefereedSimulation simulation_;
  double period_s_;
  std::uint64_t play_formations_ = 0;
};

// The match: 60 frames a second of a team running its playbook, sent in real time.
class MatchSource final : public SimulationSource {
 public:
  explicit MatchSource(simulation::MatchSimulationConfig config) : match_(std::move(config)) {}

  SimulatedStep next() override {
    simulation::MatchFrame frame = match_.next();
    SimulatedStep out;
    out.index = frame.index;
    out.t_capture = frame.t_capture;
    out.referee = std::move(frame.referee);
    out.packets = std::move(frame.packets);
    out.dropped_packets = frame.dropped_packets;
    return out;
  }
  const char* steps_name() const override { return "frames"; }
  double step_s() const override { return 1.0 / match_.config().frame_rate_hz; }
  double live_period_s() const override { return step_s(); }
  void describe(std::uint64_t steps, app::StatusLine& line) const override {
    line.figure("frames", steps);
    if (steps != 0) {
      line.figure("match_time", fmt::format("{:.1f}s", static_cast<double>(steps) * step_s()));
    }
    line.detail("plays", match_.plays_started())
        .detail("passes", match_.passes())
        .detail("shots", match_.shots())
        .detail("goals", match_.goals());
  }
  const simulation::SimulatedGameController* game_controller() const override {
    return match_.game_controller();
  }

 private:
  simulation::MatchSimulation match_;
};

}  // namespace

void describe_game_controller(const simulation::SimulatedGameController& game,
                              app::StatusLine& line) {
  const Referee& message = game.message();
  line.figure("game", to_string(game.state()))
      .figure("attacks", to_string(game.opponent_attacks()))
      .figure("score",
              fmt::format("{}:{}(yellow:blue)", message.yellow().score(), message.blue().score()));
  line.detail("stage", Referee::Stage_Name(message.stage()))
      .detail("match", game.matches_started());
}

bool simulation_done(const ProducerOptions& options, std::uint64_t steps, double step_s) {
  return (options.count != 0 && steps >= options.count) ||
         (options.duration_s > 0.0 &&
          static_cast<double>(steps) * step_s >= options.duration_s - 1e-9);
}

std::unique_ptr<SimulationSource> make_simulation_source(const ProducerOptions& options,
                                                         bool with_referee) {
  if (!(options.duration_s >= 0.0) || !std::isfinite(options.duration_s)) {
    throw app::UsageError("--duration must be a number of seconds >= 0 (0: no limit)");
  }
  std::optional<simulation::GameControllerConfig> game =
      with_referee ? game_controller_config(options) : std::nullopt;
  if (options.simulation == "paper") {
    return std::make_unique<PaperSource>(options, std::move(game));
  }
  if (options.simulation == "match") {
    simulation::MatchSimulationConfig config = match_simulation_config(options);
    config.game = std::move(game);
    return std::make_unique<MatchSource>(std::move(config));
  }
  throw app::UsageError("--simulation must be paper or match, not '" + options.simulation + "'");
}

}  // namespace ssl_formation::producer
