// --replay: sends an official SSL log's vision packets onto multicast with the recorded timing
// (packet i at start + (t_i - t_first) / speed on the clock replay_clock.hpp chooses), as fast as
// possible with --speed 0, over a window (--start/--end) and in a loop (--loop). Its referee
// messages and tracked vision go to their own groups in their places (none: not sent).

#include <spdlog/spdlog.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cmath>
#include <deque>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/producer/producer_options.hpp"
#include "ssl_formation/producer/replay_clock.hpp"

namespace ssl_formation::producer {

namespace {

using Clock = std::chrono::steady_clock;

// Packets read ahead at the start of the file to choose the clock: several seconds of any feed.
constexpr std::size_t kClockSamplePackets = 500;
// Packets sent (or skipped before --start) in a row before signals and timers get their turn.
constexpr int kPacketsPerBatch = 64;
constexpr int kSkipsPerBatch = 4096;

void add_counters(LogReadCounters& total, const LogReadCounters& more) {
  total.messages += more.messages;
  total.vision += more.vision;
  total.legacy_vision += more.legacy_vision;
  total.referee += more.referee;
  total.tracker += more.tracker;
  total.index += more.index;
  total.unknown += more.unknown;
  total.parse_errors += more.parse_errors;
  total.bytes += more.bytes;
  total.blank += more.blank;
  total.legacy_unusable += more.legacy_unusable;
}

class LogReplay {
 public:
  // `referee`, `tracker`: where the log's referee messages and tracked vision go; none: they
  // are skipped.
  LogReplay(boost::asio::io_context& io, const ProducerOptions& options,
            net::ProtoMulticastSender<SSL_WrapperPacket>& sender, net::MulticastSender* referee,
            net::MulticastSender* tracker)
      : io_(io),
        timer_(io),
        options_(options),
        sender_(sender),
        referee_(referee),
        tracker_(tracker) {}

  // Opens the file and chooses the clock; throws std::runtime_error if it cannot be read.
  void open() {
    if (const auto opened = open_pass(); !opened) throw std::runtime_error(opened.error().message);
    std::vector<ClockSample> samples;
    Pending pending;
    while (samples.size() < kClockSamplePackets && read(pending)) {
      if (pending.kind == LogReader::MatchInput::vision) {
        ClockSample sample{pending.receive_time, std::nullopt};
        if (pending.packet.has_detection())
          sample.t_capture = pending.packet.detection().t_capture();
        samples.push_back(sample);
      }
      lookahead_.push_back(std::move(pending));
      pending = Pending{};
    }
    const ClockChoice choice = choose_replay_clock(samples);
    timeline_ = ReplayTimeline(choice.clock);
    if (choice.ratio > 0.0) {
      spdlog::info(
          "timing from {}: {} (receive span / t_capture span = {:.3g} over the first {} packets)",
          to_string(choice.clock), choice.reason, choice.ratio, samples.size());
    } else {
      spdlog::info("timing from {}: {}", to_string(choice.clock), choice.reason);
    }
    if (choice.clock == ReplayClock::receive_ns && choice.ratio > 0.0 &&
        std::abs(std::log10(choice.ratio) - 9.0) > 1.0) {
      spdlog::warn(
          "the receive times advance {:.3g} per second of t_capture, far from 1e9: the "
          "replay follows the receive times",
          choice.ratio);
    }
  }

  void start() {
    started_ = Clock::now();
    step();
  }
  void stop() {
    stopped_ = true;
    timer_.cancel();
  }
  int exit_code() const { return exit_code_; }
  bool finished() const { return finished_; }

  // The same line each --status-interval and at the end ("done", "stopped", "failed").
  void log_status(const char* what, app::StatusMoment moment) const {
    LogReadCounters counters = totals_;
    if (reader_) add_counters(counters, reader_->counters());
    const double seconds = std::chrono::duration<double>(Clock::now() - started_).count();
    app::StatusLine line;
    if (sender_.sent() == 0) line.note("no vision packets sent yet");
    line.figure("sent", sender_.sent())
        .figure("log_time", fmt::format("{:.2f}s", last_t_))
        .figure("seconds", fmt::format("{:.2f}", seconds));
    // The log's referee messages and tracked vision not sent: no group for them, or before
    // --start.
    line.detail("referee_sent", referee_sent_)
        .detail("referee_unsent", counters.referee - std::min(counters.referee, referee_sent_))
        .detail("tracker_sent", tracker_sent_)
        .detail("tracker_unsent", counters.tracker - std::min(counters.tracker, tracker_sent_))
        .detail("passes", passes_)
        .detail("before_start", before_start_)
        .detail("blank", counters.blank)
        .detail("unknown", counters.unknown)
        .detail("legacy_vision_unusable", counters.legacy_unusable);
    line.problem("undecodable", counters.parse_errors)
        .problem("encode_errors", sender_.encode_errors())
        .problem("send_errors", sender_.send_errors() + (referee_ ? referee_->send_errors() : 0) +
                                    (tracker_ ? tracker_->send_errors() : 0));
    line.log(what, moment);
  }

 private:
  // A vision packet, or a referee message or tracked vision (its bytes in `payload`).
  struct Pending {
    SSL_WrapperPacket packet;
    std::int64_t receive_time = 0;
    LogReader::MatchInput kind = LogReader::MatchInput::vision;
    std::string payload;
  };

  // The log's next vision packet or referee message into `out` (cleared first).
  bool read(Pending& out) {
    out.packet.Clear();
    std::string_view payload;
    if (!reader_->next_match_input(out.kind, out.packet, payload, &out.receive_time)) return false;
    out.payload.assign(out.kind == LogReader::MatchInput::vision ? std::string_view() : payload);
    return true;
  }
  enum class Fetch { packet, end, error };

  Result<void> open_pass() {
    if (reader_) add_counters(totals_, reader_->counters());
    reader_.reset();  // its counters are in totals_ now
    Result<LogReader> opened = LogReader::open(options_.replay);
    if (!opened) return Unexpected(std::move(opened).error());
    reader_.emplace(std::move(*opened));
    ++passes_;
    pass_ended_ = false;
    anchored_ = false;
    timeline_.restart();
    return {};
  }

  Fetch fetch() {
    if (pass_ended_) return Fetch::end;
    if (!lookahead_.empty()) {
      current_ = std::move(lookahead_.front());
      lookahead_.pop_front();
      return Fetch::packet;
    }
    if (read(current_)) return Fetch::packet;
    return reader_->error().empty() ? Fetch::end : Fetch::error;
  }

  void finish(int code) {
    exit_code_ = code;
    finished_ = true;
    stopped_ = true;
    io_.stop();
  }

  bool limit_reached() const {
    return options_.count != 0 && sender_.sent() + send_failures_ >= options_.count;
  }

  void step() {
    if (stopped_) return;
    int sent_now = 0;
    int skipped_now = 0;
    for (;;) {
      if (limit_reached()) return finish(0);
      if (!have_current_) {
        const Fetch got = fetch();
        if (got == Fetch::error) {
          spdlog::error("{}; the {} packets before it were sent", reader_->error(), sender_.sent());
          return finish(1);
        }
        if (got == Fetch::end) {
          if (sender_.sent() + send_failures_ == 0) {
            spdlog::error("{}: no vision packets{} to replay", options_.replay,
                          options_.replay_start_s > 0.0 || options_.replay_end_s > 0.0
                              ? " between --start and --end"
                              : "");
            return finish(1);
          }
          if (!options_.loop) return finish(0);
          if (const auto opened = open_pass(); !opened) {
            spdlog::error("{}", opened.error().message);
            return finish(1);
          }
          continue;
        }
        if (current_.kind != LogReader::MatchInput::vision) {
          // Sent in its place among the vision packets, except before --start (the game
          // controller repeats its state every 100 ms, a tracker sends 60 frames a second: the
          // replay's first second brings them).
          const bool referee = current_.kind == LogReader::MatchInput::referee;
          net::MulticastSender* to = referee ? referee_ : tracker_;
          if (to && (anchored_ || options_.replay_start_s <= 0.0) &&
              to->send(std::as_bytes(std::span(current_.payload)))) {
            ++(referee ? referee_sent_ : tracker_sent_);
          }
          // They count for the batch too: a log of trackers' packets alone must not hold the
          // thread (signals, the status timer) for its whole length.
          if (++skipped_now >= kSkipsPerBatch) return yield();
          continue;
        }
        const double t = timeline_.time_of(current_.receive_time, current_.packet);
        if (t < options_.replay_start_s) {
          ++before_start_;
          if (++skipped_now >= kSkipsPerBatch) return yield();
          continue;
        }
        if (options_.replay_end_s > 0.0 && t > options_.replay_end_s) {
          pass_ended_ = true;  // the rest of this pass is after --end
          continue;
        }
        have_current_ = true;
        last_t_ = t;
        if (!anchored_) {
          anchored_ = true;
          anchor_wall_ = Clock::now();
          anchor_t_ = t;
        }
      }
      if (options_.speed > 0.0) {
        const auto due = anchor_wall_ +
                         std::chrono::duration_cast<Clock::duration>(
                             std::chrono::duration<double>((last_t_ - anchor_t_) / options_.speed));
        if (due > Clock::now()) {
          timer_.expires_at(due);
          timer_.async_wait([this](const boost::system::error_code& error) {
            if (!error) step();
          });
          return;
        }
      }
      if (!sender_.send(current_.packet)) ++send_failures_;
      have_current_ = false;
      if (++sent_now >= kPacketsPerBatch) return yield();
    }
  }

  void yield() {
    boost::asio::post(io_, [this] { step(); });
  }

  boost::asio::io_context& io_;
  boost::asio::steady_timer timer_;
  const ProducerOptions& options_;
  net::ProtoMulticastSender<SSL_WrapperPacket>& sender_;
  net::MulticastSender* referee_;
  net::MulticastSender* tracker_;
  std::uint64_t referee_sent_ = 0;
  std::uint64_t tracker_sent_ = 0;
  std::optional<LogReader> reader_;
  std::deque<Pending> lookahead_;  // read ahead to choose the clock, sent first
  ReplayTimeline timeline_{ReplayClock::receive_ns};
  LogReadCounters totals_;  // of the passes before the current one

  Pending current_;
  bool have_current_ = false;
  bool pass_ended_ = false;
  bool anchored_ = false;
  Clock::time_point anchor_wall_;
  double anchor_t_ = 0.0;
  double last_t_ = 0.0;
  Clock::time_point started_ = Clock::now();
  std::uint64_t passes_ = 0;
  std::uint64_t before_start_ = 0;
  std::uint64_t send_failures_ = 0;  // encode errors (the sender counts its own send errors)
  bool stopped_ = false;
  bool finished_ = false;
  int exit_code_ = 0;
};

}  // namespace

int run_replay(const ProducerOptions& options) {
  const auto group = app::parse_group_option("vision-address", options.vision_address);
  const auto interface = app::parse_interface_option(options.interface, false);
  if (options.ttl < 0 || options.ttl > 255) throw app::UsageError("--ttl must be 0 to 255");
  if (!std::isfinite(options.speed) || options.speed < 0.0) {
    throw app::UsageError("--speed must be >= 0 (1 = recorded pace, 0 = as fast as possible)");
  }
  if (!std::isfinite(options.replay_start_s) || options.replay_start_s < 0.0) {
    throw app::UsageError("--start must be >= 0 seconds from the log's first packet");
  }
  if (!std::isfinite(options.replay_end_s) || options.replay_end_s < 0.0) {
    throw app::UsageError(
        "--end must be >= 0 seconds from the log's first packet (0 = to the end)");
  }
  if (options.replay_end_s > 0.0 && options.replay_end_s <= options.replay_start_s) {
    throw app::UsageError("--end must be after --start");
  }
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);

  boost::asio::io_context io;
  const std::optional<net::MulticastEndpoint> referee_group =
      app::parse_referee_option(options.referee_address);
  net::ProtoMulticastSender<SSL_WrapperPacket> sender(io, group, interface.address, options.ttl);
  std::optional<net::MulticastSender> referee;
  if (referee_group) referee.emplace(io, *referee_group, interface.address, options.ttl);
  const std::optional<net::MulticastEndpoint> tracker_group =
      app::parse_tracker_option(options.tracker_address);
  std::optional<net::MulticastSender> tracker;
  if (tracker_group) tracker.emplace(io, *tracker_group, interface.address, options.ttl);
  LogReplay replay(io, options, sender, referee ? &*referee : nullptr,
                   tracker ? &*tracker : nullptr);
  replay.open();
  sender.open();
  if (referee) referee->open();
  if (tracker) tracker->open();
  std::string window;
  if (options.replay_start_s > 0.0) window += fmt::format(", from {} s", options.replay_start_s);
  if (options.replay_end_s > 0.0) window += fmt::format(", to {} s", options.replay_end_s);
  if (options.loop) window += ", in a loop";
  if (options.count != 0) window += fmt::format(", {} packets", options.count);
  spdlog::info("replaying {} to {} (interface {}, ttl {}): speed {}{}", options.replay,
               group.to_string(), interface.to_string(), options.ttl,
               options.speed > 0.0 ? fmt::format("{}", options.speed) : "0 (as fast as possible)",
               window);
  app::RepeatingTimer status(io, status_period,
                             [&] { replay.log_status("status", app::StatusMoment::periodic); });
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    replay.stop();
    status.cancel();
    io.stop();
  });
  app::ReadyFile ready(options.daemon.ready_file);
  ready.mark_ready("ssl-producer",
                   {{"mode", "replay"},
                    {"vision", group.to_string()},
                    {"referee", referee_group ? referee_group->to_string() : "none"},
                    {"tracker", tracker_group ? tracker_group->to_string() : "none"},
                    {"interface", interface.to_string()},
                    {"log", options.replay}});
  replay.start();
  io.run();
  replay.log_status(!replay.finished()        ? "stopped"
                    : replay.exit_code() == 0 ? "done"
                                              : "failed",
                    app::StatusMoment::at_stop);
  return replay.exit_code();
}

}  // namespace ssl_formation::producer
