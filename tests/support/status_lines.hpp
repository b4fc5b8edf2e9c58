#pragma once
// The daemons' status lines as numbers. Every daemon and ssl-record log a line like
// "status: packets=12 formations=3 ... | problems: kernel_drops=2" every --status-interval, and a
// last one as they exit: key=value throughout, so tests wait on counters instead of on the
// wording of a log line, and read the final figures from the last line. A counter at zero is left
// off the line (app/status_line.hpp): Status::at reads a key that is not there as 0.

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <thread>

#include "child_process.hpp"

namespace ssl_formation::testing {

// The key=value pairs of a status line; at() gives 0 for a key the line leaves out.
class Status : public std::map<std::string, std::uint64_t> {
 public:
  std::uint64_t at(const std::string& key) const {
    const auto it = find(key);
    return it == end() ? 0 : it->second;
  }
};

// The key=value pairs (with whole-number values) of the last complete line of `text` that
// contains `marker`, and of the "<marker without its colon>, more:" lines right after it (what a
// program's last status line had no room for): a key is a run of [a-z_] right before '=', its
// value the digits right after ("fast_path=98.2%" gives 98, "attacks=+x" nothing). A line still
// being written is left out: its last number may be cut short.
inline Status last_status(const std::string& text, const std::string& marker = "status:") {
  Status out;
  const std::size_t end = text.rfind('\n');
  if (end == std::string::npos) return out;
  std::size_t at = text.rfind(marker, end);
  if (at == std::string::npos) return out;
  const std::string more = marker.substr(0, marker.size() - 1) + ", more:";
  const auto key_char = [](char c) { return (c >= 'a' && c <= 'z') || c == '_'; };
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  for (bool first = true; at != std::string::npos && at < end; first = false) {
    const std::size_t line_end = text.find('\n', at);
    const std::string line = text.substr(at, line_end - at);
    if (!first && line.find(more) == std::string::npos) break;
    std::size_t taken = 0;  // the end of the last pair read: keys start after it
    for (std::size_t equals = line.find('='); equals != std::string::npos;
         equals = line.find('=', equals + 1)) {
      std::size_t key = equals;
      while (key > taken && key_char(line[key - 1])) --key;
      std::size_t value_end = equals + 1;
      while (value_end < line.size() && digit(line[value_end])) ++value_end;
      if (key == equals || value_end == equals + 1) continue;
      out[line.substr(key, equals - key)] =
          std::stoull(line.substr(equals + 1, value_end - equals - 1));
      taken = value_end;
    }
    at = line_end + 1;
  }
  return out;
}

// Waits until `condition(last status line of the process's stderr)` holds; false on time-out, or
// if the process ended without its last line meeting it.
template <class Condition>
bool wait_for_status_where(ChildProcess& process, Condition condition,
                           std::chrono::milliseconds timeout,
                           const std::string& marker = "status:") {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition(last_status(process.stderr_text(), marker))) return true;
    if (!process.running()) return condition(last_status(process.stderr_text(), marker));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// Waits until the process's last status line has `key` >= `value`.
inline bool wait_for_status(ChildProcess& process, const std::string& key, std::uint64_t value,
                            std::chrono::milliseconds timeout) {
  return wait_for_status_where(
      process,
      [&](const Status& status) {
        const auto it = status.find(key);
        return it != status.end() && it->second >= value;
      },
      timeout);
}

// Every datagram that reached the process's socket: those it read plus those the kernel dropped
// for want of room (and counted, SO_RXQ_OVFL). 0 before the first status line.
inline std::uint64_t received_or_dropped(const Status& status) {
  std::uint64_t total = 0;
  for (const char* key : {"packets", "kernel_drops"}) {
    if (const auto it = status.find(key); it != status.end()) total += it->second;
  }
  return total;
}

}  // namespace ssl_formation::testing
