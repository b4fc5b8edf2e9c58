#pragma once
// Every program's log lines pass here (init_logging installs it), so that bad input from a
// shared tournament network cannot flood a log: a warning that repeats is written in full the
// first few times in a period, then counted, and one summary line a period says how many
// were left out. Lines are cut at a length no real line reaches. libprotobuf's own messages
// ("Can't parse message of type ...") are routed through the same limit.
//
// What counts as "the same warning" is its text with every run of digits read as one number and
// everything from the first quote on left out: "referee: 3 datagrams that are not referee
// messages (12 in all)" and "... 1 datagrams ... (13 in all)" are one kind, and so are two
// "opponent: 'A'" and "opponent: 'B'" lines, whatever the quoted name.

#include <spdlog/sinks/base_sink.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "ssl_formation/app/clock.hpp"

namespace ssl_formation::app {

struct LogLimitSettings {
  std::size_t burst = 5;              // lines of one kind written in full per period
  double period_s = 60.0;             // of the steady clock
  std::size_t max_line_chars = 1000;  // a longer line is cut, and says by how much
  std::size_t max_kinds = 512;        // kinds followed at once; the rest share one
  bool valid() const;
};

// The kind of a log line: see the header's comment. At most 120 characters.
std::string repeat_kind(std::string_view message);

// `text` cut to `max_chars` bytes (at a UTF-8 character's start), ending "… (N more
// characters)" when it was cut; as it is otherwise.
std::string cap_line(std::string_view text, std::size_t max_chars);

// The limit itself, time handed in: whether each line is written, and the summaries due.
class RepeatLimiter {
 public:
  explicit RepeatLimiter(LogLimitSettings settings = {});

  // Whether a line of `kind` at `now_s` is written (false: counted and left out).
  bool admit(const std::string& kind, double now_s);

  struct Summary {
    std::string kind;
    std::uint64_t left_out = 0;
    double period_s = 0.0;
  };
  // The kinds whose period ended by `now_s` with lines left out: each once, its count reset.
  std::vector<Summary> due(double now_s);
  // Every kind with lines left out, whether its period ended or not (at exit); counts reset.
  std::vector<Summary> pending(double now_s);

  std::uint64_t left_out_total() const { return left_out_total_; }
  const LogLimitSettings& settings() const { return settings_; }

 private:
  struct Window {
    double start_s = 0.0;
    std::size_t written = 0;
    std::uint64_t left_out = 0;
  };
  LogLimitSettings settings_;
  std::map<std::string, Window, std::less<>> windows_;
  std::uint64_t left_out_total_ = 0;
};

// A spdlog sink that applies a RepeatLimiter to warnings (and caps every line's length) before
// handing lines to `target`, which formats them. A summary is written as a warning with the
// first line of any kind after its period ended (the daemons' periodic status lines bring it even
// when the flood stopped), and at exit for what is still left out.
class LimitedSink : public spdlog::sinks::base_sink<std::mutex> {
 public:
  // Periods are timed on `clock` (the process's steady clock when none is given).
  LimitedSink(spdlog::sink_ptr target, LogLimitSettings settings = {},
              std::shared_ptr<const Clock> clock = nullptr);
  ~LimitedSink() override;
  LimitedSink(const LimitedSink&) = delete;
  LimitedSink& operator=(const LimitedSink&) = delete;
  std::uint64_t left_out_total();

 protected:
  void sink_it_(const spdlog::details::log_msg& message) override;
  void flush_() override;
  void set_pattern_(const std::string& pattern) override;
  void set_formatter_(std::unique_ptr<spdlog::formatter> formatter) override;

 private:
  void write_due(double now_s);
  void write_summaries(const std::vector<RepeatLimiter::Summary>& summaries);
  void forward(const spdlog::details::log_msg& message, std::string_view text);

  spdlog::sink_ptr target_;
  std::shared_ptr<const Clock> clock_;
  RepeatLimiter limiter_;
  std::string logger_name_;  // of the last line, for summaries
};

// Routes libprotobuf's log messages into spdlog's default logger (and so through the limit).
void route_protobuf_log();

}  // namespace ssl_formation::app
