#include "ssl_formation/files/log_events.hpp"

#include <string>

namespace ssl_formation {
inline namespace files {

bool LogEvents::next(MatchEvent& event) {
  LogReader::MatchInput kind{};
  std::string_view payload;
  std::int64_t receive_ns = 0;
  if (!reader_.next_match_input(kind, frame_, payload, &receive_ns)) return false;
  const double receive_s = static_cast<double>(receive_ns) * 1e-9;
  switch (kind) {
    case LogReader::MatchInput::vision:
      ++vision_events_;
      event = MatchEvent::vision(frame_, receive_s);
      break;
    case LogReader::MatchInput::referee:
      event = MatchEvent::referee(payload, receive_s);
      break;
    case LogReader::MatchInput::tracker:
      event = MatchEvent::tracked_vision(payload, receive_s);
      break;
  }
  return true;
}

std::uint64_t replay_log(LogReader& reader, MatchEventSink& sink,
                         const std::function<void(std::uint64_t)>& on_progress) {
  LogEvents events(reader);
  MatchEvent event;
  while (events.next(event)) {
    sink.on_event(event);
    if (on_progress && event.kind == MatchEventKind::vision &&
        (events.vision_events() & 4095) == 0) {
      on_progress(events.vision_events());
    }
  }
  if (on_progress) on_progress(events.vision_events());
  return events.vision_events();
}

Result<RecordedLog> read_recorded_log(const std::filesystem::path& path) {
  Result<LogReader> reader = LogReader::open(path);
  if (!reader) return Unexpected(reader.error());
  RecordedLog log;
  LogEvents events(*reader);
  MatchEvent event;
  while (events.next(event)) {
    switch (event.kind) {
      case MatchEventKind::vision:
        log.match.add_vision(*event.frame, event.receive_s);
        break;
      case MatchEventKind::referee:
        log.match.add_referee(std::string(event.payload), event.receive_s);
        break;
      case MatchEventKind::tracked_vision:
        log.match.add_tracked_vision(std::string(event.payload), event.receive_s);
        break;
    }
  }
  log.ending = reader->ending();
  log.counters = reader->counters();
  if (log.ending != LogReader::Ending::none) log.stopped_early = Error{reader->error()};
  return log;
}

}  // namespace files
}  // namespace ssl_formation
