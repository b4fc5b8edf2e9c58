#include "ssl_formation/app/daemon.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ssl_formation/app/log_limit.hpp"
#include "ssl_formation/app/options.hpp"

namespace ssl_formation::app {

void init_logging(const std::string& program, bool verbose) {
  // Every line through the repeat limit (log_limit.hpp), and libprotobuf's own messages too.
  auto limited = std::make_shared<LimitedSink>(
      std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  auto logger = std::make_shared<spdlog::logger>(program, std::move(limited));
  logger->set_pattern("[%H:%M:%S.%e] %n %l: %v");
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

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
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
    spdlog::warn("referee: following the newest messages of the game controller '{}' again, "
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

std::string describe_tracked(const MatchFrontEnd& front_end) {
  if (!front_end.config().tracked_vision) return {};
  const TrackerCounters& c = front_end.tracked_vision().counters();
  return fmt::format(" tracker_packets={} tracker_frames={} tracker_other_source={} "
                     "tracker_undecodable={}",
                     c.packets, c.frames, c.other_source, c.undecodable);
}

std::string describe_referee_counts(const MatchFollower& match) {
  const RefereeCounters& c = match.referee().counters();
  const Opponent& opponent = match.opponent();
  return fmt::format(
      "opponent={} ({}) game={} referee_messages={} referee_unused={} referee_stale={} "
      "name_switches_refused={}",
      to_string(opponent.color), to_string(opponent.color_because), to_string(match.game_state()),
      c.messages, c.messages - c.used, c.stale, c.refused_name_switches);
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

std::string describe_reception(const net::VisionReceiver& receiver) {
  const net::ReceiverCounters& counters = receiver.counters();
  const std::uint64_t datagrams = counters.datagrams.load();
  std::string text = fmt::format("packets={} parse_errors={} kernel_drops={} fast_path=", datagrams,
                                 counters.parse_errors.load(), counters.kernel_drops.load());
  if (datagrams == 0) return text + "-";
  return text + fmt::format("{:.1f}%", 100.0 * static_cast<double>(receiver.direct_decodes()) /
                                           static_cast<double>(datagrams));
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

std::string describe_attacks(std::optional<AttackDirection> now, Because because) {
  const std::string why = " (" + std::string(to_string(because)) + ")";
  return now ? std::string(to_string(*now)) + why : std::string("unknown-yet") + why;
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
