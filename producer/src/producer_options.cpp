#include "ssl_formation/producer/producer_options.hpp"

#include <cmath>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/match/match.hpp"

namespace ssl_formation::producer {

namespace {

// What both simulations put on the wire the same way: cameras, noise, drops, who plays where.
struct FeedSettings {
  int cameras = 1;
  double camera_overlap_mm = 0.0;
  double jitter_mm = 0.0;
  double drop_rate = 0.0;
  TeamColor opponent_color = TeamColor::yellow;
  AttackDirection opponent_attacks = AttackDirection::positive_x;
};

FeedSettings feed_settings(const ProducerOptions& options) {
  FeedSettings feed;
  if (options.cameras < 1 || options.cameras > 8) throw app::UsageError("--cameras must be 1 to 8");
  feed.cameras = options.cameras;
  if (!(options.camera_overlap_mm >= 0.0) || !std::isfinite(options.camera_overlap_mm)) {
    throw app::UsageError("--camera-overlap must be >= 0 mm");
  }
  feed.camera_overlap_mm = options.camera_overlap_mm;
  if (!(options.jitter_mm >= 0.0) || !std::isfinite(options.jitter_mm)) {
    throw app::UsageError("--jitter-mm must be a finite number >= 0");
  }
  feed.jitter_mm = options.jitter_mm;
  if (!(options.drop_rate >= 0.0 && options.drop_rate <= 1.0)) {
    throw app::UsageError("--drop-rate must be between 0 and 1");
  }
  feed.drop_rate = options.drop_rate;
  const auto color = parse_team_color(options.opponent_color);
  if (!color) throw app::UsageError("--opponent-color must be yellow or blue");
  feed.opponent_color = *color;
  const auto attacks = parse_attack_direction(options.opponent_attacks);
  if (!attacks) throw app::UsageError("--opponent-attacks must be +x or -x");
  feed.opponent_attacks = *attacks;
  return feed;
}

// Both simulations' configs name these settings alike.
template <class Config>
void apply_feed_settings(const ProducerOptions& options, Config& config) {
  const FeedSettings feed = feed_settings(options);
  config.cameras = feed.cameras;
  config.camera_overlap_mm = feed.camera_overlap_mm;
  config.jitter_mm = feed.jitter_mm;
  config.drop_rate = feed.drop_rate;
  config.opponent_color = feed.opponent_color;
  config.opponent_attacks = feed.opponent_attacks;
}

}  // namespace

simulation::SimulationConfig simulation_config(const ProducerOptions& options) {
  simulation::SimulationConfig config;
  config.seed = options.seed;
  if (options.step_s != 0.0) {
    if (!(options.step_s > 0.0) || !std::isfinite(options.step_s)) {
      throw app::UsageError("--step must be a positive number of seconds, or auto");
    }
    config.step_s = options.step_s;
  }
  config.start_time_s = options.start_time_s;
  apply_feed_settings(options, config);
  config.field = FieldSize{options.field_length_mm, options.field_width_mm};
  if (!config.field.valid())
    throw app::UsageError("--field-length and --field-width must be positive");
  return config;
}

simulation::MatchSimulationConfig match_simulation_config(const ProducerOptions& options) {
  simulation::MatchSimulationConfig config;
  config.seed = options.seed;
  if (options.division == "A" || options.division == "a") {
    config.division = simulation::Division::a;
  } else if (options.division == "B" || options.division == "b") {
    config.division = simulation::Division::b;
  } else {
    throw app::UsageError("--division must be A or B, not '" + options.division + "'");
  }
  if (!(options.frame_rate_hz > 0.0) || options.frame_rate_hz > 1000.0) {
    throw app::UsageError("--frame-rate must be more than 0 and at most 1000 frames a second");
  }
  config.frame_rate_hz = options.frame_rate_hz;
  config.start_time_s = options.start_time_s;
  apply_feed_settings(options, config);
  Result<simulation::Playbook> playbook = simulation::builtin_or_file_playbook(options.playbook);
  if (!playbook) throw app::UsageError("--playbook: " + playbook.error().message);
  config.playbook = std::move(*playbook);
  return config;
}

std::optional<simulation::GameControllerConfig> game_controller_config(
    const ProducerOptions& options) {
  if (!options.referee) return std::nullopt;
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
  simulation::GameControllerConfig config;
  config.seed = options.seed;
  config.our_name = options.our_team;
  config.opponent_name = options.opponent_team;
  config.half_s = options.half_length_s;
  return config;
}

}  // namespace ssl_formation::producer
