#include "ssl_formation/pipeline/match_front_end.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ssl_formation {
inline namespace pipeline {

MatchFrontEnd::MatchFrontEnd(FrontEndConfig config, Handlers handlers)
    : config_(std::move(config)),
      handlers_(std::move(handlers)),
      sampler_(config_.sampler, [this](const FormationSample& sample) { on_sample(sample); }),
      match_(config_.opponent
                 ? *config_.opponent
                 : fixed_opponent(config_.sampler.opponent_color, config_.sampler.opponent_attacks,
                                  config_.sampler.infer_attacks)),
      ball_(config_.ball) {
  follow_opponent();
}

RefereeChange MatchFrontEnd::handle(const MatchEvent& event) {
  switch (event.kind) {
    case MatchEventKind::referee:
      return add_referee(event.payload, event.receive_s);
    case MatchEventKind::tracked_vision:
      // The tracker's frames stand in for the raw ones with --vision-source tracked.
      if (config_.tracked_vision && tracked_.add(event.payload, event.receive_s, scratch_)) {
        if (tracked_.ball()) ball_.set(*tracked_.ball());
        add_vision(scratch_);
      }
      return {};
    case MatchEventKind::vision:
      if (!event.frame) return {};
      if (!config_.tracked_vision) {
        // The ball first: the frame that completes a sample is in it, as its robots are. (A
        // sample a frame of a later instant hands on has that frame's ball, one frame newer
        // than its robots: the sampler says which frames it used only inside.)
        if (event.frame->has_detection) ball_.add(event.frame->detection);
        add_vision(*event.frame);
      } else if (event.frame->has_geometry) {
        // The raw vision's geometry alone: the field size the tracker's frames do not give.
        scratch_.has_detection = false;
        scratch_.has_geometry = true;
        scratch_.field_length = event.frame->field_length;
        scratch_.field_width = event.frame->field_width;
        add_vision(scratch_);
      }
      return {};
  }
  return {};
}

void MatchFrontEnd::add(const VisionFrame& frame) { handle(MatchEvent::vision(frame, 0.0)); }

void MatchFrontEnd::add(const SSL_WrapperPacket& packet) {
  VisionFrame frame;
  to_vision_frame(packet, frame);
  add(frame);
}

void MatchFrontEnd::add_vision(const VisionFrame& frame) {
  if (frame.has_detection) note_frame_time(frame.detection.t_capture);
  sampler_.add(frame);
}

RefereeChange MatchFrontEnd::add_referee(std::string_view payload, double receive_s) {
  const RefereeChange change = match_.add_referee(payload, receive_s);
  if (!change.any()) return change;
  follow_opponent();
  if (change.command) pending_commands_.push_back(match_.referee().view().command);
  if (change.command && config_.keep_commands_apart) {
    sampler_.start_new_segment();
    learn_from_s_ = std::numeric_limits<double>::infinity();
  }
  return change;
}

void MatchFrontEnd::start_new_stream() {
  sampler_.start_new_stream();
  match_.reset();
  tracked_.reset();
  ball_.reset();
  phases_.reset();
  pending_commands_.clear();
  forget();
  follow_opponent();
  learn_from_s_ = -std::numeric_limits<double>::infinity();
  last_frame_time_s_.reset();
  frame_gaps_seen_ = 0;
}

void MatchFrontEnd::follow_opponent() {
  const Opponent& opponent = match_.opponent();
  if (opponent.color != sampler_.config().opponent_color) forget();
  sampler_.set_opponent(opponent.color, opponent.attacks);
}

void MatchFrontEnd::forget() {
  if (handlers_.on_forget) handlers_.on_forget();
  for (const Handlers& joined : joined_) {
    if (joined.on_forget) joined.on_forget();
  }
}

void MatchFrontEnd::on_sample(const FormationSample& sample) {
  if (learn_from_s_ == std::numeric_limits<double>::infinity()) {
    learn_from_s_ = sample.formation.time_s;
  }
  const double t = sample.formation.time_s;
  for (const int command : pending_commands_) phases_.on_command(command, t);
  pending_commands_.clear();
  if (!handlers_.on_sample && joined_.empty()) return;
  // The ball and the placement's target, turned as the sample's robots were.
  const AttackDirection turned = sample.formation.opponent_attacks;
  const std::optional<BallState> ball = ball_.at(t);
  const RefereeView& referee = match_.referee().view();
  std::optional<Point> designated_position;
  if (referee.state == GameState::ball_placement && referee.designated_position) {
    designated_position = normalise(*referee.designated_position, turned);
  }
  const MatchMoment moment{
      sample,
      sampler_.codec(),
      sampler_.field(),
      attacks(),
      match_.game_state(),
      phases_.phase(t, match_.opponent().color),
      phases_.since_command_s(t),
      learn_from_s_,
      ball ? std::optional<Point>(normalise(ball->position, turned)) : std::nullopt,
      ball ? normalise(ball->velocity, turned) : Point{},
      designated_position};
  if (handlers_.on_sample) handlers_.on_sample(moment);
  for (const Handlers& joined : joined_) {
    if (joined.on_sample) joined.on_sample(moment);
  }
}

void MatchFrontEnd::note_frame_time(double t_capture) {
  if (!std::isfinite(t_capture)) return;
  if (last_frame_time_s_) {
    const double gap = t_capture - *last_frame_time_s_;
    // Cameras of one instant share their time, and a clock that went back is another stream.
    if (gap < 1e-4 && gap > -1.0) return;
    if (gap > 0.0) {
      frame_gaps_s_[frame_gaps_seen_ % frame_gaps_s_.size()] = gap;
      ++frame_gaps_seen_;
    } else {
      frame_gaps_seen_ = 0;
    }
  }
  last_frame_time_s_ = t_capture;
}

double MatchFrontEnd::recent_frame_gap_s() const {
  if (frame_gaps_seen_ < frame_gaps_s_.size()) return 0.0;
  return *std::min_element(frame_gaps_s_.begin(), frame_gaps_s_.end());
}

}  // namespace pipeline
}  // namespace ssl_formation
