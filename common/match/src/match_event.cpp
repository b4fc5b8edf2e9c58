#include "ssl_formation/match/match_event.hpp"

#include <algorithm>

namespace ssl_formation {
inline namespace match {

std::string_view to_string(MatchEventKind kind) {
  switch (kind) {
    case MatchEventKind::vision:
      return "vision";
    case MatchEventKind::tracked_vision:
      return "tracked_vision";
    case MatchEventKind::referee:
      return "referee";
  }
  return "?";
}

void RecordedMatch::push(Event event) {
  if (event.kind == MatchEventKind::vision) ++vision_events_;
  if (event.kind == MatchEventKind::referee) ++referee_events_;
  events_.push_back(std::move(event));
}

void RecordedMatch::add_vision(const VisionFrame& frame, double receive_s) {
  push({MatchEventKind::vision, receive_s, frame, {}});
}

void RecordedMatch::add_vision(const SSL_WrapperPacket& packet, double receive_s) {
  Event event{MatchEventKind::vision, receive_s, {}, {}};
  to_vision_frame(packet, event.frame);
  push(std::move(event));
}

void RecordedMatch::add_tracked_vision(std::string payload, double receive_s) {
  push({MatchEventKind::tracked_vision, receive_s, {}, std::move(payload)});
}

void RecordedMatch::add_referee(std::string payload, double receive_s) {
  push({MatchEventKind::referee, receive_s, {}, std::move(payload)});
}

void RecordedMatch::replay(MatchEventSink& sink) const {
  for (const Event& event : events_) {
    sink.on_event(MatchEvent{event.kind, event.receive_s,
                             event.kind == MatchEventKind::vision ? &event.frame : nullptr,
                             event.payload});
  }
}

std::pair<RecordedMatch, RecordedMatch> RecordedMatch::split(double fraction) const {
  const auto head_vision = static_cast<std::size_t>(std::clamp(fraction, 0.0, 1.0) *
                                                    static_cast<double>(vision_events_));
  RecordedMatch head;
  RecordedMatch tail;
  std::size_t vision_seen = 0;
  for (const Event& event : events_) {
    const bool in_head = vision_seen < head_vision;
    if (event.kind == MatchEventKind::vision) ++vision_seen;
    (in_head ? head : tail).push(event);
  }
  return {std::move(head), std::move(tail)};
}

}  // namespace match
}  // namespace ssl_formation
