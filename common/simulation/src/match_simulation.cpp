#include "ssl_formation/simulation/match_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

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
// The share of shots that score in the plain game (GameShape has its own); the others go wide,
// for a free kick.
constexpr double kGoalShare = 0.4;
// Of the shots wide, the share a defender touched last: a corner for the opponent; the others
// give us a goal kick.
constexpr double kCornerShare = 0.5;
// While the game is stopped robots keep this far from the ball and drive at most this fast
// (the rules: 0.5 m and 1.5 m/s).
constexpr double kStopDistanceMm = 600.0;
constexpr double kStopSpeedMmS = 1500.0;
// On their way robots keep out of this disc around the ball (the rules' 0.5 m and a margin).
constexpr double kKeepOutMm = 560.0;
// A foul the referee calls (GameShape): the ball is placed this far from where it was, and at
// least this far inside the field lines.
constexpr double kFoulPlacementMinMm = 1000.0;
constexpr double kFoulPlacementMaxMm = 3000.0;
constexpr double kPlacementMarginMm = 300.0;
// A kick-off: the kicking team's other robots, and all of the other team, stay out of the
// centre circle (radius 0.5 m) and in their own halves.
constexpr double kCentreCircleMm = 650.0;
constexpr double kOwnHalfMarginMm = 150.0;
// Ball placement carries the ball at this speed once the placing robot has it.
constexpr double kPlacementSpeedMmS = 1500.0;
// Our possession, after a goal kick or our kick-off, lasts this long before the opponent wins
// the ball back.
constexpr double kOurPossessionMinS = 2.0;
constexpr double kOurPossessionMaxS = 5.0;

double length(Point p) { return std::hypot(p.x, p.y); }
// `p` moved out to `distance` from `centre` if it is closer.
Point away_from(Point p, Point centre, double distance) {
  const double dx = p.x - centre.x;
  const double dy = p.y - centre.y;
  const double l = std::hypot(dx, dy);
  if (l >= distance) return p;
  if (l == 0.0) return Point{centre.x - distance, centre.y};
  return Point{centre.x + dx / l * distance, centre.y + dy / l * distance};
}
// `p` moved out to `distance` from the segment from `a` to `b` if it is closer: off the path a
// robot placing the ball takes.
Point away_from_segment(Point p, Point a, Point b, double distance) {
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  const double l2 = dx * dx + dy * dy;
  const double t =
      l2 > 0.0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / l2, 0.0, 1.0) : 0.0;
  const Point closest{a.x + t * dx, a.y + t * dy};
  if (std::hypot(p.x - closest.x, p.y - closest.y) >= distance) return p;
  if (p.x == closest.x && p.y == closest.y && l2 > 0.0) {
    // On the path: out to its right.
    const double l = std::sqrt(l2);
    return Point{closest.x + dy / l * distance, closest.y - dx / l * distance};
  }
  return away_from(p, closest, distance);
}
// The team a team command (a kick-off, a free kick, a placement) is for: its yellow value is
// even, its blue one odd.
TeamColor team_of_command(int command) {
  return command % 2 == 0 ? TeamColor::yellow : TeamColor::blue;
}
Point minus(Point a, Point b) { return Point{a.x - b.x, a.y - b.y}; }
Point towards(Point from, Point to, double distance) {
  const Point d = minus(to, from);
  const double l = length(d);
  if (l <= distance || l == 0.0) return to;
  return Point{from.x + d.x * distance / l, from.y + d.y * distance / l};
}

// The index in [first, last) whose position (position_of(index)) is nearest to `p`; the first
// such on a tie.
template <class PositionOf>
int nearest_of(int first, int last, Point p, PositionOf position_of) {
  int nearest = first;
  double best = 1e18;
  for (int i = first; i < last; ++i) {
    const double d = length(minus(position_of(i), p));
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  return nearest;
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
      attacks_(config_.opponent_attacks),
      field_(field_of(config_.division)),
      team_size_(team_size_of(config_.division)),
      random_(config_.seed),
      // The vision's noise and drops draw from a stream of their own: with and without them,
      // a seed plays the same match.
      noise_random_(config_.seed ^ 0x5bd1e995a5a5a5a5ULL),
      robots_(within_boundary(config_.limits, field_), line_up(field_, team_size_)),
      geometry_(config_.geometry_interval_s) {
  if (config_.playbook.plays.empty()) throw std::invalid_argument("the playbook has no plays");
  if (!(config_.frame_rate_hz > 0.0) || !std::isfinite(config_.frame_rate_hz)) {
    throw std::invalid_argument("the frame rate must be positive");
  }
  check_camera_settings(config_.cameras, config_.drop_rate, config_.jitter_mm);
  if (!(config_.position_variation >= 0.0 && config_.position_variation <= 0.5) ||
      !(config_.timing_variation >= 0.0 && config_.timing_variation < 1.0)) {
    throw std::invalid_argument("play variation: positions 0 to 0.5, timing 0 to under 1");
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
  if (config_.game) {
    GameControllerConfig game = *config_.game;
    game.opponent_color = config_.opponent_color;
    game.opponent_attacks = config_.opponent_attacks;
    game.start_time_s = config_.start_time_s;
    game.random_stoppages = false;  // the play calls them
    game_.emplace(std::move(game));
  }
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
  } else if (step.ball_robot && receiver_for(step) != ball_.holder) {
    const int receiver = receiver_for(step);
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

int MatchSimulation::receiver_for(const PlayStep& step) const {
  const auto id = *step.ball_robot;
  if (id < static_cast<std::uint32_t>(team_size_)) return static_cast<int>(id);
  // A robot the division does not field (Division B has ids 0 to 5): the pass goes to the
  // field player whose target is nearest to where it would have been.
  Point meant = play_targets_[1];
  for (const PlayTarget& target : step.targets) {
    if (target.robot_id == id) meant = on_field(target.position);
  }
  return nearest_of(1, team_size_, meant,
                    [&](int i) { return play_targets_[static_cast<std::size_t>(i)]; });
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
  if (first.ball_robot) {
    const Point taker = play_targets_[static_cast<std::size_t>(receiver_for(first))];
    ball_.position = Point{taker.x + kBallAheadMm, taker.y};
  } else {
    ball_.position = on_field(Point{0.9, 0.9});
  }
}

void MatchSimulation::update_targets(double now_s) {
  const double half_length = field_.length_mm / 2.0;
  const auto keeper_y = [&](double ball_y) {
    return std::clamp(ball_y * kKeeperFollow, -kKeeperRangeMm, kKeeperRangeMm);
  };
  const auto robot = [this](int i) { return robot_position(i); };
  if (mode_ == Mode::halted) return;  // nobody moves, whatever the targets
  if (mode_ == Mode::lining_up) {
    // The teams walk to where the next kick-off lines them up (after half time, at the end they
    // now defend), away from the ball.
    const std::vector<Point> shape = line_up(field_, team_size_);
    for (std::size_t i = 0; i < targets_.size(); ++i) {
      targets_[i] = inside_field(away_from(shape[i], ball_.position, kStopDistanceMm));
    }
    return;
  }
  // The opponent: its keeper on its line, the others where the play puts them. Ours: the
  // keeper on our line, every other robot marking the opponent with its id, between it and our
  // goal.
  targets_[0] = Point{-half_length + kKeeperLineMm, keeper_y(ball_.position.y)};
  for (int id = 1; id < team_size_; ++id) targets_[id] = play_targets_[id];
  const Point our_goal{half_length, 0.0};
  targets_[team_size_] = Point{half_length - kKeeperLineMm, keeper_y(ball_.position.y)};
  for (int id = 1; id < team_size_; ++id) {
    targets_[team_size_ + id] = inside_field(towards(robot(id), our_goal, kMarkingMm));
  }
  switch (mode_) {
    case Mode::opponent_play:
      // A free kick is taken a moment after its command: until then the taker waits.
      if (ball_.holder >= 0 && !ours(ball_.holder) && now_s < kick_at_s_) {
        targets_[static_cast<std::size_t>(ball_.holder)] = robot(ball_.holder);
      }
      break;
    case Mode::our_possession: {
      // Our holder drives at the opponent's goal; the opponent's nearest field player presses.
      if (ball_.holder >= 0 && ours(ball_.holder)) {
        // A free kick is taken a moment after its command: until then the taker waits.
        const Point p = robot(ball_.holder);
        targets_[ball_.holder] =
            now_s < kick_at_s_ ? p : inside_field(Point{p.x - 1500.0, p.y * 0.8});
      }
      targets_[nearest_of(1, team_size_, ball_.position, robot)] = ball_.position;
      break;
    }
    case Mode::kickoff_preparation:
      // Both teams in their halves, out of the centre circle but for the kicker at the ball.
      for (int i = 1; i < 2 * team_size_; ++i) {
        if (i == team_size_) continue;  // our keeper
        Point& t = targets_[static_cast<std::size_t>(i)];
        t.x = ours(i) ? std::max(t.x, kOwnHalfMarginMm) : std::min(t.x, -kOwnHalfMarginMm);
        t = inside_field(away_from(t, Point{0.0, 0.0}, kCentreCircleMm));
      }
      if (kickoff_by_opponent_) {
        const PlayStep& first = config_.playbook.plays[play_].steps.front();
        if (first.ball_robot) {
          targets_[static_cast<std::size_t>(receiver_for(first))] =
              Point{-kBallAheadMm - 100.0, 0.0};
        }
      } else {
        targets_[static_cast<std::size_t>(2 * team_size_ - 1)] = Point{kBallAheadMm + 100.0, 0.0};
      }
      break;
    case Mode::stopped:
    case Mode::ball_placement:
      // Everybody away from the ball, keepers too; the placing robot goes to the ball instead,
      // on the side away from where it carries it.
      for (int i = 0; i < 2 * team_size_; ++i) {
        targets_[static_cast<std::size_t>(i)] = inside_field(
            away_from(targets_[static_cast<std::size_t>(i)], ball_.position, kStopDistanceMm));
      }
      if (mode_ == Mode::ball_placement && ball_.receiver >= 0) {
        // The others make way for the robot placing the ball: off its way to the ball and off
        // the ball's way to its spot (the rules: 0.5 m).
        // A robot standing in the way steps aside, on its own side.
        const Point placer = robot(ball_.receiver);
        const auto off_the_way = [&](Point p) {
          p = away_from_segment(p, placer, ball_.position, kStopDistanceMm);
          return inside_field(away_from_segment(p, ball_.position, placement_, kStopDistanceMm));
        };
        for (int i = 0; i < 2 * team_size_; ++i) {
          if (i == ball_.receiver) continue;
          const Point at = robot(i);
          const Point aside = off_the_way(at);
          targets_[static_cast<std::size_t>(i)] =
              aside == at ? off_the_way(targets_[static_cast<std::size_t>(i)]) : aside;
        }
        // Behind the ball as it carries it; once it is on its spot, where the robot takes the
        // free kick from (its team's goal side, the ball at its feet).
        const Point to_spot = minus(placement_, ball_.position);
        const double l = length(to_spot);
        if (l > 1.0) {
          placement_behind_ = Point{-to_spot.x / l * kBallAheadMm, -to_spot.y / l * kBallAheadMm};
        } else {
          placement_behind_ = Point{ours(ball_.receiver) ? kBallAheadMm : -kBallAheadMm, 0.0};
        }
        targets_[static_cast<std::size_t>(ball_.receiver)] =
            Point{ball_.position.x + placement_behind_.x, ball_.position.y + placement_behind_.y};
      }
      break;
    case Mode::halted:
    case Mode::lining_up:
      break;
  }
  // A robot sent to fetch a loose ball goes to it (in running play).
  const bool running = mode_ == Mode::opponent_play || mode_ == Mode::our_possession;
  if (running && ball_.receiver >= 0 && !ball_.rolling) {
    targets_[static_cast<std::size_t>(ball_.receiver)] = ball_.position;
  }
}

void MatchSimulation::move_ball(double dt_s, double now_s) {
  const double half_length = field_.length_mm / 2.0;
  const double half_width = field_.width_mm / 2.0;
  if (mode_ == Mode::ball_placement) {
    // Carried to the spot once the placing robot has it.
    if (ball_.receiver >= 0 &&
        length(minus(robots_.position(static_cast<std::size_t>(ball_.receiver)), ball_.position)) <
            2.0 * kTakeBallMm) {
      ball_.position = towards(ball_.position, placement_, kPlacementSpeedMmS * dt_s);
      if (ball_.position == placement_ && game_) game_->ball_placed(now_s);
    }
    return;
  }
  if (ball_.holder >= 0) {
    // At the holder's feet, on the side of the goal it attacks.
    const Point holder = robots_.position(static_cast<std::size_t>(ball_.holder));
    const double ahead = ours(ball_.holder) ? -kBallAheadMm : kBallAheadMm;
    ball_.position = Point{holder.x + ahead, holder.y};
    ball_.velocity = Point{0.0, 0.0};
    return;
  }
  if (ball_.shot) {
    ball_.position.x += ball_.velocity.x * dt_s;
    ball_.position.y += ball_.velocity.y * dt_s;
    if (ball_.position.x > half_length || std::abs(ball_.position.y) > half_width) {
      if (game_) {
        call_stoppage(now_s);
      } else {
        restart(now_s);
      }
    }
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

void MatchSimulation::call_stoppage(double now_s) {
  // The ball stops where it left the field.
  ball_.position = Point{std::clamp(ball_.position.x, -field_.length_mm / 2, field_.length_mm / 2),
                         std::clamp(ball_.position.y, -field_.width_mm / 2, field_.width_mm / 2)};
  ball_.velocity = Point{0.0, 0.0};
  ball_.shot = false;
  std::uniform_real_distribution<double> draw(0.0, 1.0);
  const std::optional<GameShape>& shape = game_->config().shape;
  const double kind = draw(random_);
  if (kind < (shape ? shape->shot_goal_share : kGoalShare)) {
    ++goals_;
    game_->stop_for_goal(config_.opponent_color, now_s);
    return;
  }
  if (shape && kind < shape->shot_goal_share + shape->shot_saved_share) {
    // Our keeper saves it and throws the ball to a team mate: play goes on.
    const Point keeper = robot_position(team_size_);
    ball_.position = inside_field(Point{keeper.x - kBallAheadMm, keeper.y});
    start_our_possession(now_s);
    ball_.rolling = true;
    return;
  }
  if (draw(random_) < kCornerShare) {
    // A corner (or another set piece): the play waits, and the ball is placed where its taker
    // starts.
    start_play(now_s, PlayRestart::free_kick);
    holding_play_ = true;
    taker_kicks_ = true;
    const PlayStep& first = config_.playbook.plays[play_].steps.front();
    Point spot = on_field(Point{0.9, ball_.position.y < 0 ? -0.9 : 0.9});
    if (first.ball_robot) {
      // The taker places the ball: it goes to fetch it, then carries it to where it starts.
      Point& taker = play_targets_[static_cast<std::size_t>(receiver_for(first))];
      spot = inside_field(Point{taker.x + kBallAheadMm, taker.y});
      taker = ball_.position;
    }
    game_->stop_for_ball_out(config_.opponent_color, now_s, normalise(spot, attacks_));
    return;
  }
  // A goal kick for us, from the side of our goal area where the ball went out.
  const Point spot{field_.length_mm / 2 - 500.0, ball_.position.y < 0 ? -1000.0 : 1000.0};
  game_->stop_for_ball_out(opposite(config_.opponent_color), now_s, normalise(spot, attacks_));
}

void MatchSimulation::call_foul(double now_s) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const bool opponents_kick = unit(random_) < 0.5;
  const double angle = unit(random_) * 2.0 * kPi;
  const double distance =
      kFoulPlacementMinMm + (kFoulPlacementMaxMm - kFoulPlacementMinMm) * unit(random_);
  const double half_length = field_.length_mm / 2.0 - kPlacementMarginMm;
  const double half_width = field_.width_mm / 2.0 - kPlacementMarginMm;
  const Point spot{
      std::clamp(ball_.position.x + distance * std::cos(angle), -half_length, half_length),
      std::clamp(ball_.position.y + distance * std::sin(angle), -half_width, half_width)};
  // Play stops where it is; nobody kicks until the restart.
  ball_.velocity = Point{0.0, 0.0};
  ball_.holder = -1;
  ball_.receiver = -1;
  ball_.rolling = false;
  ball_.shot = false;
  if (opponents_kick) {
    // A play from where the foul was, waiting (a playbook's free-kick plays are set pieces near
    // the goal, such as corners). The robot nearest to the ball places it and kicks.
    start_play(now_s, PlayRestart::any);
    holding_play_ = true;
    taker_kicks_ = false;
  }
  const TeamColor team = opponents_kick ? config_.opponent_color : opposite(config_.opponent_color);
  game_->stop_for_foul(team, now_s, normalise(spot, attacks_));
}

void MatchSimulation::start_our_possession(double now_s) {
  mode_ = Mode::our_possession;
  holding_play_ = false;
  kick_at_s_ = now_s;
  // Our robot nearest to the ball fetches it; the opponent falls back and presses.
  const int nearest = nearest_of(team_size_ + 1, 2 * team_size_, ball_.position,
                                 [this](int i) { return robot_position(i); });
  ball_.holder = -1;
  ball_.rolling = false;
  ball_.shot = false;
  ball_.receiver = nearest;
  std::uniform_real_distribution<double> lasts(kOurPossessionMinS, kOurPossessionMaxS);
  possession_ends_s_ = now_s + lasts(random_);
  play_ = -1;
  const std::vector<Point> shape = line_up(field_, team_size_);
  for (int id = 1; id < team_size_; ++id) {
    play_targets_[static_cast<std::size_t>(id)] = shape[static_cast<std::size_t>(id)];
  }
}

void MatchSimulation::follow_referee(const Referee& message, double now_s) {
  const bool new_command = message.command_counter() != command_counter_;
  const bool new_stage = static_cast<int>(message.stage()) != stage_;
  if (!new_command && !new_stage) return;
  command_counter_ = message.command_counter();
  stage_ = static_cast<int>(message.stage());
  if (game_->opponent_attacks() != attacks_) {
    // The teams changed ends: the same robots, seen from the other end. Nothing moves on the
    // wire; in normalised positions everything turns about the centre.
    attacks_ = game_->opponent_attacks();
    robots_.mirror();
    for (Point& p : play_targets_) p = Point{-p.x, -p.y};
    ball_ = Ball{};
  }
  if (!new_command) return;
  const auto state = game_state_of_command(message.command());
  if (!state) return;
  const bool team_command = message.command() >= Referee::PREPARE_KICKOFF_YELLOW;
  const bool for_opponent =
      team_command && team_of_command(message.command()) == config_.opponent_color;
  const auto freeze_ball = [&] {
    ball_.velocity = Point{0.0, 0.0};
    ball_.holder = -1;
    ball_.receiver = -1;
    ball_.rolling = false;
    ball_.shot = false;
  };
  const std::optional<GameShape>& game_shape = game_->config().shape;
  switch (*state) {
    case GameState::halt:
    case GameState::timeout:
      freeze_ball();
      mode_ = Mode::halted;
      return;
    case GameState::stop:
      freeze_ball();
      // Before a half's kick-off (after the break), the teams line up for it.
      mode_ = message.stage() == Referee::NORMAL_FIRST_HALF_PRE ||
                      message.stage() == Referee::NORMAL_SECOND_HALF_PRE
                  ? Mode::lining_up
                  : Mode::stopped;
      return;
    case GameState::penalty_preparation:
      freeze_ball();
      mode_ = Mode::stopped;
      return;
    case GameState::kickoff_preparation:
      ball_ = Ball{};
      mode_ = Mode::kickoff_preparation;
      kickoff_by_opponent_ = for_opponent;
      holding_play_ = true;
      taker_kicks_ = true;
      if (for_opponent) {
        start_play(now_s, PlayRestart::kickoff);
        ball_.receiver = -1;  // nobody touches the ball before NORMAL_START
      } else {
        play_ = -1;
        const std::vector<Point> shape = line_up(field_, team_size_);
        for (int id = 1; id < team_size_; ++id) {
          play_targets_[static_cast<std::size_t>(id)] = shape[static_cast<std::size_t>(id)];
        }
      }
      return;
    case GameState::ball_placement: {
      mode_ = Mode::ball_placement;
      freeze_ball();
      placement_ = message.has_designated_position()
                       ? normalise(Point{message.designated_position().x(),
                                         message.designated_position().y()},
                                   attacks_)
                       : ball_.position;
      // The placing team's robot nearest to the ball carries it (keepers stay home); for the
      // opponent's set play, the robot that will take the free kick.
      const int first = for_opponent ? 1 : team_size_ + 1;
      ball_.receiver = nearest_of(first, first + team_size_ - 1, ball_.position,
                                  [this](int i) { return robot_position(i); });
      if (for_opponent && holding_play_ && play_ >= 0 && taker_kicks_) {
        const PlayStep& step = config_.playbook.plays[play_].steps.front();
        if (step.ball_robot) ball_.receiver = receiver_for(step);
      }
      return;
    }
    case GameState::running:
    case GameState::free_kick: {
      // A placement cut short (the game controller waits 30 s at most): the free kick is taken
      // where the ball was to be placed, as a referee would put it there.
      if (mode_ == Mode::ball_placement) ball_.position = placement_;
      const bool ours_to_take = *state == GameState::free_kick
                                    ? !for_opponent
                                    : message.command() == Referee::NORMAL_START &&
                                          mode_ == Mode::kickoff_preparation &&
                                          !kickoff_by_opponent_;
      ball_.receiver = -1;
      // A shaped game's free kick is taken its kick delay after the command.
      const bool kick_after_delay = game_shape && *state == GameState::free_kick;
      const double kick_at_s = kick_after_delay ? now_s + game_shape->kick_delay_s : now_s;
      if (ours_to_take) {
        start_our_possession(now_s);
        kick_at_s_ = kick_at_s;
        return;
      }
      kick_at_s_ = kick_at_s;
      mode_ = Mode::opponent_play;
      if (play_ < 0) {
        start_play(now_s, PlayRestart::any);
      } else if (holding_play_) {
        // The restart's play goes: its first step was held until now. Unless its own taker
        // stands at the ball, the robot nearest to the ball (after a placement, the one that
        // placed it) takes the kick: a pass to the play's first receiver, which starts the play.
        const int kicker =
            nearest_of(1, team_size_, ball_.position, [this](int i) { return robot_position(i); });
        const PlayStep& first = config_.playbook.plays[play_].steps.front();
        if (!taker_kicks_ && first.ball_robot && receiver_for(first) != kicker) {
          ball_.receiver = kicker;
          step_ = -1;
          const double fetch_s =
              length(minus(robot_position(kicker), ball_.position)) / kStopSpeedMmS;
          step_ends_s_ = std::max(kick_at_s_, now_s + fetch_s);
        } else {
          aim_at_step();
          step_ends_s_ = kick_after_delay
                             ? kick_at_s_
                             : now_s + hold_scale_ * config_.playbook.plays[play_]
                                                         .steps[static_cast<std::size_t>(step_)]
                                                         .hold_s;
        }
      }
      holding_play_ = false;
      return;
    }
    case GameState::unknown:
      return;
  }
}

MatchFrame MatchSimulation::next() {
  MatchFrame frame;
  frame.index = frames_;
  const double dt_s = 1.0 / config_.frame_rate_hz;
  frame.t_capture = config_.start_time_s + static_cast<double>(frames_) * dt_s;
  frame.frame_number = frame_number_++;
  if (game_) {
    frame.referee = game_->message_at(frame.t_capture);
    follow_referee(*frame.referee, frame.t_capture);
  }
  if (frames_ > 0) {
    if (mode_ == Mode::opponent_play && !holding_play_) advance_play(frame.t_capture);
    if (mode_ == Mode::our_possession && frame.t_capture >= possession_ends_s_) {
      if (ball_.holder >= 0) {
        // The opponent wins the ball back where it is, and plays on.
        ball_.holder = -1;
        mode_ = Mode::opponent_play;
        start_play(frame.t_capture, PlayRestart::any);
      } else {
        possession_ends_s_ = frame.t_capture + 1.0;  // not ours yet
      }
    }
    update_targets(frame.t_capture);
    if (mode_ == Mode::halted) {
      robots_.halt(dt_s);
    } else {
      // While the game is stopped: 1.5 m/s at most, and 0.5 m from the ball but for the robot
      // placing it.
      const bool slow =
          mode_ == Mode::stopped || mode_ == Mode::ball_placement || mode_ == Mode::lining_up;
      std::optional<KeepOut> keep_out;
      if (slow) {
        keep_out = KeepOut{ball_.position, kKeepOutMm,
                           mode_ == Mode::ball_placement ? ball_.receiver : -1};
      }
      robots_.step(dt_s, targets_, slow ? kStopSpeedMmS : 0.0, keep_out);
    }
    move_ball(dt_s, frame.t_capture);
    const bool running = mode_ == Mode::opponent_play || mode_ == Mode::our_possession;
    if (game_ && running && game_->stoppage_due(frame.t_capture)) call_foul(frame.t_capture);
  }
  ++frames_;
  for (int id = 0; id < team_size_; ++id) {
    frame.opponent.push_back(robots_.position(static_cast<std::size_t>(id)));
    frame.ours.push_back(robots_.position(static_cast<std::size_t>(team_size_ + id)));
  }
  frame.ball = ball_.position;
  frame.opponent_attacks = attacks_;
  if (play_ >= 0) {
    frame.play = config_.playbook.plays[play_].name;
    frame.play_step = step_;
  }
  build_packets(frame);
  return frame;
}

void MatchSimulation::build_packets(MatchFrame& frame) {
  if (geometry_.due(frame.t_capture)) frame.packets.push_back(make_geometry_packet(field_));
  std::normal_distribution<double> jitter(0.0, config_.jitter_mm > 0 ? config_.jitter_mm : 1.0);
  const auto observe = [&](Point normalised) {
    Point feed = normalise(normalised, attacks_);
    if (config_.jitter_mm > 0) {
      feed.x += jitter(noise_random_);
      feed.y += jitter(noise_random_);
    }
    return feed;
  };
  std::vector<Point> opponent_feed;
  std::vector<Point> ours_feed;
  for (int id = 0; id < team_size_; ++id) {
    opponent_feed.push_back(observe(frame.opponent[static_cast<std::size_t>(id)]));
    ours_feed.push_back(observe(frame.ours[static_cast<std::size_t>(id)]));
  }
  SeenInstant instant;
  instant.frame_number = frame.frame_number;
  instant.t_capture = frame.t_capture;
  instant.opponent_color = config_.opponent_color;
  instant.opponent = opponent_feed;
  instant.ours = ours_feed;
  instant.ball = observe(frame.ball);
  // Each team faces the goal it attacks.
  instant.opponent_facing =
      attacks_ == AttackDirection::positive_x ? 0.0F : static_cast<float>(kPi);
  instant.our_facing = instant.opponent_facing == 0.0F ? static_cast<float>(kPi) : 0.0F;
  const CameraLayout layout{config_.cameras, field_, config_.camera_overlap_mm, config_.drop_rate};
  frame.dropped_packets += append_camera_packets(layout, instant, noise_random_, frame.packets);
}

}  // namespace ssl_formation::sim
