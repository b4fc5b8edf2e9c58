#pragma once
// Tracked vision (TrackerWrapperPacket) as what sampling reads: the frames of one
// tracker, followed by its uuid as the game controller does (the first heard becomes the one
// followed; one silent for source_timeout_s gives way to the next heard), turned into
// VisionFrames in millimetres with camera 0, so that sampling and everything after it run as on
// raw vision. Pure: the daemons feed it datagrams, offline tools a log's type-5 payloads, each
// with its receive time.
//
// Only the robots' positions are taken. Their velocities are left to the model's own robot
// tracker, which also serves raw vision, so that a table means the same whichever source trained
// it. The ball is taken whole (position and velocity): the tracker sees kicks and bounces that a
// few frames of positions would only show late.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "ssl_formation/vision/ball_tracker.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_vision_wrapper_tracked.pb.h"

namespace ssl_formation {
inline namespace match {

struct TrackerCounters {
  std::uint64_t packets = 0;
  std::uint64_t undecodable = 0;          // not a TrackerWrapperPacket
  std::uint64_t without_frame = 0;        // from the followed tracker, but no tracked_frame
  std::uint64_t other_source = 0;         // from another tracker while one is followed
  std::uint64_t source_switches = 0;      // the followed one fell silent, another took over
  std::uint64_t robots_without_team = 0;  // robots with no id or no team colour: left out
  std::uint64_t frames = 0;               // handed on
};

class TrackedVision {
 public:
  static constexpr double source_timeout_s = 1.0;

  // A tracker's datagram received at `receive_s` (any clock that increases). True when it is a
  // frame of the followed tracker: then `frame` holds its detection and ball() its ball. Bad
  // input is counted.
  bool add(std::string_view payload, double receive_s, VisionFrame& frame);
  // The ball of the last frame add() handed on (tracked_ball()); none if it had none.
  const std::optional<BallState>& ball() const { return ball_; }

  // The tracker followed: its uuid and its source_name; empty before the first.
  const std::string& source_uuid() const { return uuid_; }
  const std::string& source_name() const { return name_; }
  const TrackerCounters& counters() const { return counters_; }
  // Forgets the tracker followed (a new log file): the next one heard is followed.
  void reset() {
    uuid_.clear();
    name_.clear();
    last_s_ = 0.0;
    ball_.reset();
  }

 private:
  TrackerWrapperPacket packet_;  // reused
  std::string uuid_;
  std::string name_;
  double last_s_ = 0.0;
  std::optional<BallState> ball_;
  TrackerCounters counters_;
};

// Fills `frame` with `tracked`'s robots and balls in millimetres (camera 0, t_capture its
// timestamp, visibility as confidence, 1 when not given), leaving out robots without an id or a
// team colour (counted in `without_team`).
void to_vision_frame(const TrackedFrame& tracked, VisionFrame& frame, std::uint64_t& without_team);

// The frame's ball as the tracker estimates it, in feed coordinates: the most visible one (the
// first of equals) with a finite position, in millimetres, its velocity in millimetres per second
// (zero when not given or not finite), at the frame's timestamp. None if the frame has no such
// ball. The height and the vertical velocity of a chipped ball are left out.
std::optional<BallState> tracked_ball(const TrackedFrame& tracked);

}  // namespace match
}  // namespace ssl_formation
