#include "ssl_formation/evaluate/log_streams.hpp"

#include <spdlog/spdlog.h>

#include <optional>
#include <stdexcept>

#include "ssl_formation/files/log_events.hpp"

namespace ssl_formation::evaluate {

struct LogFile::State {
  std::string path;
  std::optional<std::uint64_t> vision_events;
  bool warned = false;
};

namespace {

LogReader open(const std::string& path) {
  Result<LogReader> reader = LogReader::open(path);
  if (!reader) throw std::runtime_error(reader.error().message);
  return std::move(*reader);
}

}  // namespace

LogFile::LogFile(const std::string& path) : state_(std::make_shared<State>()) {
  state_->path = path;
  (void)open(path);  // a file that is not a log stops the run before any work
}

evaluation::EventStream LogFile::stream(VisionRange range) const {
  return [state = state_, range](MatchEventSink& sink) {
    LogReader reader = open(state->path);
    LogEvents events(reader);
    MatchEvent event;
    std::uint64_t vision_before = 0;
    while (vision_before < range.end && events.next(event)) {
      if (vision_before >= range.first) sink.on_event(event);
      if (event.kind == MatchEventKind::vision) ++vision_before;
    }
    if (vision_before >= range.end || reader.ending() == LogReader::Ending::none) return;
    // Damaged or cut off: what came before it is used, as when the whole file was read first.
    if (events.vision_events() == 0) throw std::runtime_error(reader.error());
    if (!state->warned) {
      spdlog::warn("{}; using the {} vision packets before it", reader.error(),
                   events.vision_events());
      state->warned = true;
    }
  };
}

std::uint64_t LogFile::vision_events() const {
  if (!state_->vision_events) {
    struct Count final : MatchEventSink {
      std::uint64_t vision = 0;
      void on_event(const MatchEvent& event) override {
        if (event.kind == MatchEventKind::vision) ++vision;
      }
      void start_new_stream() override {}
    } count;
    stream()(count);
    state_->vision_events = count.vision;
  }
  return *state_->vision_events;
}

}  // namespace ssl_formation::evaluate
