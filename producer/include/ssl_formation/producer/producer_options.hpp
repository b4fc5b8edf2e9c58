#pragma once
// ssl-producer's options: the simulated opponent, the network it sends on, and the log files it
// writes (-o/--output) or replays (--replay). Parsed in main.cpp, used by the three modes.

#include <cstdint>
#include <optional>
#include <string>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/simulation/match_simulation.hpp"
#include "ssl_formation/simulation/simulated_game_controller.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"

namespace ssl_formation::producer {

struct ProducerOptions {
  // Network (live simulation and --replay).
  std::string vision_address = app::default_vision_address;
  // The simulated game controller's referee messages (live), or a log's (--replay), go here;
  // "none": not at all.
  std::string referee_address = app::default_referee_address;
  // --replay sends a log's tracked vision (type 5) here; "none": not at all.
  std::string tracker_address = app::default_tracker_address;
  std::string interface = app::default_interface;
  int ttl = net::kDefaultMulticastTtl;
  // Simulation (live and -o).
  // match (the default: camera-rate frames, what the default motion model learns from) | paper
  std::string simulation = "match";
  std::string division = "A";      // the match simulation's: A | B
  double frame_rate_hz = 60.0;     // the match simulation's frames per second
  std::string playbook = "wings";  // the match simulation's: a built-in name or a file
  double duration_s = 0.0;         // seconds of data time to simulate; 0: --count decides
  double period_s = 2.0;
  double step_s = 0.0;      // the paper simulation's step; 0: its own (2 s, the paper's)
  std::uint64_t count = 0;  // formations; with --replay: packets
  std::uint64_t seed = 1;
  int cameras = 4;  // as a Division A field has them, and as the demo sends
  double camera_overlap_mm = 200.0;
  double jitter_mm = 0.0;
  double drop_rate = 0.0;
  std::string opponent_color = "yellow";
  std::string opponent_attacks = "+x";
  double field_length_mm = 9000.0;
  double field_width_mm = 6000.0;
  double start_time_s = 0.0;
  // The simulated game controller (live and -o).
  bool referee = true;
  std::string our_team = "ssl-formation";
  std::string opponent_team = "Simulated Opponent";
  double half_length_s = 300.0;
  // Log files.
  std::string write_log;  // -o/--output FILE (once --write-log)
  std::string replay;     // --replay FILE
  double speed = 1.0;
  bool loop = false;
  double replay_start_s = 0.0;
  double replay_end_s = 0.0;  // 0 = to the end of the log
  // Everyday.
  app::DaemonOptions daemon;  // --ready-file: written once the sending socket is open
  double status_interval_s = 5.0;
  bool verbose = false;
};

// The simulation the options describe; throws app::UsageError naming the bad option.
simulation::SimulationConfig simulation_config(const ProducerOptions& options);
// The match simulation the options describe (--simulation match); the game controller is set
// apart (game_controller_config).
simulation::MatchSimulationConfig match_simulation_config(const ProducerOptions& options);
// Its game controller: none with --referee off.
std::optional<simulation::GameControllerConfig> game_controller_config(
    const ProducerOptions& options);

// The three modes; each returns the exit status.
int run_simulation(const ProducerOptions& options);  // live_feed.cpp
int run_write_log(const ProducerOptions& options);   // log_output.cpp
int run_replay(const ProducerOptions& options);      // replay.cpp

}  // namespace ssl_formation::producer
