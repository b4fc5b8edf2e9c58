// ssl-record: captures a live multicast feed into an official SSL log file (.log or .log.gz), so
// a match can be replayed (ssl-producer --replay) or trained from later.
//
// Every datagram that decodes as an SSL_WrapperPacket is written as a type-4 message, byte for
// byte as received, with its receive time (Unix time, ns). Datagrams that do not decode are
// counted and left out: the file then holds only what every log player and our reader accept.
// SIGINT, SIGTERM, --duration and --count all end with a complete, valid file.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <filesystem>
#include <optional>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/log_file.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

struct RecordOptions {
  sf::app::NetworkOptions network;
  std::string output;
  bool overwrite = false;
  bool index = false;
  double duration_s = 0.0;
  std::uint64_t count = 0;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = sf::net::kDefaultReceiveBufferBytes;
  bool verbose = false;
};

std::int64_t unix_time_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class Recorder {
 public:
  Recorder(sf::LogWriter& writer, const RecordOptions& options)
      : writer_(writer), options_(options) {}

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
    const std::string_view payload(reinterpret_cast<const char*>(data.data()), data.size());
    if (!writer_.write(static_cast<std::int32_t>(sf::LogMessageType::vision), unix_time_ns(),
                       payload)) {
      failed_ = true;
      return false;
    }
    ++recorded_;
    return options_.count == 0 || recorded_ < options_.count;
  }

  std::uint64_t recorded() const { return recorded_; }
  std::uint64_t skipped() const { return skipped_; }
  bool failed() const { return failed_; }

 private:
  sf::LogWriter& writer_;
  const RecordOptions& options_;
  SSL_WrapperPacket packet_;  // reused
  std::uint64_t recorded_ = 0;
  std::uint64_t skipped_ = 0;
  bool failed_ = false;
};

int run_record(const RecordOptions& options) {
  const auto group = sf::app::parse_group_option("vision-address", options.network.vision_address);
  const auto interface = sf::app::parse_interface_option(options.network.interface, true);
  if (options.output.empty())
    throw sf::app::UsageError("--output FILE is required (.log or .log.gz)");
  if (!(options.duration_s >= 0.0) || options.duration_s > 1e9) {
    throw sf::app::UsageError("--duration must be >= 0 seconds (0 = until a signal)");
  }
  if (options.receive_buffer_bytes < 0) throw sf::app::UsageError("--receive-buffer must be >= 0");
  const auto status_period = sf::app::seconds_option("status-interval", options.status_interval_s);
  std::error_code ec;
  if (!options.overwrite && std::filesystem::exists(options.output, ec)) {
    throw sf::app::UsageError(options.output + " exists; pass --overwrite to replace it");
  }

  std::string error;
  std::optional<sf::LogWriter> writer = sf::LogWriter::create(options.output, &error);
  if (!writer) throw std::runtime_error(error);
  Recorder recorder(*writer, options);

  boost::asio::io_context io;
  sf::net::MulticastReceiver receiver(io, group, interface, options.receive_buffer_bytes);
  const auto started = std::chrono::steady_clock::now();
  const auto log_status = [&](const char* what) {
    const auto& net = receiver.counters();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    spdlog::info(
        "{}: recorded={} bytes={} skipped={} kernel_drops={} receive_errors={} seconds={:.1f}",
        what, recorder.recorded(), writer->offset(), recorder.skipped(), net.kernel_drops.load(),
        net.receive_errors.load(), seconds);
  };
  bool by_signal = false;
  const auto stop = [&] {
    receiver.stop();
    io.stop();
  };
  receiver.start([&](std::span<const std::byte> data, const sf::net::udp::endpoint&) {
    if (!recorder.add(data)) stop();
  });
  spdlog::info("recording {} (interface {}, receive buffer {} bytes) to {}{}{}", group.to_string(),
               interface.to_string(), receiver.granted_receive_buffer(), options.output,
               options.duration_s > 0.0 ? fmt::format(" for {} s", options.duration_s) : "",
               options.count ? fmt::format(", at most {} packets", options.count) : "");

  sf::app::RepeatingTimer status(io, status_period, [&] { log_status("status"); });
  boost::asio::steady_timer deadline(io);
  if (options.duration_s > 0.0) {
    deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(options.duration_s)));
    deadline.async_wait([&](const boost::system::error_code& e) {
      if (!e) stop();
    });
  }
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: closing {} and stopping", signal, options.output);
    by_signal = true;
    stop();
  });
  io.run();
  receiver.stop();

  if (recorder.failed()) {
    spdlog::error("{}; the {} packets before it are in the file", writer->error(),
                  recorder.recorded());
    writer->close(options.index);
    return 1;
  }
  if (!writer->close(options.index)) {
    spdlog::error("{}", writer->error());
    return 1;
  }
  log_status(by_signal ? "stopped" : "done");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-record", [&] {
    RecordOptions o;
    po::options_description general("Options");
    sf::app::add_vision_options(general, o.network);
    // clang-format off
    general.add_options()
        ("output,o", po::value(&o.output)->value_name("FILE"),
         "log file to write: FILE.log, or FILE.log.gz for gzip-compressed")
        ("overwrite", po::bool_switch(&o.overwrite), "replace --output if it exists")
        ("duration", po::value(&o.duration_s)->default_value(o.duration_s),
         "seconds to record, then stop; 0 = until SIGINT/SIGTERM")
        ("count", po::value(&o.count)->default_value(o.count),
         "vision packets to record, then stop; 0 = no limit")
        ("index", po::bool_switch(&o.index),
         "end the file with an index message (as ssl-go-tools' indexer writes it)")
        ("receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
         "SO_RCVBUF to request, bytes")
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr (recorded, bytes, skipped, kernel drops)")
        ("verbose", po::bool_switch(&o.verbose), "more logging");
    // clang-format on
    if (!sf::app::parse_command_line(
            argc, argv, general, "ssl-record --output FILE [options]",
            "Records a live SSL-Vision multicast feed into an official SSL log file (type-4 "
            "messages,\nreceive time = Unix time in ns). Datagrams that are not SSL_WrapperPacket "
            "are counted, not recorded.\nSIGINT/SIGTERM, --duration or --count end it with a "
            "complete file.")) {
      return 0;
    }
    sf::app::init_logging("ssl-record", o.verbose);
    return run_record(o);
  });
}
