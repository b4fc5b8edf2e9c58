#include "ssl_formation/recorder/recorder.hpp"

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <filesystem>
#include <optional>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "ssl_vision_wrapper_tracked.pb.h"

namespace ssl_formation::recorder {

namespace {

std::int64_t unix_time_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class Recorder {
 public:
  Recorder(LogWriter& writer, const RecordOptions& options) : writer_(writer), options_(options) {}

  // Returns false when recording must end (--count reached or the file cannot be written).
  bool add(std::span<const std::byte> data) {
    const int size = static_cast<int>(data.size());  // <= kMaxUdpPayload
    if (!packet_.ParsePartialFromArray(data.data(), size) || !packet_.IsInitialized()) {
      if (skipped_++ == 0) {
        spdlog::warn(
            "a datagram of {} bytes is not an SSL_WrapperPacket: not recorded (the "
            "status lines count them)",
            data.size());
      }
      return true;
    }
    const std::string_view payload = net::as_text(data);
    if (!writer_.write(static_cast<std::int32_t>(LogMessageType::vision), unix_time_ns(),
                       payload)) {
      failed_ = true;
      return false;
    }
    ++recorded_;
    return options_.count == 0 || recorded_ < options_.count;
  }

  // A datagram from the referee group: recorded as a referee message (type 3) if it is one.
  // Does not count towards --count, which counts vision packets. False when the file cannot be
  // written.
  bool add_referee(std::span<const std::byte> data) {
    return add_other(data, referee_message_, LogMessageType::referee, "the referee group",
                     "referee message", referee_);
  }
  // A datagram from the trackers' group: recorded as tracked vision (type 5) if it is some.
  bool add_tracked(std::span<const std::byte> data) {
    return add_other(data, tracked_packet_, LogMessageType::tracker, "the trackers' group",
                     "TrackerWrapperPacket", tracked_);
  }

  std::uint64_t recorded() const { return recorded_; }
  std::uint64_t skipped() const { return skipped_; }
  struct OtherCounts {
    std::uint64_t recorded = 0;
    std::uint64_t skipped = 0;
  };
  const OtherCounts& referee() const { return referee_; }
  const OtherCounts& tracked() const { return tracked_; }
  bool failed() const { return failed_; }

 private:
  bool add_other(std::span<const std::byte> data, google::protobuf::MessageLite& scratch,
                 LogMessageType type, const char* where, const char* what, OtherCounts& counts) {
    if (!scratch.ParsePartialFromArray(data.data(), static_cast<int>(data.size()))) {
      if (counts.skipped++ == 0) {
        spdlog::warn(
            "a datagram of {} bytes on {} is not a {}: not recorded (the status lines "
            "count them)",
            data.size(), where, what);
      }
      return true;
    }
    const std::string_view payload = net::as_text(data);
    if (!writer_.write(static_cast<std::int32_t>(type), unix_time_ns(), payload)) {
      failed_ = true;
      return false;
    }
    ++counts.recorded;
    return true;
  }

  LogWriter& writer_;
  const RecordOptions& options_;
  SSL_WrapperPacket packet_;             // reused
  Referee referee_message_;              // reused
  TrackerWrapperPacket tracked_packet_;  // reused
  std::uint64_t recorded_ = 0;
  std::uint64_t skipped_ = 0;
  OtherCounts referee_;
  OtherCounts tracked_;
  bool failed_ = false;
};

}  // namespace

int run_record(const RecordOptions& options) {
  const auto group = app::parse_group_option("vision-address", options.network.vision_address);
  const auto interface = app::parse_interface_option(options.network.interface, true);
  const std::optional<net::MulticastEndpoint> referee_group =
      app::parse_referee_option(options.network.referee_address);
  const std::optional<net::MulticastEndpoint> tracker_group =
      app::parse_tracker_option(options.network.tracker_address);
  if (options.output.empty()) throw app::UsageError("--output FILE is required (.log or .log.gz)");
  if (!(options.duration_s >= 0.0) || options.duration_s > 1e9) {
    throw app::UsageError("--duration must be >= 0 seconds (0 = until a signal)");
  }
  if (options.receive_buffer_bytes < 0) throw app::UsageError("--receive-buffer must be >= 0");
  const auto status_period = app::seconds_option("status-interval", options.status_interval_s);
  std::error_code ec;
  if (!options.overwrite && std::filesystem::exists(options.output, ec)) {
    throw app::UsageError(options.output + " exists; pass --overwrite to replace it");
  }

  Result<LogWriter> writer = LogWriter::create(options.output);
  if (!writer) throw std::runtime_error(writer.error().message);
  Recorder recorder(*writer, options);

  boost::asio::io_context io;
  net::MulticastReceiver receiver(io, group, interface, options.receive_buffer_bytes);
  const auto started = std::chrono::steady_clock::now();
  std::optional<net::MulticastReceiver> referee;
  if (referee_group) referee.emplace(io, *referee_group, interface, options.receive_buffer_bytes);
  std::optional<net::MulticastReceiver> tracker;
  if (tracker_group) tracker.emplace(io, *tracker_group, interface, options.receive_buffer_bytes);
  const auto log_status = [&](const char* what, app::StatusMoment moment) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    app::StatusLine line;
    if (recorder.recorded() == 0) line.note("no vision packets yet");
    line.figure("recorded", recorder.recorded())
        .figure("bytes", writer->offset())
        .figure("seconds", fmt::format("{:.1f}", seconds));
    line.detail("referee_recorded", recorder.referee().recorded)
        .detail("tracked_recorded", recorder.tracked().recorded);
    // Datagrams that are not what their group carries, and every receiver's losses.
    line.problem("skipped", recorder.skipped())
        .problem("referee_skipped", recorder.referee().skipped)
        .problem("tracked_skipped", recorder.tracked().skipped)
        .problem("kernel_drops", receiver.counters().kernel_drops.load());
    std::uint64_t receive_errors = receiver.counters().receive_errors.load();
    if (referee) {
      line.problem("referee_kernel_drops", referee->counters().kernel_drops.load());
      receive_errors += referee->counters().receive_errors.load();
    }
    if (tracker) {
      line.problem("tracker_kernel_drops", tracker->counters().kernel_drops.load());
      receive_errors += tracker->counters().receive_errors.load();
    }
    line.problem("receive_errors", receive_errors);
    line.log(what, moment);
  };
  bool by_signal = false;
  const auto stop = [&] {
    receiver.stop();
    if (referee) referee->stop();
    if (tracker) tracker->stop();
    io.stop();
  };
  receiver.start([&](std::span<const std::byte> data, const net::udp::endpoint&) {
    if (!recorder.add(data)) stop();
  });
  // Both groups on one thread, so the file holds their messages in the order they arrived.
  if (referee) {
    referee->start([&](std::span<const std::byte> data, const net::udp::endpoint&) {
      if (!recorder.add_referee(data)) stop();
    });
  }
  if (tracker) {
    tracker->start([&](std::span<const std::byte> data, const net::udp::endpoint&) {
      if (!recorder.add_tracked(data)) stop();
    });
  }
  spdlog::info(
      "recording {}, the referee on {} and trackers on {} (interface {}, receive buffer {} "
      "bytes) to {}{}{}",
      group.to_string(), referee_group ? referee_group->to_string() : "none",
      tracker_group ? tracker_group->to_string() : "none", interface.to_string(),
      receiver.granted_receive_buffer(), options.output,
      options.duration_s > 0.0 ? fmt::format(" for {} s", options.duration_s) : "",
      options.count ? fmt::format(", at most {} packets", options.count) : "");

  app::RepeatingTimer status(io, status_period,
                             [&] { log_status("status", app::StatusMoment::periodic); });
  boost::asio::steady_timer deadline(io);
  if (options.duration_s > 0.0) {
    deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(options.duration_s)));
    deadline.async_wait([&](const boost::system::error_code& e) {
      if (!e) stop();
    });
  }
  app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: closing {} and stopping", signal, options.output);
    by_signal = true;
    stop();
  });
  app::ReadyFile ready(options.daemon.ready_file);
  ready.mark_ready("ssl-record", {{"vision", group.to_string()},
                                  {"referee", referee_group ? referee_group->to_string() : "none"},
                                  {"tracker", tracker_group ? tracker_group->to_string() : "none"},
                                  {"interface", interface.to_string()},
                                  {"output", options.output}});
  io.run();
  receiver.stop();
  if (referee) referee->stop();
  if (tracker) tracker->stop();

  if (recorder.failed()) {
    spdlog::error("{}; {} not written (an earlier file there is as it was)", writer->error(),
                  options.output);
    return 1;
  }
  if (!writer->close(options.index)) {
    spdlog::error("{}", writer->error());
    return 1;
  }
  log_status(by_signal ? "stopped" : "done", app::StatusMoment::at_stop);
  return 0;
}

}  // namespace ssl_formation::recorder
