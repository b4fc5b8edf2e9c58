#pragma once
// How a replay times a log's packets: which clock the file's timing comes from,
// and the replay timeline built on it. Pure: no sockets, files or wall clock.
//
// The official format stores receive times in nanoseconds, but older recorders wrote
// microseconds, and some tools write zeros. The detection frames' own t_capture tells the real
// spacing, so the unit is chosen by comparing the span of receive times with the span of
// t_capture over the first packets of the file.

#include <cstdint>
#include <optional>
#include <span>
#include <string>

class SSL_WrapperPacket;

namespace ssl_formation::producer {

enum class ReplayClock {
  receive_ns,  // the official unit
  receive_us,  // older recorders
  t_capture,   // receive times unusable (all zero, going backwards): the frames' own clock
};
const char* to_string(ReplayClock clock);

// What the choice looks at for one packet.
struct ClockSample {
  std::int64_t receive_time = 0;    // as stored, unit unknown
  std::optional<double> t_capture;  // seconds, if the packet has a detection frame
};

struct ClockChoice {
  ReplayClock clock = ReplayClock::receive_ns;
  std::string reason;  // one phrase for the log: why this clock
  // receive span / t_capture span over the samples (0 if it could not be measured).
  double ratio = 0.0;
};

// Chooses from the first packets of a file (a few hundred are plenty):
// - receive times all zero, equal, or going backwards: t_capture;
// - a first receive time of 1e17 or more: nanoseconds (in microseconds it would be more than
//   3,000 years after 1970, whereas nanoseconds of Unix time are about 1.7e18);
// - else the ratio of the spans: microseconds if it is within 1e5 to 10^7.5, nanoseconds
//   otherwise (the official unit, also when t_capture gives no span to compare with).
ClockChoice choose_replay_clock(std::span<const ClockSample> first_packets);

// Turns each packet's stored times into seconds since the first packet of a pass, on the chosen
// clock. The result never decreases: a packet a little behind the newest one (cameras'
// t_capture interleave) gets the newest time; a jump back of more than `reset_s` (a restarted
// clock) continues the timeline from where it was instead of sending the rest at once.
class ReplayTimeline {
 public:
  explicit ReplayTimeline(ReplayClock clock, double reset_s = 1.0)
      : clock_(clock), reset_s_(reset_s) {}

  double time_of(std::int64_t receive_time, const SSL_WrapperPacket& packet);
  void restart() {
    started_ = false;
    now_s_ = 0.0;
  }
  ReplayClock clock() const { return clock_; }

 private:
  ReplayClock clock_;
  double reset_s_;
  bool started_ = false;
  std::int64_t origin_ = 0;       // receive clocks: the first stored value of the segment
  double origin_capture_ = 0.0;   // t_capture clock: the first t_capture of the segment
  double segment_start_s_ = 0.0;  // timeline value where the segment began
  double newest_s_ = 0.0;         // newest clock value in the segment, relative to its origin
  double now_s_ = 0.0;
};

}  // namespace ssl_formation::producer
