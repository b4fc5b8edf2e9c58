#pragma once
// An official log file as the match's event stream (match/match_event.hpp): its vision (type 4,
// and type 2 where its detection frame is usable), referee (type 3) and tracked vision (type 5)
// messages in the file's order, each received at the log's own receive time.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>

#include "ssl_formation/base/result.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/match/match_event.hpp"

namespace ssl_formation {
inline namespace files {

class LogEvents {
 public:
  explicit LogEvents(LogReader& reader) : reader_(reader) {}
  // The next event; false at the end of the file or where it stops being readable (the reader
  // says which). The event is valid until the next call.
  bool next(MatchEvent& event);
  std::uint64_t vision_events() const { return vision_events_; }

 private:
  LogReader& reader_;
  VisionFrame frame_;  // reused: its vectors keep their capacity
  std::uint64_t vision_events_ = 0;
};

// Hands every event of `reader` to `sink` (no start_new_stream: the caller says where a stream
// begins), calling `on_progress` every 4096 vision events and at the end. Returns the vision
// events handed on.
std::uint64_t replay_log(LogReader& reader, MatchEventSink& sink,
                         const std::function<void(std::uint64_t vision_events)>& on_progress = {});

// A whole log in memory, for tools that go over it more than once (the evaluation).
struct RecordedLog {
  RecordedMatch match;
  // Set when the file stopped being readable before its end: everything before is kept.
  std::optional<Error> stopped_early;
  LogReader::Ending ending = LogReader::Ending::none;
  LogReadCounters counters;
};
// An error only when the file cannot be opened or has no valid header.
Result<RecordedLog> read_recorded_log(const std::filesystem::path& path);

}  // namespace files
}  // namespace ssl_formation
