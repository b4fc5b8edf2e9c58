#pragma once
// The front end every consumer of a match shares: the event stream in (match/match_event.hpp),
// the vision source chosen (raw, or a tracker's frames), the opponent followed by the referee,
// the ball followed, the formations sampled on the data clock, and each sample handed on with
// what is known of the game then (models/model.hpp's MatchMoment). Training, PredictionPipeline and
// the evaluation all run exactly this, fed by sockets, log files, a match in memory or a
// simulation.

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string_view>
#include <vector>

#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/match/match.hpp"
#include "ssl_formation/match/match_event.hpp"
#include "ssl_formation/match/tracked_vision.hpp"
#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/vision/ball_tracker.hpp"
#include "ssl_formation/vision/sampler.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {
inline namespace pipeline {

struct FrontEndConfig {
  SamplerConfig sampler;
  // Who the opponent is, with the referee filling in what the options leave open; none: the
  // sampler's colour and side, fixed as if given by option (the referee changes neither).
  std::optional<OpponentChoice> opponent;
  // --vision-source tracked: a tracker's frames stand in for the raw vision, whose geometry still
  // gives the field size (the tracker's frames have none). Never both: they are two clocks.
  bool tracked_vision = false;
  // Learning in running play keeps the game's states apart: no transition spans a new command,
  // and MatchMoment::learn_from_s is the first sample under the current one.
  bool keep_commands_apart = false;
  // How the ball is followed from the raw vision (with tracked vision the tracker's ball is
  // taken as it is); a sample's ball is none when it was not seen within ball.forget_after_s.
  BallTrackerSettings ball;
};

class MatchFrontEnd final : public MatchEventSink {
 public:
  struct Handlers {
    // Every sample, with what is known of the game then.
    std::function<void(const MatchMoment&)> on_sample;
    // What was followed of the match no longer holds: a new stream began, or the opponent changed
    // colour (its robots share the ids of the old one's).
    std::function<void()> on_forget;
  };

  // Throws std::invalid_argument for a bad sampler configuration or ball settings.
  MatchFrontEnd(FrontEndConfig config, Handlers handlers);
  // The sampler's handler points at this object.
  MatchFrontEnd(const MatchFrontEnd&) = delete;
  MatchFrontEnd& operator=(const MatchFrontEnd&) = delete;

  void on_event(const MatchEvent& event) override { handle(event); }
  // A new stream (another log file): its first formation follows nothing, its referee and tracker
  // are heard anew.
  void start_new_stream() override;
  // on_event(), returning what a referee message changed (nothing for the others).
  RefereeChange handle(const MatchEvent& event);

  // Shortcuts for code that holds the parts (tests, benchmarks): a raw vision frame or packet
  // received at its own t_capture, a referee message received at `receive_s`.
  void add(const VisionFrame& frame);
  void add(const SSL_WrapperPacket& packet);
  RefereeChange add_referee(std::string_view payload, double receive_s);

  // Hands every sample and forget to `handlers` too, after the ones it was made with: consumers
  // that sample alike (the evaluation's methods) share one front end, so that each message is
  // read once rather than once per consumer. Whoever joins must outlive the front end's use.
  void join(Handlers handlers) { joined_.push_back(std::move(handlers)); }

  const FrontEndConfig& config() const { return config_; }
  const FormationSampler& sampler() const { return sampler_; }
  const MatchFollower& match() const { return match_; }
  const TrackedVision& tracked_vision() const { return tracked_; }
  // The ball as followed so far, in feed coordinates (raw vision's or the tracker's).
  const BallTracker& ball() const { return ball_; }
  // The data time of the newest detection frame (raw or tracked) of this stream; none yet.
  std::optional<double> last_frame_time_s() const { return last_frame_time_s_; }
  // The phase of the game at that frame for the opponent followed (running before any frame). A
  // command heard since takes effect with the next sample, as it does for the samples.
  GamePhase phase_now() const {
    return last_frame_time_s_ ? phases_.phase(*last_frame_time_s_, match_.opponent().color)
                              : GamePhase::running;
  }
  // The side the opponent attacks now: the sampler's (inferred, or as the options and referee
  // say).
  AttackDirection attacks() const {
    return sampler_.attacks().value_or(sampler_.config().opponent_attacks);
  }
  // How far apart the feed's detection frames lately came on the data clock: the smallest of the
  // last three gaps between frames of different instants (0 before three), so that one pause in
  // a camera-rate feed does not count.
  double recent_frame_gap_s() const;

 private:
  void add_vision(const VisionFrame& frame);
  void on_sample(const FormationSample& sample);
  // Hands the match's opponent to the sampler; another colour forgets what was followed.
  void follow_opponent();
  void note_frame_time(double t_capture);
  void forget();

  FrontEndConfig config_;
  Handlers handlers_;
  std::vector<Handlers> joined_;
  FormationSampler sampler_;
  MatchFollower match_;
  TrackedVision tracked_;
  BallTracker ball_;
  GamePhaseTracker phases_;
  // The commands since the last sample, in effect from the next one, in order.
  std::vector<int> pending_commands_;
  VisionFrame scratch_;  // a tracker's frame, or the raw feed's geometry alone
  // The current command's first sample time; +infinity from a new command until its first
  // sample; -infinity when commands are not kept apart (or none came in this stream).
  double learn_from_s_ = -std::numeric_limits<double>::infinity();
  // The feed's pace (recent_frame_gap_s).
  std::optional<double> last_frame_time_s_;
  std::array<double, 3> frame_gaps_s_{};
  std::size_t frame_gaps_seen_ = 0;
};

}  // namespace pipeline
}  // namespace ssl_formation
