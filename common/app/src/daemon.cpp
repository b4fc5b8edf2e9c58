#include "ssl_formation/app/daemon.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ssl_formation/app/log_limit.hpp"
#include "ssl_formation/app/options.hpp"

namespace ssl_formation::app {

namespace {
// What every log line starts with: "[23:14:05.123] ssl-trainer: info: ", and an error
// "ssl-trainer: error: " as the programs' own error lines (run_main) are: one format a user or
// a script looks for, whether the error stopped the program or not. info_prefix_chars counts it
// for status lines.
constexpr const char* log_pattern = "%*%n: %l: %v";
constexpr std::string_view info_level = "info";
constexpr std::size_t time_chars = std::string_view("[23:14:05.123] ").size();

// %*: the time of day, but not before an error.
class TimeUnlessError : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& message, const std::tm&,
              spdlog::memory_buf_t& out) override {
    if (message.level >= spdlog::level::err) return;
    // The formatter only fills in its std::tm for its own time flags: this one makes its own.
    const std::time_t seconds = spdlog::log_clock::to_time_t(message.time);
    std::tm time{};
    localtime_r(&seconds, &time);
    const auto millis =
        std::chrono::duration_cast<std::chrono::milliseconds>(message.time.time_since_epoch())
            .count() %
        1000;
    char text[32];
    const int n = std::snprintf(text, sizeof text, "[%02d:%02d:%02d.%03d] ", time.tm_hour,
                                time.tm_min, time.tm_sec, static_cast<int>(millis));
    out.append(text, text + n);
  }
  std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<TimeUnlessError>();
  }
};
}  // namespace

std::size_t info_prefix_chars(std::string_view program) {
  return time_chars + program.size() + 2 + info_level.size() + 2;  // ": info: "
}

void init_logging(const std::string& program, bool verbose) {
  // Every line through the repeat limit (log_limit.hpp), and libprotobuf's own messages too.
  auto limited =
      std::make_shared<LimitedSink>(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  auto logger = std::make_shared<spdlog::logger>(program, std::move(limited));
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<TimeUnlessError>('*').set_pattern(log_pattern);
  logger->set_formatter(std::move(formatter));
  logger->set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  route_protobuf_log();
}

net::MulticastEndpoint parse_group_option(const std::string& option, const std::string& text) {
  const auto endpoint = net::parse_multicast_endpoint(text);
  if (!endpoint) throw UsageError("--" + option + ": " + endpoint.error().message);
  return *endpoint;
}

net::InterfaceChoice parse_interface_option(const std::string& text, bool allow_all) {
  const auto choice = net::parse_interface(text, allow_all);
  if (!choice) throw UsageError("--interface: " + choice.error().message);
  return *choice;
}

std::optional<net::MulticastEndpoint> parse_referee_option(const std::string& text) {
  if (text == "none") return std::nullopt;
  return parse_group_option("referee-address", text);
}

std::optional<net::MulticastEndpoint> parse_tracker_option(const std::string& text) {
  if (text == "none") return std::nullopt;
  return parse_group_option("tracker-address", text);
}

void MatchLog::update(const MatchFrontEnd& front_end, const RefereeChange& change) {
  const MatchFollower& match = front_end.match();
  const std::optional<AttackDirection> attacks_now = front_end.sampler().attacks();
  const TrackedVision& tracked = front_end.tracked_vision();
  if (tracked.source_uuid() != logged_tracker_) {
    spdlog::info("tracked vision: following tracker '{}' (uuid {}){}", tracked.source_name(),
                 tracked.source_uuid(),
                 logged_tracker_.empty() ? "" : ": the one followed before fell silent");
    logged_tracker_ = tracked.source_uuid();
  }
  if (!logged_opponent_ || !(*logged_opponent_ == match.opponent()) ||
      logged_attacks_ != attacks_now) {
    spdlog::info("opponent: {}", describe(match.opponent(), attacks_now));
    logged_opponent_ = match.opponent();
    logged_attacks_ = attacks_now;
  }
  const RefereeFollower& referee = match.referee();
  if (referee.heard() && logged_state_ != match.game_state()) {
    spdlog::info("referee: {}", describe(referee));
    logged_state_ = match.game_state();
  }
  const RefereeCounters& c = referee.counters();
  if (change.conflict) {
    spdlog::warn(
        "referee: a second game controller sends on the referee group; still following the "
        "first ('{}'), {} messages of others ignored so far",
        referee.view().source, c.other_source);
  }
  if (change.stale && c.stale == 1) {
    // Said once; the status lines count them (referee_stale).
    spdlog::warn(
        "referee: a message from the game controller followed ('{}') is older than what it said "
        "before (its command counter went back, or its timestamp is more than {} s behind or {} s "
        "ahead): not used, nor any like it (counted as referee_stale in the status lines)",
        referee.view().source, RefereeFollower::max_timestamp_back_s,
        RefereeFollower::max_timestamp_ahead_s);
  }
  if (change.resync) {
    spdlog::warn(
        "referee: following the newest messages of the game controller '{}' again, "
        "after refusing them as stale (a replay heard first, a log starting over, or "
        "forged messages); {} such times so far",
        referee.view().source, c.resyncs);
  }
  if (change.source) {
    spdlog::warn("referee: the game controller followed fell silent; now following '{}'",
                 referee.view().source);
  }
  if (c.undecodable > reported_.undecodable) {
    spdlog::warn("referee: {} datagrams that are not referee messages ({} in all)",
                 c.undecodable - reported_.undecodable, c.undecodable);
  }
  if (c.unknown_command > reported_.unknown_command) {
    spdlog::warn("referee: {} messages with a command this program does not know ({} in all)",
                 c.unknown_command - reported_.unknown_command, c.unknown_command);
  }
  reported_ = c;
}

net::LiveFeeds live_feeds(const NetworkOptions& network, int receive_buffer_bytes) {
  net::LiveFeeds feeds;
  feeds.vision = parse_group_option("vision-address", network.vision_address);
  feeds.referee = parse_referee_option(network.referee_address);
  if (network.tracked()) {
    feeds.tracker = parse_group_option("tracker-address", network.tracker_address);
  }
  feeds.interface = parse_interface_option(network.interface, true);
  feeds.receive_buffer_bytes = receive_buffer_bytes;
  return feeds;
}

void add_match(StatusLine& line, const MatchFrontEnd& front_end) {
  const MatchFollower& match = front_end.match();
  const Opponent& opponent = match.opponent();
  const std::optional<AttackDirection> attacks = front_end.sampler().attacks();
  // Why, unless the referee said so: what it says is what a match runs on.
  const auto why = [](Because because) {
    return because == Because::referee ? std::string()
                                       : "(" + std::string(to_string(because)) + ")";
  };
  line.figure("game", to_string(match.game_state()))
      .figure("opponent", std::string(to_string(opponent.color)) + why(opponent.color_because))
      .figure("attacks", (attacks ? std::string(to_string(*attacks)) : "unknown-yet") +
                             why(opponent.attacks_because));
  const RefereeCounters& c = match.referee().counters();
  line.problem("referee_unused", c.messages - c.used)
      .problem("referee_stale", c.stale)
      .problem("name_switches_refused", c.refused_name_switches);
}

StopSignals::StopSignals(boost::asio::io_context& io, std::function<void(int)> on_stop)
    : signals_(io, SIGINT, SIGTERM) {
  signals_.async_wait(
      [this, on_stop = std::move(on_stop)](const boost::system::error_code& error, int signal) {
        if (error) return;
        // Asio gives the signals back their default action when no set holds them any more.
        boost::system::error_code ignored;
        signals_.clear(ignored);
        on_stop(signal);
      });
}

ReadyFile::~ReadyFile() {
  if (!written_) return;
  // unlink, not std::filesystem::remove: that takes a path, and building one from path_ allocates,
  // which can throw in a destructor. Nothing to do about a file that is already gone.
  ::unlink(path_.c_str());
}

void ReadyFile::mark_ready(const std::string& program,
                           const std::vector<std::pair<std::string, std::string>>& facts) {
  if (path_.empty()) return;
  std::string text = "program=" + program + "\npid=" + std::to_string(::getpid()) + "\n";
  for (const auto& [key, value] : facts) text += key + "=" + value + "\n";
  const std::string temporary = path_ + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      ::unlink(temporary.c_str());  // whatever part of it was written
      throw std::runtime_error("cannot write the ready file " + temporary);
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path_, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw std::runtime_error("cannot write the ready file " + path_ + ": " + error.message());
  }
  written_ = true;
}

RepeatingTimer::RepeatingTimer(boost::asio::io_context& io,
                               std::chrono::steady_clock::duration period,
                               std::function<void()> tick)
    : timer_(io), period_(period), tick_(std::move(tick)) {
  arm();
}

void RepeatingTimer::cancel() {
  // The flag covers what timer_.cancel() cannot: an expiry already queued, and a tick that
  // cancels its own timer (there is no wait to cancel while it runs).
  cancelled_ = true;
  timer_.cancel();
}

void RepeatingTimer::arm() {
  timer_.expires_after(period_);
  timer_.async_wait([this](const boost::system::error_code& error) {
    if (error || cancelled_) return;
    tick_();
    if (!cancelled_) arm();
  });
}

void add_reception(StatusLine& line, const net::LiveMatchEvents* live,
                   const MatchFrontEnd& front_end) {
  const bool tracked = front_end.config().tracked_vision;
  if (tracked) {
    const TrackerCounters& c = front_end.tracked_vision().counters();
    if (c.frames == 0) line.note("no tracked frames yet");
    line.figure("tracker_frames", c.frames).problem("tracker_undecodable", c.undecodable);
  }
  if (!live) return;
  const net::ReceiverCounters& vision = live->vision().counters();
  const std::uint64_t packets = vision.datagrams.load();
  // With tracked vision the vision packets give only the field's size: a detail.
  if (tracked) {
    line.detail("packets", packets);
  } else {
    if (packets == 0) line.note("no vision packets yet");
    line.figure("packets", packets);
  }
  line.problem("parse_errors", vision.parse_errors.load())
      .problem("kernel_drops", vision.kernel_drops.load());
  std::uint64_t receive_errors = vision.receive_errors.load();
  if (const net::MulticastReceiver* referee = live->referee()) {
    line.problem("referee_kernel_drops", referee->counters().kernel_drops.load());
    receive_errors += referee->counters().receive_errors.load();
  }
  if (const net::MulticastReceiver* tracker = live->tracker()) {
    line.problem("tracker_kernel_drops", tracker->counters().kernel_drops.load());
    receive_errors += tracker->counters().receive_errors.load();
  }
  line.problem("receive_errors", receive_errors);
}

void add_reception_details(StatusLine& line, const net::LiveMatchEvents* live,
                           const MatchFrontEnd& front_end) {
  if (front_end.config().tracked_vision) {
    const TrackerCounters& c = front_end.tracked_vision().counters();
    line.detail("tracker_packets", c.packets).detail("tracker_other_source", c.other_source);
  }
  if (!live) return;
  const std::uint64_t datagrams = live->vision().counters().datagrams.load();
  if (datagrams == 0) return;
  line.detail("fast_path",
              fmt::format("{:.1f}%", 100.0 * static_cast<double>(live->vision().direct_decodes()) /
                                         static_cast<double>(datagrams)));
}

void add_sampler_counters(StatusLine& line, const SamplerCounters& counters) {
  for (const auto& [name, count] : rejection_counts(counters)) {
    line.problem(name, count, "input_refused");
  }
  line.detail("clock_resets", counters.clock_resets)
      .detail("field_changes", counters.field_changes);
}

FieldSizeLog::FieldSizeLog(const FieldSize& from_options, bool geometry_used)
    : logged_(from_options) {
  spdlog::info("field: {} from the options{}", describe(from_options),
               geometry_used ? ", until a geometry packet gives the size" : " (--ignore-geometry)");
}

void FieldSizeLog::update(const FieldSize& field) {
  if (field == logged_) return;
  spdlog::info("field: {} from a geometry packet (was {})", describe(field), describe(logged_));
  logged_ = field;
}

std::chrono::steady_clock::duration seconds_option(const std::string& option, double seconds) {
  if (!std::isfinite(seconds) || seconds <= 0.0 || seconds > 1e6) {
    std::ostringstream text;
    text << "--" << option << " must be a positive number of seconds, not " << seconds;
    throw UsageError(text.str());
  }
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(seconds));
}

}  // namespace ssl_formation::app
