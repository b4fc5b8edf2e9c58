#include "ssl_formation/producer/producer_options.hpp"

#include <cmath>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/match.hpp"

namespace ssl_formation::producer {

sim::SimulationConfig simulation_config(const ProducerOptions& options) {
  sim::SimulationConfig config;
  config.seed = options.seed;
  if (!(options.step_s > 0.0)) throw app::UsageError("--step must be a positive number of seconds");
  config.step_s = options.step_s;
  config.start_time_s = options.start_time_s;
  if (options.cameras < 1 || options.cameras > 8) throw app::UsageError("--cameras must be 1 to 8");
  config.cameras = options.cameras;
  if (!(options.camera_overlap_mm >= 0.0))
    throw app::UsageError("--camera-overlap must be >= 0 mm");
  config.camera_overlap_mm = options.camera_overlap_mm;
  if (!(options.jitter_mm >= 0.0)) throw app::UsageError("--jitter-mm must be >= 0");
  config.jitter_mm = options.jitter_mm;
  if (!(options.drop_rate >= 0.0 && options.drop_rate <= 1.0)) {
    throw app::UsageError("--drop-rate must be between 0 and 1");
  }
  config.drop_rate = options.drop_rate;
  const auto color = parse_team_color(options.opponent_color);
  if (!color) throw app::UsageError("--opponent-color must be yellow or blue");
  config.opponent_color = *color;
  const auto attacks = parse_attack_direction(options.opponent_attacks);
  if (!attacks) throw app::UsageError("--opponent-attacks must be +x or -x");
  config.opponent_attacks = *attacks;
  config.field = FieldSize{options.field_length_mm, options.field_width_mm};
  if (!config.field.valid())
    throw app::UsageError("--field-length and --field-width must be positive");
  return config;
}

std::optional<sim::GameControllerConfig> game_controller_config(const ProducerOptions& options,
                                                                bool live) {
  if (!options.referee) return std::nullopt;
  if (live && !app::parse_referee_option(options.referee_address)) return std::nullopt;
  if (!(options.half_length_s > 0.0) || !std::isfinite(options.half_length_s)) {
    throw app::UsageError("--half-length must be a positive number of seconds");
  }
  if (trimmed_team_name(options.our_team).empty() ||
      trimmed_team_name(options.opponent_team).empty()) {
    throw app::UsageError("--our-team and --opponent-team must not be empty");
  }
  if (same_team_name(options.our_team, options.opponent_team)) {
    throw app::UsageError(
        "--our-team and --opponent-team must differ: the daemons tell the "
        "teams apart by name");
  }
  sim::GameControllerConfig config;
  config.seed = options.seed;
  config.our_name = options.our_team;
  config.opponent_name = options.opponent_team;
  config.half_s = options.half_length_s;
  return config;
}

}  // namespace ssl_formation::producer
