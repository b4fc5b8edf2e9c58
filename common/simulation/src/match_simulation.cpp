#include "ssl_formation/simulation/match_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "match_rules.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::simulation {

using namespace detail;

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

}  // namespace ssl_formation::simulation
