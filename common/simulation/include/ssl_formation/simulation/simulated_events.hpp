#pragma once
// The simulations as the match's event stream (match/match_event.hpp), kept in memory: what the
// evaluation and the tests learn and test on in-process. Each frame's referee message comes
// before its vision, as ssl-producer sends and writes them, every event received at the frame's
// t_capture.

#include <optional>

#include "ssl_formation/match/match_event.hpp"
#include "ssl_formation/simulation/match_simulation.hpp"
#include "ssl_formation/simulation/simulated_game_controller.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"

namespace ssl_formation::simulation {

// `duration_s` of data time of a simulated match (with its game controller if config.game).
RecordedMatch record_match_simulation(MatchSimulationConfig config, double duration_s);

// `formations` of the paper's simulated opponent (with a game controller if `game`).
RecordedMatch record_paper_simulation(SimulationConfig config, int formations,
                                      std::optional<GameControllerConfig> game = std::nullopt);

}  // namespace ssl_formation::simulation
