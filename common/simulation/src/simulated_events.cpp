#include "ssl_formation/simulation/simulated_events.hpp"

#include <cmath>

namespace ssl_formation::simulation {

namespace {

void record(RecordedMatch& match, double t_capture, const std::optional<Referee>& referee,
            const std::vector<SSL_WrapperPacket>& packets) {
  if (referee) match.add_referee(referee->SerializeAsString(), t_capture);
  for (const SSL_WrapperPacket& packet : packets) match.add_vision(packet, t_capture);
}

}  // namespace

RecordedMatch record_match_simulation(MatchSimulationConfig config, double duration_s) {
  MatchSimulation simulation(std::move(config));
  const auto frames =
      static_cast<std::uint64_t>(std::llround(duration_s * simulation.config().frame_rate_hz));
  RecordedMatch match;
  for (std::uint64_t i = 0; i < frames; ++i) {
    const MatchFrame frame = simulation.next();
    record(match, frame.t_capture, frame.referee, frame.packets);
  }
  return match;
}

RecordedMatch record_paper_simulation(SimulationConfig config, int formations,
                                      std::optional<GameControllerConfig> game) {
  RefereedSimulation simulation(std::move(config), std::move(game));
  RecordedMatch match;
  for (int i = 0; i < formations; ++i) {
    const RefereedFormation step = simulation.next();
    record(match, step.formation.t_capture, step.referee, step.formation.packets);
  }
  return match;
}

}  // namespace ssl_formation::simulation
