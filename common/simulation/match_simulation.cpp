#include "ssl_formation/simulation/match_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision_packet.hpp"

namespace ssl_formation::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
// The ball: at a holder's feet this far ahead of its centre, passed and shot at these speeds,
// taken by a robot this close to it.
constexpr double kBallAheadMm = 110.0;
constexpr double kPassSpeedMmS = 4000.0;
constexpr double kShotSpeedMmS = 6000.0;
constexpr double kTakeBallMm = 150.0;
// A goalkeeper stands this far in front of its goal line, and follows the ball's y by this
// share within the goal's width.
constexpr double kKeeperLineMm = 200.0;
constexpr double kKeeperFollow = 0.4;
constexpr double kKeeperRangeMm = 450.0;
// Our markers stand between their opponent and our goal, this far from the opponent.
constexpr double kMarkingMm = 350.0;
// The share of shots that score; the others go wide, for a free kick.
constexpr double kGoalShare = 0.4;

double length(Point p) { return std::hypot(p.x, p.y); }
Point minus(Point a, Point b) { return Point{a.x - b.x, a.y - b.y}; }
Point towards(Point from, Point to, double distance) {
  const Point d = minus(to, from);
  const double l = length(d);
  if (l <= distance || l == 0.0) return to;
  return Point{from.x + d.x * distance / l, from.y + d.y * distance / l};
}

// A kick-off line-up: the opponent in its half (-x), ours in the other, in rows, keepers on
// their lines. Far enough apart for TeamMotion.
std::vector<Point> line_up(const FieldSize& field, int team_size) {
  std::vector<Point> out;
  const double half_length = field.length_mm / 2.0;
  const double half_width = field.width_mm / 2.0;
  for (const double side : {-1.0, 1.0}) {
    out.push_back(Point{side * (half_length - kKeeperLineMm), 0.0});
    const int players = team_size - 1;
    for (int i = 0; i < players; ++i) {
      const int row = i % 2;
      const int column = i / 2;
      const int columns = (players + 1) / 2;
      const double x = side * half_length * (0.25 + 0.35 * row);
      const double y = -half_width * 0.8 + 1.6 * half_width * (column + 0.5) / columns;
      out.push_back(Point{x, y});
    }
  }
  return out;
}

// The limits with the area robots stay in: the field and most of its boundary area (300 mm in
// the rules), which robots making way for one another may use.
MotionLimits within_boundary(MotionLimits limits, const FieldSize& field) {
  constexpr double kBoundaryUsedMm = 250.0;
  limits.area_half_length_mm = field.length_mm / 2.0 + kBoundaryUsedMm;
  limits.area_half_width_mm = field.width_mm / 2.0 + kBoundaryUsedMm;
  return limits;
}

}  // namespace

int team_size_of(Division division) { return division == Division::a ? 11 : 6; }

FieldSize field_of(Division division) {
  return division == Division::a ? FieldSize{12000.0, 9000.0} : FieldSize{9000.0, 6000.0};
}

MatchSimulation::MatchSimulation(MatchSimulationConfig config)
    : config_(std::move(config)),
      field_(field_of(config_.division)),
      team_size_(team_size_of(config_.division)),
      random_(config_.seed),
      robots_(within_boundary(config_.limits, field_), line_up(field_, team_size_)),
      next_geometry_s_(config_.start_time_s) {
  if (config_.playbook.plays.empty()) throw std::invalid_argument("the playbook has no plays");
  if (!(config_.frame_rate_hz > 0.0) || !std::isfinite(config_.frame_rate_hz)) {
    throw std::invalid_argument("the frame rate must be positive");
  }
  if (config_.cameras < 1 || config_.cameras > 8) {
    throw std::invalid_argument("cameras must be between 1 and 8");
  }
  if (!(config_.drop_rate >= 0.0 && config_.drop_rate <= 1.0)) {
    throw std::invalid_argument("drop rate must be between 0 and 1");
  }
  if (!(config_.jitter_mm >= 0.0) || !std::isfinite(config_.jitter_mm)) {
    throw std::invalid_argument("jitter must be a finite, non-negative number of millimetres");
  }
  if (!(config_.loose_play_min_s >= 0.0) ||
      !(config_.loose_play_max_s >= config_.loose_play_min_s)) {
    throw std::invalid_argument("loose play needs 0 <= shortest <= longest");
  }
  targets_.resize(robots_.size());
  for (std::size_t i = 0; i < robots_.size(); ++i) targets_[i] = robots_.position(i);
  play_targets_.assign(targets_.begin(), targets_.begin() + team_size_);
  play_offsets_.assign(static_cast<std::size_t>(team_size_), Point{0.0, 0.0});
  ball_.position = Point{0.0, 0.0};
  start_play(config_.start_time_s, PlayRestart::kickoff);
}

Point MatchSimulation::inside_field(Point p) const {
  return Point{std::clamp(p.x, -field_.length_mm / 2, field_.length_mm / 2),
               std::clamp(p.y, -field_.width_mm / 2, field_.width_mm / 2)};
}

Point MatchSimulation::on_field(Point fraction) const {
  return Point{fraction.x * field_.length_mm / 2.0, fraction.y * field_.width_mm / 2.0};
}

void MatchSimulation::start_play(double now_s, PlayRestart restart) {
  // A play for this restart, by weight; any play if the playbook has none for it.
  std::vector<double> weights;
  for (const Play& play : config_.playbook.plays) {
    weights.push_back(play.restart == restart ? play.weight : 0.0);
  }
  if (std::all_of(weights.begin(), weights.end(), [](double w) { return w == 0.0; })) {
    for (std::size_t i = 0; i < weights.size(); ++i) weights[i] = config_.playbook.plays[i].weight;
  }
  std::discrete_distribution<int> pick(weights.begin(), weights.end());
  play_ = pick(random_);
  step_ = 0;
  ++plays_started_;
  std::uniform_real_distribution<double> offset(-config_.position_variation,
                                                config_.position_variation);
  for (Point& p : play_offsets_) p = on_field(Point{offset(random_), offset(random_)});
  std::uniform_real_distribution<double> scale(1.0 - config_.timing_variation,
                                               1.0 + config_.timing_variation);
  hold_scale_ = scale(random_);
  aim_at_step();
  step_ends_s_ = now_s + hold_scale_ * config_.playbook.plays[play_].steps[0].hold_s;
}

void MatchSimulation::start_loose_play(double now_s) {
  play_ = -1;
  std::uniform_real_distribution<double> duration(config_.loose_play_min_s,
                                                  config_.loose_play_max_s);
  step_ends_s_ = now_s + duration(random_);
  // Everyone drifts from where the play left them.
  std::uniform_real_distribution<double> drift(-0.12, 0.12);
  for (int id = 1; id < team_size_; ++id) {
    Point& target = play_targets_[static_cast<std::size_t>(id)];
    const Point moved = on_field(Point{drift(random_), drift(random_)});
    target = inside_field(Point{target.x + moved.x, target.y + moved.y});
  }
}

void MatchSimulation::aim_at_step() {
  const PlayStep& step = config_.playbook.plays[play_].steps[static_cast<std::size_t>(step_)];
  for (const PlayTarget& target : step.targets) {
    if (target.robot_id >= static_cast<std::uint32_t>(team_size_)) continue;  // Division B
    const Point p = on_field(target.position);
    const Point offset = play_offsets_[target.robot_id];
    play_targets_[target.robot_id] = inside_field(Point{p.x + offset.x, p.y + offset.y});
  }
  if (step.shot && ball_.holder >= 0) {
    // At the goal it attacks, somewhere within the posts.
    std::uniform_real_distribution<double> aim(-400.0, 400.0);
    const Point goal{field_.length_mm / 2.0 + 200.0, aim(random_)};
    const Point from = ball_.position;
    const double l = length(minus(goal, from));
    ball_.velocity =
        Point{(goal.x - from.x) / l * kShotSpeedMmS, (goal.y - from.y) / l * kShotSpeedMmS};
    ball_.holder = -1;
    ball_.receiver = -1;
    ball_.shot = true;
    ++shots_;
  } else if (step.ball_robot && *step.ball_robot < static_cast<std::uint32_t>(team_size_) &&
             static_cast<int>(*step.ball_robot) != ball_.holder) {
    const int receiver = static_cast<int>(*step.ball_robot);
    if (ball_.holder >= 0) {
      ball_.holder = -1;
      ball_.rolling = true;
      ++passes_;
    }
    // A pass from the holder (or one rolling already, sent on), or a loose ball the receiver is
    // to fetch.
    ball_.receiver = receiver;
  }
}

void MatchSimulation::advance_play(double now_s) {
  if (now_s < step_ends_s_) return;
  if (play_ < 0) {
    start_play(now_s, PlayRestart::any);
    return;
  }
  const Play& play = config_.playbook.plays[play_];
  if (static_cast<std::size_t>(step_ + 1) < play.steps.size()) {
    ++step_;
    aim_at_step();
    step_ends_s_ = now_s + hold_scale_ * play.steps[static_cast<std::size_t>(step_)].hold_s;
    return;
  }
  start_loose_play(now_s);
}

void MatchSimulation::restart(double now_s) {
  std::bernoulli_distribution goal(kGoalShare);
  ball_ = Ball{};
  if (goal(random_)) {
    // A goal: the next play is a kick-off, from the centre.
    ++goals_;
    start_play(now_s, PlayRestart::kickoff);
    return;
  }
  // Wide: a free kick, the ball placed where the play's taker starts.
  start_play(now_s, PlayRestart::free_kick);
  const PlayStep& first = config_.playbook.plays[play_].steps.front();
  if (first.ball_robot && *first.ball_robot < static_cast<std::uint32_t>(team_size_)) {
    const Point taker = play_targets_[*first.ball_robot];
    ball_.position = Point{taker.x + kBallAheadMm, taker.y};
  } else {
    ball_.position = on_field(Point{0.9, 0.9});
  }
}

void MatchSimulation::update_targets() {
  const double half_length = field_.length_mm / 2.0;
  const auto keeper_y = [&](double ball_y) {
    return std::clamp(ball_y * kKeeperFollow, -kKeeperRangeMm, kKeeperRangeMm);
  };
  // The opponent: its keeper on its line, the others where the play puts them; the receiver
  // of a loose ball fetches it.
  targets_[0] = Point{-half_length + kKeeperLineMm, keeper_y(ball_.position.y)};
  for (int id = 1; id < team_size_; ++id) targets_[id] = play_targets_[id];
  if (ball_.receiver >= 0 && !ball_.rolling) {
    targets_[ball_.receiver] = ball_.position;
  }
  // Ours: the keeper on our line, every other robot marking the opponent with its id, between
  // it and our goal.
  const Point our_goal{half_length, 0.0};
  targets_[team_size_] = Point{half_length - kKeeperLineMm, keeper_y(ball_.position.y)};
  for (int id = 1; id < team_size_; ++id) {
    const Point opponent = robots_.position(static_cast<std::size_t>(id));
    targets_[team_size_ + id] = inside_field(towards(opponent, our_goal, kMarkingMm));
  }
}

void MatchSimulation::move_ball(double dt_s, double now_s) {
  const double half_length = field_.length_mm / 2.0;
  const double half_width = field_.width_mm / 2.0;
  if (ball_.holder >= 0) {
    const Point holder = robots_.position(static_cast<std::size_t>(ball_.holder));
    ball_.position = Point{holder.x + kBallAheadMm, holder.y};
    ball_.velocity = Point{0.0, 0.0};
    return;
  }
  if (ball_.shot) {
    ball_.position.x += ball_.velocity.x * dt_s;
    ball_.position.y += ball_.velocity.y * dt_s;
    if (ball_.position.x > half_length || std::abs(ball_.position.y) > half_width) restart(now_s);
    return;
  }
  if (ball_.receiver < 0) return;
  const Point receiver = robots_.position(static_cast<std::size_t>(ball_.receiver));
  if (length(minus(receiver, ball_.position)) < kTakeBallMm) {
    ball_.holder = ball_.receiver;
    ball_.receiver = -1;
    ball_.rolling = false;
    ball_.velocity = Point{0.0, 0.0};
    return;
  }
  // A loose ball waits for its receiver to fetch it (update_targets() sends it there); a pass
  // rolls towards the receiver, which runs on to where the play sends it.
  if (!ball_.rolling) return;
  const Point next = towards(ball_.position, receiver, kPassSpeedMmS * dt_s);
  ball_.velocity = Point{(next.x - ball_.position.x) / dt_s, (next.y - ball_.position.y) / dt_s};
  ball_.position = next;
}

MatchFrame MatchSimulation::next() {
  MatchFrame frame;
  frame.index = frames_;
  const double dt_s = 1.0 / config_.frame_rate_hz;
  frame.t_capture = config_.start_time_s + static_cast<double>(frames_) * dt_s;
  frame.frame_number = frame_number_++;
  if (frames_ > 0) {
    advance_play(frame.t_capture);
    update_targets();
    robots_.step(dt_s, targets_);
    move_ball(dt_s, frame.t_capture);
  }
  ++frames_;
  for (int id = 0; id < team_size_; ++id) {
    frame.opponent.push_back(robots_.position(static_cast<std::size_t>(id)));
    frame.ours.push_back(robots_.position(static_cast<std::size_t>(team_size_ + id)));
  }
  frame.ball = ball_.position;
  if (play_ >= 0) {
    frame.play = config_.playbook.plays[play_].name;
    frame.play_step = step_;
  }
  build_packets(frame);
  return frame;
}

void MatchSimulation::build_packets(MatchFrame& frame) {
  if (!geometry_sent_ || frame.t_capture >= next_geometry_s_) {
    frame.packets.push_back(make_geometry_packet(field_));
    geometry_sent_ = true;
    next_geometry_s_ = frame.t_capture + config_.geometry_interval_s;
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
  std::vector<Point> opponent_feed;
  std::vector<Point> ours_feed;
  for (int id = 0; id < team_size_; ++id) {
    opponent_feed.push_back(observe(frame.opponent[static_cast<std::size_t>(id)]));
    ours_feed.push_back(observe(frame.ours[static_cast<std::size_t>(id)]));
  }
  const Point ball = observe(frame.ball);
  // Each team faces the goal it attacks.
  const float opponent_facing =
      config_.opponent_attacks == AttackDirection::positive_x ? 0.0F : static_cast<float>(kPi);
  const float our_facing = opponent_facing == 0.0F ? static_cast<float>(kPi) : 0.0F;

  std::bernoulli_distribution dropped(config_.drop_rate);
  for (int camera = 0; camera < config_.cameras; ++camera) {
    const SimulatedVision::Area area =
        SimulatedVision::camera_area(camera, config_.cameras, field_, config_.camera_overlap_mm);
    DetectionFrameSpec spec;
    spec.camera_id = static_cast<std::uint32_t>(camera);
    spec.frame_number = frame.frame_number;
    spec.t_capture = frame.t_capture;
    spec.t_sent = frame.t_capture + 0.004;  // processing latency, as SSL-Vision reports
    std::vector<RobotDetection>& opponent =
        config_.opponent_color == TeamColor::yellow ? spec.yellow : spec.blue;
    std::vector<RobotDetection>& ours =
        config_.opponent_color == TeamColor::yellow ? spec.blue : spec.yellow;
    for (int id = 0; id < team_size_; ++id) {
      const auto i = static_cast<std::size_t>(id);
      const auto robot_id = static_cast<std::uint32_t>(id);
      if (area.contains(opponent_feed[i])) {
        opponent.push_back({robot_id, opponent_feed[i], opponent_facing, 0.92F});
      }
      if (area.contains(ours_feed[i])) ours.push_back({robot_id, ours_feed[i], our_facing, 0.92F});
    }
    if (area.contains(ball)) spec.balls.push_back(ball);
    if (config_.drop_rate > 0 && dropped(random_)) {
      ++frame.dropped_packets;
      continue;
    }
    frame.packets.push_back(make_detection_packet(spec));
  }
}

}  // namespace ssl_formation::sim
