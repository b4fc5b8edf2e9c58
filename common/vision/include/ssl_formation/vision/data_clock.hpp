#pragma once
// The data clock (docs/models.md): places every detection frame on the sample instants of the
// data's own t_capture (instant k at anchor + k * step), decides when an instant is complete, and
// tells the current clock's frames from late, duplicate and another clock's frames (a restarted
// sender, a feed resuming after a gap, a second sender on the same group).
//
// Pure: no sockets, clocks or threads. FormationSampler drives it; tests drive it alone.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace ssl_formation {
inline namespace vision {

// The clock's settings, each rule stated here once. SamplerConfig inherits them, so programs and
// tests set them by these names on a SamplerConfig.
struct DataClockConfig {
  // The model's step: the time between the two states of a transition, and the time scale of
  // the windows below. Must be positive and finite.
  double step_s = 2.0;
  // Sample instants are interval_s() apart on t_capture; the instant numbered 0 is the first
  // frame's time (the anchor). 0 means one instant per step (the paper's sampling); a small
  // interval makes every frame time an instant of its own (rolling sampling).
  double instant_interval_s = 0.0;
  // A camera counts as live (an instant waits for it) if it sent a frame within
  // camera_live_window_s() = max(camera_timeout_s, 1.5 * step_s) of the newest frame: a camera of
  // a 2 s simulated feed is live, a dead one stops holding instants back after that. The first
  // instant also waits until a frame first_instant_wait_s() = min(camera_timeout_s, interval_s())
  // after the anchor, so that every camera has a chance to be discovered (otherwise the first
  // sample would hold only the first camera's robots).
  double camera_timeout_s = 1.0;
  // A frame more than clock_reset_window_s() from the clock's newest time (behind or ahead)
  // belongs to another clock: a restarted sender, a feed resuming after a gap, or a second
  // sender on the same group. 0 means two steps; network reordering is milliseconds, never that
  // much.
  double clock_reset_s = 0.0;
  // Frames of another clock are set aside. When they show this many distinct t_capture values
  // with no frame of the current clock between them, that clock takes over (a restart or a
  // resumed feed): the clock starts over, then the set-aside frames are used, so nothing is lost
  // but the transition across. One stray old or future frame never moves the clock.
  int clock_confirm_times = 3;
  std::size_t max_pending_frames = 256;  // the set-aside frames also take over at this many
  // Frames of two advancing clocks interleaving (a second sender, e.g. a replay beside a live
  // feed) are a clock conflict: instants are still completed (on the current clock only) but are
  // marked in conflict until the other clock has been silent for conflict_hold_s() of the current
  // clock's time. 0 means four steps.
  double clock_conflict_hold_s = 0.0;

  // The effective values of the rules above, defaults resolved.
  double interval_s() const { return instant_interval_s > 0.0 ? instant_interval_s : step_s; }
  double clock_reset_window_s() const { return clock_reset_s > 0.0 ? clock_reset_s : 2.0 * step_s; }
  double camera_live_window_s() const { return std::max(camera_timeout_s, 1.5 * step_s); }
  double first_instant_wait_s() const { return std::min(camera_timeout_s, interval_s()); }
  double conflict_hold_s() const {
    return clock_conflict_hold_s > 0.0 ? clock_conflict_hold_s : 4.0 * step_s;
  }
};

// One accepted robot of a frame: the clock carries it (set aside with its frame, handed back when
// the frame is used) and never reads it.
struct FrameDetection {
  std::uint32_t robot_id = 0;
  double x = 0.0;  // millimetres, feed coordinates
  double y = 0.0;
  float confidence = 0.0F;
};

// A detection frame as the clock sees it.
struct ClockFrame {
  std::uint32_t camera_id = 0;
  std::uint32_t frame_number = 0;
  double time_s = 0.0;  // t_capture, finite
};

// A sample instant handed on.
struct ClockInstant {
  std::int64_t k = 0;   // instant number on the current clock
  double time_s = 0.0;  // anchor + k * step
  // Handed on without every live camera's frame, because a frame of a later instant arrived
  // first (a dropped frame). Instant 0 is never reported forced.
  bool forced = false;
  bool in_conflict = false;  // a second clock is interleaving: count no transition
};

// Frames the clock did not use, and the start of a conflict: what the sampler counts.
enum class ClockEvent {
  frame_late,       // older than the last instant handed on: out of order, dropped
  frame_duplicate,  // same camera, frame number and t_capture as that camera's last frame
  frame_set_aside,  // another clock's: kept until that clock takes over or the current one goes on
  conflict,         // two advancing clocks interleave (once per episode)
};

enum class ClockRestart {
  take_over,         // the set-aside clock was confirmed; its frames are replayed next
  instant_overflow,  // an instant number beyond 1e12 steps from the anchor: anchored afresh
};

// What the clock tells its user, synchronously, from inside DataClock::place(). The listener may
// call DataClock::reset() from on_instant() (a sample handler starting a new stream); a take-over
// then goes on replaying its remaining frames into the new stream.
class DataClockListener {
 public:
  // A frame used on the current clock: its detections belong to the instants from its time on.
  virtual void on_frame(const ClockFrame& frame, const std::vector<FrameDetection>& detections) = 0;
  // An instant is complete: every live camera has a frame at or after it, or a later instant
  // forced it. Instants come in increasing k; numbers between them are skipped (a gap).
  virtual void on_instant(const ClockInstant& instant) = 0;
  // The clock started over by itself: forget the stream (no transition spans the restart).
  virtual void on_restart(ClockRestart why) = 0;
  virtual void on_event(ClockEvent event) = 0;

 protected:
  ~DataClockListener() = default;
};

class DataClock {
 public:
  // Throws std::invalid_argument for a step that is not positive and finite.
  explicit DataClock(const DataClockConfig& config);

  // Places one frame (finite t_capture) and reports to `listener` what follows from it: zero or
  // more instants, the frame used or refused, and after a take-over the set-aside frames used in
  // their order of arrival.
  //
  // The rules, in order:
  //  1. Far from the clock (beyond clock_reset_window_s() of its newest time): set aside.
  //  2. While frames are set aside, a frame near the other clock that is older than the last
  //     instant handed on is that clock's too (a restarted clock passes through the old one's
  //     times): set aside.
  //  3. Otherwise the current clock goes on and the set-aside frames are dropped; if the other
  //     clock had advanced (two distinct times) that is a conflict. It ends once the current
  //     clock is conflict_hold_s() past its newest time when the other was last seen.
  //  4. The first frame anchors the clock (instant 0 at its time).
  //  5. A repeat of a camera's last frame (number and time) is a duplicate. A frame beyond 1e12
  //     steps from the anchor anchors the clock afresh (instant_overflow). A frame older than the
  //     last instant handed on is late.
  //  6. A frame of a later instant first hands on the instant still open (forced).
  //  7. The frame is used; then the open instant is handed on if complete.
  // Set-aside frames of one other clock (each within clock_reset_window_s() of the one before)
  // take over when they show clock_confirm_times distinct times or number max_pending_frames.
  // The clock left behind then becomes the other clock (advancing if it had handed on two
  // instants), and a conflict going on goes on.
  void place(DataClockListener& listener, const ClockFrame& frame,
             const std::vector<FrameDetection>& detections);

  // Forgets the stream: the next frame anchors a new clock. Reports nothing.
  void reset();

  const DataClockConfig& config() const { return config_; }
  bool anchored() const { return anchored_; }
  double instant_s(std::int64_t k) const {
    return anchor_s_ + static_cast<double>(k) * config_.interval_s();
  }
  double newest_s() const { return newest_s_; }                         // of the frames used
  std::optional<std::int64_t> open_instant() const { return open_k_; }  // waiting for cameras
  std::int64_t next_instant() const { return next_k_; }  // the earliest not yet handed on
  bool in_conflict() const { return conflict_; }
  std::size_t frames_set_aside() const { return pending_.size(); }

 private:
  // A camera's frames on the current clock.
  struct CameraClock {
    std::uint32_t camera_id = 0;
    double newest_s = 0.0;
    double last_s = 0.0;  // of its last frame, with:
    std::uint32_t last_frame_number = 0;
  };
  // A frame of another clock, set aside until that clock takes over or the current one goes on.
  struct PendingFrame {
    ClockFrame frame;
    std::vector<FrameDetection> detections;
  };
  // The most recent other clock seen: tells a second interleaving sender from a stray frame.
  struct OtherClock {
    bool active = false;
    bool advancing = false;  // seen at two or more distinct times
    double newest_s = 0.0;
    double seen_at_s = 0.0;  // the current clock's newest time when last seen
  };

  void set_aside(DataClockListener& listener, const ClockFrame& frame,
                 const std::vector<FrameDetection>& detections);
  void take_over(DataClockListener& listener);
  bool instant_complete(std::int64_t k) const;
  void hand_on(DataClockListener& listener, std::int64_t k, bool forced);
  CameraClock* find_camera(std::uint32_t camera_id);

  DataClockConfig config_;
  std::vector<CameraClock> cameras_;
  std::vector<PendingFrame> pending_;
  std::vector<double> times_scratch_;  // distinct set-aside times are counted in this
  OtherClock other_;
  bool conflict_ = false;

  bool anchored_ = false;
  double anchor_s_ = 0.0;
  double newest_s_ = 0.0;
  std::int64_t next_k_ = 0;
  std::optional<std::int64_t> open_k_;
};

}  // namespace vision
}  // namespace ssl_formation
