#include "ssl_formation/simulation/simulated_vision.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::simulation {

namespace {

// Robot 0 is the goalkeeper; the opponent attacks towards +x, so its own goal is at x = -4500.
// "Left" is +y, as seen by a player facing the attack direction.
const std::array<std::array<TeamPositions, formations_per_play>, play_count> plays{{
    // Play 1: a pass and a shot through the centre.
    {{
        {{{-4200, 0}, {-2500, -1200}, {-2500, 1200}, {-600, -1500}, {-600, 1500}, {400, 0}}},
        {{{-4200, 0}, {-1600, -1000}, {-1600, 1000}, {900, -1800}, {1400, 1100}, {2000, 0}}},
        {{{-4000, 0}, {-500, -1000}, {-500, 1000}, {2600, -1400}, {3100, 900}, {3900, 200}}},
    }},
    // Play 2: a corner from the left.
    {{
        {{{-4200, 0}, {-2000, -800}, {-1500, 1200}, {1500, 2100}, {2500, 500}, {3000, -800}}},
        {{{-4200, 0}, {-1000, -500}, {0, 1600}, {4300, 2850}, {3500, 900}, {3200, -1000}}},
        {{{-4000, 0}, {0, -500}, {1600, 1600}, {4000, 2600}, {3900, 300}, {3600, -700}}},
    }},
    // Play 3: a corner from the right, the mirror image of play 2.
    {{
        {{{-4200, 0}, {-2000, 800}, {-1500, -1200}, {1500, -2100}, {2500, -500}, {3000, 800}}},
        {{{-4200, 0}, {-1000, 500}, {0, -1600}, {4300, -2850}, {3500, -900}, {3200, 1000}}},
        {{{-4000, 0}, {0, 500}, {1600, -1600}, {4000, -2600}, {3900, -300}, {3600, 700}}},
    }},
}};

// Our own team (the other colour): a compact defence in front of our goal at +x.
const TeamPositions our_team{
    {{4200, 0}, {3000, -1000}, {3000, 1000}, {1800, -1800}, {1800, 1800}, {1000, 0}}};

}  // namespace

const TeamPositions& play_formation(int play, int formation) {
  return plays.at(static_cast<std::size_t>(play)).at(static_cast<std::size_t>(formation));
}

void check_camera_settings(int cameras, double drop_rate, double jitter_mm) {
  if (cameras < 1 || cameras > 8) throw std::invalid_argument("cameras must be between 1 and 8");
  if (!(drop_rate >= 0.0 && drop_rate <= 1.0)) {
    throw std::invalid_argument("drop rate must be between 0 and 1");
  }
  if (!(jitter_mm >= 0.0) || !std::isfinite(jitter_mm)) {
    throw std::invalid_argument("jitter must be a finite, non-negative number of millimetres");
  }
}

SimulatedVision::SimulatedVision(SimulationConfig config)
    : config_(config), random_(config.seed), geometry_(config.geometry_interval_s) {
  check_camera_settings(config_.cameras, config_.drop_rate, config_.jitter_mm);
  if (!(config_.step_s > 0.0) || !std::isfinite(config_.step_s)) {
    throw std::invalid_argument("step must be positive");
  }
  if (!config_.field.valid()) throw std::invalid_argument("field size must be positive");
}

SimulatedVision::Area SimulatedVision::camera_area(int camera, int cameras, const FieldSize& field,
                                                   double overlap_mm) {
  // SSL-Vision's layouts: 1 camera, 2 halves, 4 quadrants, 8 = 4 x 2; otherwise columns.
  const int rows = cameras >= 4 && cameras % 2 == 0 ? 2 : 1;
  const int columns = cameras / rows;
  const int column = camera % columns;
  const int row = camera / columns;
  // Include the boundary area so robots there are seen, as real cameras do.
  const double boundary = 300.0;
  const double length = field.length_mm + 2 * boundary;
  const double width = field.width_mm + 2 * boundary;
  const double half = overlap_mm / 2.0;
  Area area{-length / 2 + length * column / columns - half,
            -length / 2 + length * (column + 1) / columns + half,
            -width / 2 + width * row / rows - half, -width / 2 + width * (row + 1) / rows + half};
  // The outer edges of the outer cameras reach beyond the boundary: nothing is lost there.
  if (column == 0) area.min_x = -1e9;
  if (column == columns - 1) area.max_x = 1e9;
  if (row == 0) area.min_y = -1e9;
  if (row == rows - 1) area.max_y = 1e9;
  return area;
}

TeamPositions SimulatedVision::random_formation() {
  std::uniform_real_distribution<double> x(-config_.field.length_mm / 2,
                                           config_.field.length_mm / 2);
  std::uniform_real_distribution<double> y(-config_.field.width_mm / 2, config_.field.width_mm / 2);
  TeamPositions team;
  for (Point& p : team) p = Point{x(random_), y(random_)};
  return team;
}

SimulatedFormation SimulatedVision::next() {
  SimulatedFormation formation;
  formation.index = formations_;
  formation.t_capture = next_t_capture();
  formation.frame_number = frame_number_++;
  ++formations_;

  if (current_play_ < 0) {
    // A new cycle: uniform over {random, play 1, play 2, play 3}.
    std::uniform_int_distribution<int> pick(0, play_count);
    const int choice = pick(random_);
    if (choice == 0) {
      formation.source = FormationSource::random;
      formation.opponent = random_formation();
      build_packets(formation);
      return formation;
    }
    current_play_ = choice - 1;
    current_step_ = 0;
  }
  formation.source = FormationSource::play;
  formation.play = current_play_;
  formation.play_step = current_step_;
  // Plays are drawn for a 9 x 6 m field; another field size stretches them.
  formation.opponent = play_formation(current_play_, current_step_);
  for (Point& p : formation.opponent) {
    p.x *= config_.field.length_mm / 9000.0;
    p.y *= config_.field.width_mm / 6000.0;
  }
  if (++current_step_ == formations_per_play) current_play_ = -1;
  build_packets(formation);
  return formation;
}

void SimulatedVision::build_packets(SimulatedFormation& formation) {
  if (geometry_.due(formation.t_capture)) {
    formation.packets.push_back(make_geometry_packet(config_.field));
  }

  std::normal_distribution<double> jitter(0.0, config_.jitter_mm > 0 ? config_.jitter_mm : 1.0);
  const auto observe = [&](Point normalised) {
    Point feed = normalise(normalised, config_.opponent_attacks);
    if (config_.jitter_mm > 0) {
      feed.x += jitter(random_);
      feed.y += jitter(random_);
    }
    return feed;
  };
  std::array<Point, robots_per_team> opponent_feed;
  std::array<Point, robots_per_team> ours_feed;
  for (int id = 0; id < robots_per_team; ++id) {
    opponent_feed[static_cast<std::size_t>(id)] =
        observe(formation.opponent[static_cast<std::size_t>(id)]);
    const Point ours = our_team[static_cast<std::size_t>(id)];
    ours_feed[static_cast<std::size_t>(id)] = observe(
        Point{ours.x * config_.field.length_mm / 9000.0, ours.y * config_.field.width_mm / 6000.0});
  }
  // The ball is at the feet of the opponent's most advanced robot.
  const auto leader = std::max_element(formation.opponent.begin(), formation.opponent.end(),
                                       [](const Point& a, const Point& b) { return a.x < b.x; });
  SeenInstant instant;
  instant.frame_number = formation.frame_number;
  instant.t_capture = formation.t_capture;
  instant.opponent_color = config_.opponent_color;
  instant.opponent = opponent_feed;
  instant.ours = ours_feed;
  instant.opponent_facing = 0.0F;
  instant.our_facing = 3.14F;
  instant.ball = normalise(Point{leader->x + 100.0, leader->y}, config_.opponent_attacks);
  const CameraLayout layout{config_.cameras, config_.field, config_.camera_overlap_mm,
                            config_.drop_rate};
  formation.dropped_packets += append_camera_packets(layout, instant, random_, formation.packets);
}

int append_camera_packets(const CameraLayout& layout, const SeenInstant& instant,
                          std::mt19937_64& random, std::vector<SSL_WrapperPacket>& packets) {
  int dropped = 0;
  std::bernoulli_distribution lost(layout.drop_rate);
  for (int camera = 0; camera < layout.cameras; ++camera) {
    const SimulatedVision::Area area =
        SimulatedVision::camera_area(camera, layout.cameras, layout.field, layout.overlap_mm);
    DetectionFrameSpec spec;
    spec.camera_id = static_cast<std::uint32_t>(camera);
    spec.frame_number = instant.frame_number;
    spec.t_capture = instant.t_capture;
    spec.t_sent = instant.t_capture + 0.004;  // processing latency, as SSL-Vision reports
    std::vector<RobotDetection>& opponent =
        instant.opponent_color == TeamColor::yellow ? spec.yellow : spec.blue;
    std::vector<RobotDetection>& ours =
        instant.opponent_color == TeamColor::yellow ? spec.blue : spec.yellow;
    for (std::size_t i = 0; i < instant.opponent.size(); ++i) {
      const auto id = static_cast<std::uint32_t>(i);
      if (area.contains(instant.opponent[i])) {
        opponent.push_back({id, instant.opponent[i], instant.opponent_facing, 0.92F});
      }
    }
    for (std::size_t i = 0; i < instant.ours.size(); ++i) {
      const auto id = static_cast<std::uint32_t>(i);
      if (area.contains(instant.ours[i])) {
        ours.push_back({id, instant.ours[i], instant.our_facing, 0.92F});
      }
    }
    if (area.contains(instant.ball)) spec.balls.push_back(instant.ball);
    if (layout.drop_rate > 0 && lost(random)) {
      ++dropped;
      continue;
    }
    packets.push_back(make_detection_packet(spec));
  }
  return dropped;
}

}  // namespace ssl_formation::simulation
