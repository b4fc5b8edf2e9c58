#include "ssl_formation/producer/replay_clock.hpp"

#include <cmath>

#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::producer {

namespace {
// In microseconds this is more than 3,000 years of Unix time; in nanoseconds it is 1973.
constexpr std::int64_t kSurelyNanoseconds = 100'000'000'000'000'000;  // 1e17
constexpr double kMicrosecondRatioLow = 1e5;
const double kMicrosecondRatioHigh = std::pow(10.0, 7.5);  // halfway to 1e9 on a log scale
}  // namespace

const char* to_string(ReplayClock clock) {
  switch (clock) {
    case ReplayClock::receive_ns:
      return "receive times in nanoseconds";
    case ReplayClock::receive_us:
      return "receive times in microseconds";
    case ReplayClock::t_capture:
      return "the frames' t_capture";
  }
  return "?";
}

ClockChoice choose_replay_clock(std::span<const ClockSample> first_packets) {
  ClockChoice choice;
  if (first_packets.empty()) {
    choice.reason = "no packets to look at";
    return choice;
  }
  bool all_zero = true;
  bool monotonic = true;
  for (std::size_t i = 0; i < first_packets.size(); ++i) {
    if (first_packets[i].receive_time != 0) all_zero = false;
    if (i > 0 && first_packets[i].receive_time < first_packets[i - 1].receive_time)
      monotonic = false;
  }
  const std::int64_t first = first_packets.front().receive_time;
  const std::int64_t last = first_packets.back().receive_time;
  if (all_zero || !monotonic || (first_packets.size() > 1 && first == last)) {
    choice.clock = ReplayClock::t_capture;
    choice.reason = all_zero     ? "every receive time is zero"
                    : !monotonic ? "the receive times go backwards"
                                 : "every receive time is the same";
    return choice;
  }

  // The spans between the first and the last packet that carry a detection frame.
  const ClockSample* first_frame = nullptr;
  const ClockSample* last_frame = nullptr;
  for (const ClockSample& sample : first_packets) {
    if (!sample.t_capture || !std::isfinite(*sample.t_capture)) continue;
    if (first_frame == nullptr) first_frame = &sample;
    last_frame = &sample;
  }
  if (first_frame != nullptr && last_frame != first_frame) {
    const double capture_span = *last_frame->t_capture - *first_frame->t_capture;
    const double receive_span = static_cast<double>(last_frame->receive_time) -
                                static_cast<double>(first_frame->receive_time);
    if (capture_span > 0.0 && receive_span > 0.0) choice.ratio = receive_span / capture_span;
  }

  if (first >= kSurelyNanoseconds) {
    choice.clock = ReplayClock::receive_ns;
    choice.reason = "the receive times are Unix time in nanoseconds";
  } else if (choice.ratio >= kMicrosecondRatioLow && choice.ratio < kMicrosecondRatioHigh) {
    choice.clock = ReplayClock::receive_us;
    choice.reason = "the receive times advance about 1e6 per second of t_capture";
  } else if (choice.ratio > 0.0) {
    choice.clock = ReplayClock::receive_ns;
    choice.reason = "the receive times advance about 1e9 per second of t_capture";
  } else {
    choice.clock = ReplayClock::receive_ns;
    choice.reason = "no t_capture span to compare with: the official unit";
  }
  return choice;
}

double ReplayTimeline::time_of(std::int64_t receive_time, const SSL_WrapperPacket& packet) {
  // The clock's value relative to the segment's origin, in seconds; nullopt when the packet has
  // no time of its own (geometry-only packets on the t_capture clock): it goes with the previous.
  std::optional<double> value;
  bool new_origin = !started_;
  if (clock_ == ReplayClock::t_capture) {
    if (!packet.has_detection() || !std::isfinite(packet.detection().t_capture())) return now_s_;
    const double t = packet.detection().t_capture();
    if (new_origin) origin_capture_ = t;
    value = t - origin_capture_;
  } else {
    if (new_origin) origin_ = receive_time;
    std::int64_t delta = 0;
    if (__builtin_sub_overflow(receive_time, origin_, &delta)) {
      new_origin = true;  // nonsense far away: take it as a restarted clock
      origin_ = receive_time;
      delta = 0;
    }
    value = static_cast<double>(delta) / (clock_ == ReplayClock::receive_ns ? 1e9 : 1e6);
  }
  if (!started_) {
    started_ = true;
    segment_start_s_ = 0.0;
    newest_s_ = *value;
    now_s_ = 0.0;
    return now_s_;
  }
  if (new_origin || *value < newest_s_ - reset_s_) {
    // The clock restarted: a new segment that goes on from the current time.
    if (clock_ == ReplayClock::t_capture) {
      origin_capture_ = packet.detection().t_capture();
    } else {
      origin_ = receive_time;
    }
    segment_start_s_ = now_s_;
    newest_s_ = 0.0;
    return now_s_;
  }
  if (*value > newest_s_) newest_s_ = *value;
  now_s_ = segment_start_s_ + newest_s_;
  return now_s_;
}

}  // namespace ssl_formation::producer
