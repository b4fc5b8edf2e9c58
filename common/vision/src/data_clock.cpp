#include "ssl_formation/vision/data_clock.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace ssl_formation {
inline namespace vision {

namespace {
constexpr double time_epsilon_s = 1e-9;
// Beyond this many steps from the anchor the clock is treated as restarted, which also keeps
// the instant number far from int64 overflow whatever t_capture a packet claims.
constexpr double max_instant_number = 1e12;
}  // namespace

DataClock::DataClock(const DataClockConfig& config) : config_(config) {
  if (!std::isfinite(config_.step_s) || config_.step_s <= 0.0) {
    throw std::invalid_argument("step must be a positive number of seconds");
  }
  if (!std::isfinite(config_.instant_interval_s) || config_.instant_interval_s < 0.0) {
    throw std::invalid_argument("the instant interval must be 0 (one a step) or positive seconds");
  }
  cameras_.reserve(8);
}

DataClock::CameraClock* DataClock::find_camera(std::uint32_t camera_id) {
  for (CameraClock& camera : cameras_) {
    if (camera.camera_id == camera_id) return &camera;
  }
  return nullptr;
}

void DataClock::place(DataClockListener& listener, const ClockFrame& frame,
                      const std::vector<FrameDetection>& detections) {
  const double t = frame.time_s;
  const double reset_window_s = config_.clock_reset_window_s();
  if (anchored_ && std::abs(t - newest_s_) > reset_window_s) {
    set_aside(listener, frame, detections);
    return;
  }
  if (!pending_.empty() && std::abs(t - other_.newest_s) <= reset_window_s && next_k_ > 0 &&
      t < instant_s(next_k_ - 1) - time_epsilon_s) {
    set_aside(listener, frame, detections);
    return;
  }
  if (!pending_.empty()) {
    // A stray old frame (or a duplicate of one) never advanced: no conflict.
    if (other_.advancing && !conflict_) {
      conflict_ = true;
      listener.on_event(ClockEvent::conflict);
    }
    pending_.clear();
  }
  if (!anchored_) {
    anchored_ = true;
    anchor_s_ = t;
    newest_s_ = t;
    next_k_ = 0;
  }
  if (other_.active && std::max(newest_s_, t) - other_.seen_at_s > config_.conflict_hold_s()) {
    other_ = OtherClock{};
    conflict_ = false;
  }

  if (const CameraClock* camera = find_camera(frame.camera_id);
      camera != nullptr && camera->last_s == t && camera->last_frame_number == frame.frame_number) {
    listener.on_event(ClockEvent::frame_duplicate);
    return;
  }

  double instant_number = std::floor((t - anchor_s_) / config_.interval_s() + time_epsilon_s);
  if (std::abs(instant_number) > max_instant_number) {
    reset();
    listener.on_restart(ClockRestart::instant_overflow);
    anchored_ = true;
    anchor_s_ = t;
    newest_s_ = t;
    instant_number = 0.0;
  }
  const auto k = static_cast<std::int64_t>(instant_number);

  if (k < next_k_) {
    // Between two instants (the normal case at 60 Hz), unless older than the last one handed on.
    if (next_k_ > 0 && t < instant_s(next_k_ - 1) - time_epsilon_s) {
      listener.on_event(ClockEvent::frame_late);
      return;
    }
  } else {
    // This frame reaches a new instant. If an earlier one is still waiting for a camera that
    // never delivered (a dropped frame), hand it on now, before the new data overwrites it.
    if (open_k_ && k > *open_k_) hand_on(listener, *open_k_, *open_k_ != 0);
    // (The listener may have reset the clock meanwhile: the frame is still used.)
    if (!open_k_ || k > *open_k_) open_k_ = k;
  }

  if (CameraClock* camera = find_camera(frame.camera_id)) {
    camera->newest_s = std::max(camera->newest_s, t);
    camera->last_s = t;
    camera->last_frame_number = frame.frame_number;
  } else {
    cameras_.push_back(CameraClock{frame.camera_id, t, t, frame.frame_number});
  }
  listener.on_frame(frame, detections);
  newest_s_ = std::max(newest_s_, t);
  if (open_k_ && instant_complete(*open_k_)) hand_on(listener, *open_k_, false);
}

void DataClock::set_aside(DataClockListener& listener, const ClockFrame& frame,
                          const std::vector<FrameDetection>& detections) {
  listener.on_event(ClockEvent::frame_set_aside);
  const double t = frame.time_s;
  const double reset_window_s = config_.clock_reset_window_s();
  if (!other_.active || std::abs(t - other_.newest_s) > reset_window_s) {
    // Not the other clock seen before: a new one, and what was set aside is not its.
    other_ = OtherClock{true, false, t, newest_s_};
    pending_.clear();
  } else {
    if (t > other_.newest_s + time_epsilon_s) other_.advancing = true;
    other_.newest_s = std::max(other_.newest_s, t);
    other_.seen_at_s = newest_s_;
  }
  if (!pending_.empty() && std::abs(t - pending_.back().frame.time_s) > reset_window_s) {
    pending_.clear();
  }
  pending_.push_back(PendingFrame{frame, detections});

  // Times within time_epsilon_s of the one before, in order, count as one.
  std::vector<double>& times = times_scratch_;
  times.clear();
  for (const PendingFrame& f : pending_) times.push_back(f.frame.time_s);
  std::sort(times.begin(), times.end());
  int distinct_times = 0;
  double last_s = std::nan("");
  for (const double time_s : times) {
    if (!(std::abs(time_s - last_s) <= time_epsilon_s)) ++distinct_times;
    last_s = time_s;
  }
  if (distinct_times >= config_.clock_confirm_times ||
      pending_.size() >= config_.max_pending_frames) {
    take_over(listener);
  }
}

// The set-aside frames' clock takes over: a new stream, then those frames in their order.
void DataClock::take_over(DataClockListener& listener) {
  std::vector<PendingFrame> frames = std::move(pending_);
  // The clock left behind becomes the other clock: if it comes back, that is a conflict.
  const OtherClock left{true, next_k_ > 1, newest_s_, frames.back().frame.time_s};
  const bool conflict = conflict_;
  reset();
  listener.on_restart(ClockRestart::take_over);
  other_ = left;
  conflict_ = conflict;
  for (const PendingFrame& f : frames) place(listener, f.frame, f.detections);
}

bool DataClock::instant_complete(std::int64_t k) const {
  const double sample_s = instant_s(k);
  if (k == 0 && newest_s_ < anchor_s_ + config_.first_instant_wait_s()) return false;
  const double live_window_s = config_.camera_live_window_s();
  for (const CameraClock& camera : cameras_) {
    if (camera.newest_s >= newest_s_ - live_window_s &&
        camera.newest_s < sample_s - time_epsilon_s) {
      return false;
    }
  }
  return true;
}

void DataClock::hand_on(DataClockListener& listener, std::int64_t k, bool forced) {
  next_k_ = k + 1;
  open_k_.reset();
  listener.on_instant(ClockInstant{k, instant_s(k), forced, conflict_});
}

void DataClock::reset() {
  // The anchor and newest time stay as they were until the next frame anchors the clock anew.
  anchored_ = false;
  open_k_.reset();
  next_k_ = 0;
  cameras_.clear();
  pending_.clear();
  other_ = OtherClock{};
  conflict_ = false;
}

}  // namespace vision
}  // namespace ssl_formation
