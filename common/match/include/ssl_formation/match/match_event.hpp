#pragma once
// One seam for everything a match sends: raw vision, tracked vision and the referee, as one
// stream of events in the order they came. The live sockets (net/live_match_events.hpp), a log
// file (files/log_events.hpp), a match kept in memory (RecordedMatch, below) and the simulations
// all produce it; the front end (pipeline/match_front_end.hpp) consumes it, for training,
// prediction and evaluation alike, so none of them wires its own receivers to its own copy of
// the front end.

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ssl_formation/vision/vision_frame.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {
inline namespace match {

enum class MatchEventKind : std::uint8_t {
  vision,          // an SSL_WrapperPacket (detection and/or geometry)
  tracked_vision,  // a tracker's TrackerWrapperPacket
  referee,         // a game controller's Referee message
};
std::string_view to_string(MatchEventKind kind);  // "vision", "tracked_vision", "referee"

struct MatchEvent {
  MatchEventKind kind = MatchEventKind::vision;
  // When it was received, in seconds on the receiver's clock: the daemon's steady clock live, the
  // log's receive time offline. The referee and tracker followers time their sources by it;
  // sampling uses the vision's own t_capture.
  double receive_s = 0.0;
  // vision: the packet, decoded (the receivers and the log reader decode straight from the bytes).
  const VisionFrame* frame = nullptr;
  // tracked vision and referee: the datagram or log message as it came.
  std::string_view payload;

  static MatchEvent vision(const VisionFrame& frame, double receive_s) {
    return {MatchEventKind::vision, receive_s, &frame, {}};
  }
  static MatchEvent tracked_vision(std::string_view payload, double receive_s) {
    return {MatchEventKind::tracked_vision, receive_s, nullptr, payload};
  }
  static MatchEvent referee(std::string_view payload, double receive_s) {
    return {MatchEventKind::referee, receive_s, nullptr, payload};
  }
};

// What consumes the stream.
class MatchEventSink {
 public:
  virtual ~MatchEventSink() = default;
  virtual void on_event(const MatchEvent& event) = 0;
  // What follows is another stream (another log file): nothing spans the two.
  virtual void start_new_stream() = 0;
};

// A match kept in memory as it came, replayed into any sink as often as needed: the evaluation
// trains, fits and tests on the same streams, and tests build streams by hand.
class RecordedMatch {
 public:
  void add_vision(const VisionFrame& frame, double receive_s);
  void add_vision(const SSL_WrapperPacket& packet, double receive_s);
  void add_tracked_vision(std::string payload, double receive_s);
  void add_referee(std::string payload, double receive_s);

  // Hands every event to `sink`, in order (no start_new_stream: the caller says where a stream
  // begins).
  void replay(MatchEventSink& sink) const;

  std::size_t size() const { return events_.size(); }
  bool empty() const { return events_.empty(); }
  std::size_t vision_events() const { return vision_events_; }
  bool has_referee() const { return referee_events_ > 0; }

  // The first `fraction` of the vision packets with what came before each of them, and the rest
  // (with the referee messages between the two parts, which the rest's state needs): a split of
  // one match in time.
  std::pair<RecordedMatch, RecordedMatch> split(double fraction) const;

 private:
  struct Event {
    MatchEventKind kind;
    double receive_s;
    VisionFrame frame;    // vision
    std::string payload;  // tracked vision and referee
  };
  void push(Event event);

  std::vector<Event> events_;
  std::size_t vision_events_ = 0;
  std::size_t referee_events_ = 0;
};

}  // namespace match
}  // namespace ssl_formation
