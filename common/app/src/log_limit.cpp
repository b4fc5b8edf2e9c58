#include "ssl_formation/app/log_limit.hpp"

#include <google/protobuf/stubs/common.h>
#if GOOGLE_PROTOBUF_VERSION < 4022000
#include <google/protobuf/stubs/logging.h>
#endif
#include <spdlog/spdlog.h>

#include <cctype>
#include <cmath>
#include <stdexcept>

namespace ssl_formation::app {

namespace {

constexpr std::size_t max_kind_chars = 120;
constexpr std::string_view shared_kind = "(other kinds)";

}  // namespace

bool LogLimitSettings::valid() const {
  return burst >= 1 && std::isfinite(period_s) && period_s > 0.0 && max_line_chars >= 80 &&
         max_kinds >= 1;
}

std::string repeat_kind(std::string_view message) {
  std::string kind;
  kind.reserve(std::min(message.size(), max_kind_chars));
  bool in_number = false;
  for (const char c : message) {
    if (c == '\'' || c == '"') break;
    if (std::isdigit(static_cast<unsigned char>(c))) {
      if (!in_number) kind += '#';
      in_number = true;
      continue;
    }
    in_number = false;
    kind += c;
    if (kind.size() >= max_kind_chars) break;
  }
  return kind;
}

std::string cap_line(std::string_view text, std::size_t max_chars) {
  if (text.size() <= max_chars) return std::string(text);
  constexpr std::size_t room = 40;  // for the note saying how much was cut
  std::size_t keep = max_chars > room ? max_chars - room : 0;
  // Not in the middle of a UTF-8 character: back up over continuation bytes.
  while (keep > 0 && (static_cast<unsigned char>(text[keep]) & 0xC0) == 0x80) --keep;
  std::string out(text.substr(0, keep));
  out += "… (" + std::to_string(text.size() - keep) + " more characters)";
  return out;
}

RepeatLimiter::RepeatLimiter(LogLimitSettings settings) : settings_(settings) {
  if (!settings_.valid()) throw std::invalid_argument("log limit settings out of range");
}

bool RepeatLimiter::admit(const std::string& kind, double now_s) {
  auto it = windows_.find(kind);
  if (it == windows_.end()) {
    // Beyond max_kinds, new kinds share one window: memory stays bounded whatever comes in.
    const std::string& key =
        windows_.size() < settings_.max_kinds ? kind : std::string(shared_kind);
    it = windows_.try_emplace(key, Window{now_s, 0, 0}).first;
  }
  Window& w = it->second;
  if (now_s - w.start_s >= settings_.period_s && w.left_out == 0) w = Window{now_s, 0, 0};
  if (w.written < settings_.burst) {
    ++w.written;
    return true;
  }
  ++w.left_out;
  ++left_out_total_;
  return false;
}

std::vector<RepeatLimiter::Summary> RepeatLimiter::pending(double now_s) {
  std::vector<Summary> out;
  for (auto& [kind, w] : windows_) {
    if (w.left_out == 0) continue;
    out.push_back(Summary{kind, w.left_out, now_s - w.start_s});
    w.left_out = 0;
  }
  return out;
}

std::vector<RepeatLimiter::Summary> RepeatLimiter::due(double now_s) {
  std::vector<Summary> out;
  for (auto it = windows_.begin(); it != windows_.end();) {
    Window& w = it->second;
    if (now_s - w.start_s < settings_.period_s) {
      ++it;
      continue;
    }
    if (w.left_out > 0) {
      out.push_back(Summary{it->first, w.left_out, now_s - w.start_s});
      // The next period starts now, and its lines are written in full again.
      w = Window{now_s, 0, 0};
      ++it;
    } else {
      it = windows_.erase(it);  // quiet for a whole period: forgotten
    }
  }
  return out;
}

LimitedSink::LimitedSink(spdlog::sink_ptr target, LogLimitSettings settings,
                         std::shared_ptr<const Clock> clock)
    : target_(std::move(target)),
      clock_(clock ? std::move(clock) : std::make_shared<const SystemClock>()),
      limiter_(settings) {}

void LimitedSink::forward(const spdlog::details::log_msg& message, std::string_view text) {
  spdlog::details::log_msg copy = message;
  copy.payload = spdlog::string_view_t(text.data(), text.size());
  target_->log(copy);
}

LimitedSink::~LimitedSink() {
  // What was left out in the last period is said too, not lost with the program.
  try {
    write_summaries(limiter_.pending(clock_->steady_s()));
    target_->flush();
  } catch (...) {  // NOLINT(bugprone-empty-catch): nothing left to tell it to at exit
  }
}

void LimitedSink::write_due(double now_s) { write_summaries(limiter_.due(now_s)); }

void LimitedSink::write_summaries(const std::vector<RepeatLimiter::Summary>& summaries) {
  for (const RepeatLimiter::Summary& s : summaries) {
    const std::string text = fmt::format("{} more lines like '{}…' left out in the last {:.0f} s",
                                         s.left_out, s.kind, s.period_s);
    spdlog::details::log_msg summary(spdlog::string_view_t(logger_name_), spdlog::level::warn,
                                     spdlog::string_view_t(text));
    target_->log(summary);
  }
}

void LimitedSink::sink_it_(const spdlog::details::log_msg& message) {
  const double now = clock_->steady_s();
  logger_name_.assign(message.logger_name.data(), message.logger_name.size());
  write_due(now);
  const std::string_view payload(message.payload.data(), message.payload.size());
  // Warnings only: they are what bad input from the network produces; an error is rare and
  // each one matters (a batch tool's unreadable log file).
  if (message.level == spdlog::level::warn && !limiter_.admit(repeat_kind(payload), now)) {
    return;
  }
  const std::size_t max_chars = limiter_.settings().max_line_chars;
  if (payload.size() > max_chars) {
    forward(message, cap_line(payload, max_chars));
  } else {
    target_->log(message);
  }
}

void LimitedSink::flush_() { target_->flush(); }

void LimitedSink::set_pattern_(const std::string& pattern) { target_->set_pattern(pattern); }

void LimitedSink::set_formatter_(std::unique_ptr<spdlog::formatter> formatter) {
  target_->set_formatter(std::move(formatter));
}

std::uint64_t LimitedSink::left_out_total() {
  std::lock_guard<std::mutex> lock(mutex_);
  return limiter_.left_out_total();
}

#if GOOGLE_PROTOBUF_VERSION < 4022000
namespace {

void protobuf_to_spdlog(google::protobuf::LogLevel level, const char* /*filename*/, int /*line*/,
                        const std::string& message) {
  // libprotobuf says "Can't parse message of type ..." for every bad datagram the programs
  // already count: a warning of our own, under the same limit as the rest.
  switch (level) {
    case google::protobuf::LOGLEVEL_INFO:
      spdlog::debug("protobuf: {}", message);
      break;
    case google::protobuf::LOGLEVEL_WARNING:
    case google::protobuf::LOGLEVEL_ERROR:
      spdlog::warn("protobuf: {}", message);
      break;
    case google::protobuf::LOGLEVEL_FATAL:
      spdlog::error("protobuf: {}", message);
      break;
  }
}

}  // namespace

void route_protobuf_log() { google::protobuf::SetLogHandler(&protobuf_to_spdlog); }
#else
// Protobuf 22 and later log through Abseil, whose sink this build does not install.
void route_protobuf_log() {}
#endif
}  // namespace ssl_formation::app
