#pragma once
// What the three daemons share around the core: logging, parsing the network options into
// endpoints, clean shutdown on SIGINT/SIGTERM through Asio's signal_set (no work inside a signal
// handler), and repeating timers.

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/app/status_line.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/match/match.hpp"
#include "ssl_formation/match/tracked_vision.hpp"
#include "ssl_formation/net/live_match_events.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/net/vision_receiver.hpp"
#include "ssl_formation/pipeline/match_front_end.hpp"

namespace ssl_formation::app {

// All log lines go to stderr through spdlog: "[23:14:05.123] ssl-trainer info: ...".
void init_logging(const std::string& program, bool verbose = false);
// The characters init_logging puts before an info message of `program`:
// "[23:14:05.123] ssl-trainer: info: ".
std::size_t info_prefix_chars(std::string_view program);

// Both throw UsageError naming the option.
net::MulticastEndpoint parse_group_option(const std::string& option, const std::string& text);
net::InterfaceChoice parse_interface_option(const std::string& text, bool allow_all);

// --referee-address, --tracker-address: the group, or none for "none". Throw UsageError.
std::optional<net::MulticastEndpoint> parse_referee_option(const std::string& text);
std::optional<net::MulticastEndpoint> parse_tracker_option(const std::string& text);

// The network feeds the options ask for (--vision-address, --referee-address, --vision-source
// and --tracker-address, --interface). Throws UsageError naming the option.
net::LiveFeeds live_feeds(const NetworkOptions& network, int receive_buffer_bytes);

// Logs who the opponent is and the game state whenever either changes, which tracker is followed
// when that changes, and a warning when a second game controller appears or referee messages
// arrive that cannot be used.
class MatchLog {
 public:
  // Cheap when nothing changed; call it after every referee message, tracker packet (and after
  // frames with --opponent-attacks auto, whose side the sampler infers).
  void update(const MatchFrontEnd& front_end, const RefereeChange& change = {});

 private:
  // What was logged last, compared before anything is formatted: update() runs for every frame
  // while the side is inferred.
  std::optional<Opponent> logged_opponent_;
  std::optional<AttackDirection> logged_attacks_;
  std::optional<GameState> logged_state_;
  RefereeCounters reported_;
  std::string logged_tracker_;  // the uuid of the tracker followed, as last logged
};

// The match on a status line: the figures game=running opponent=blue attacks=+x(inferred) (the
// opponent's colour and the side it attacks, and why they are believed unless the referee said
// so: option, default or inferred), and as problems the referee messages not followed
// (referee_unused: another game controller, unknown commands, undecodable), the stale ones
// (referee_stale) and the team names refused (name_switches_refused).
void add_match(StatusLine& line, const MatchFrontEnd& front_end);

// Calls `on_stop` once on the first SIGINT or SIGTERM, from the io_context's thread. From then on
// the signals have their default action again, so a second Ctrl-C (or SIGTERM) ends the process
// at once, even while `on_stop` is still busy (a slow save): the user always has a way out, and
// the table file is never half-written because saves replace it atomically.
class StopSignals {
 public:
  StopSignals(boost::asio::io_context& io, std::function<void(int signal)> on_stop);

 private:
  boost::asio::signal_set signals_;
};

// Calls `tick` every `period` on the io_context's thread until cancel() or destruction.
class RepeatingTimer {
 public:
  RepeatingTimer(boost::asio::io_context& io, std::chrono::steady_clock::duration period,
                 std::function<void()> tick);
  // No tick runs after this, also when called from inside a tick or while a tick is queued.
  void cancel();

 private:
  void arm();
  bool cancelled_ = false;
  boost::asio::steady_timer timer_;
  std::chrono::steady_clock::duration period_;
  std::function<void()> tick_;
};

// The daemon's readiness, for whoever started it: once the sockets are open and joined (and, for
// the predictor, the table there at start-up is loaded), `mark_ready` writes the file atomically
// (a reader never sees part of it) as "key=value" lines, starting with "program=" and "pid=".
// The destructor removes it, so a file left behind names a process that died.
class ReadyFile {
 public:
  explicit ReadyFile(std::string path) : path_(std::move(path)) {}
  ReadyFile(const ReadyFile&) = delete;
  ReadyFile& operator=(const ReadyFile&) = delete;
  ~ReadyFile();
  // Does nothing without a path. Throws std::runtime_error if the file cannot be written: a
  // supervisor waiting for it would wait forever.
  void mark_ready(const std::string& program,
                  const std::vector<std::pair<std::string, std::string>>& facts);

 private:
  std::string path_;
  bool written_ = false;
};

// The receiving side of a status line, the same in every daemon: the figure packets (vision
// datagrams read; "no vision packets yet" before the first), and the problems parse_errors,
// kernel_drops (vision datagrams the kernel dropped for want of room), referee_kernel_drops,
// tracker_kernel_drops and receive_errors. With --vision-source tracked the figure is
// tracker_frames, packets a detail, and tracker_undecodable a problem. `live` null: the events
// come from a test's hands, not the network.
void add_reception(StatusLine& line, const net::LiveMatchEvents* live,
                   const MatchFrontEnd& front_end);
// The receiving side's details, for the end of a status line: with --vision-source tracked
// tracker_packets and tracker_other_source (packets of trackers not followed), and fast_path=99.9%,
// the share of vision datagrams decoded without protobuf, so that a change in SSL-Vision's
// packets that moves everything to the slow path is visible.
void add_reception_details(StatusLine& line, const net::LiveMatchEvents* live,
                           const MatchFrontEnd& front_end);
// The sampler's refusals of bad input as problems (non_finite=N late=N ..., the names of
// rejection_counts; summed as input_refused=N when they crowd the figures out), and the details
// clock_resets and field_changes.
void add_sampler_counters(StatusLine& line, const SamplerCounters& counters);

// Logs the field size sampling uses, once at start and once per change (geometry packets), with
// the division it implies: a wrong field size silently moves every robot to other cells.
class FieldSizeLog {
 public:
  // `from_options`: the size the options give, used until a geometry packet says otherwise.
  FieldSizeLog(const FieldSize& from_options, bool geometry_used);
  // Cheap when nothing changed; call it after every packet that carries geometry.
  void update(const FieldSize& field);

 private:
  FieldSize logged_;
};

std::chrono::steady_clock::duration seconds_option(const std::string& option, double seconds);

}  // namespace ssl_formation::app
