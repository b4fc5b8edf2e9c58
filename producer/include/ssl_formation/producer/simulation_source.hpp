#pragma once
// What ssl-producer simulates, step by step, whichever simulation the options choose: the
// paper's (a formation every --step seconds of data time) or the match (a frame every
// 1/--frame-rate seconds). The live feed and --write-log send or write each step the same way:
// its referee message first, then its vision packets.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ssl_formation/app/status_line.hpp"
#include "ssl_formation/producer/producer_options.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::producer {

struct SimulatedStep {
  std::uint64_t index = 0;
  double t_capture = 0.0;
  std::optional<Referee> referee;  // the game controller's message, if one runs
  std::vector<SSL_WrapperPacket> packets;
  int dropped_packets = 0;
};

class SimulationSource {
 public:
  virtual ~SimulationSource() = default;
  virtual SimulatedStep next() = 0;
  // What a step is ("formations", "frames"), and its data time.
  virtual const char* steps_name() const = 0;
  virtual double step_s() const = 0;
  // The wall time between two steps of the live feed; 0: as fast as possible.
  virtual double live_period_s() const = 0;
  // What has happened so far, on a status line: "frames=12000 match_time=200.0s plays=40 ...".
  virtual void describe(std::uint64_t steps, app::StatusLine& line) const = 0;
  virtual const simulation::SimulatedGameController* game_controller() const = 0;
};

// The simulated game controller on a status line: the figures game=running attacks=-x
// score=1:0(yellow:blue) (the side the opponent attacks), and the details stage and match (how
// many matches began).
void describe_game_controller(const simulation::SimulatedGameController& game,
                              app::StatusLine& line);

// Whether `steps` steps of `step_s` each are all that --count or --duration ask for.
bool simulation_done(const ProducerOptions& options, std::uint64_t steps, double step_s);

// The simulation the options choose, with its game controller when `with_referee` (and the
// options ask for one). Throws app::UsageError naming a bad option; a playbook file with an
// error is one, its message naming the file and line.
std::unique_ptr<SimulationSource> make_simulation_source(const ProducerOptions& options,
                                                         bool with_referee);

}  // namespace ssl_formation::producer
