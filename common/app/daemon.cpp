#include "ssl_formation/app/daemon.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <csignal>
#include <sstream>

#include "ssl_formation/app/options.hpp"

namespace ssl_formation::app {

void init_logging(const std::string& program, bool verbose) {
  auto logger = spdlog::stderr_color_mt(program);
  logger->set_pattern("[%H:%M:%S.%e] %n %l: %v");
  logger->set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
}

net::MulticastEndpoint parse_group_option(const std::string& option, const std::string& text) {
  std::string error;
  const auto endpoint = net::parse_multicast_endpoint(text, &error);
  if (!endpoint) throw UsageError("--" + option + ": " + error);
  return *endpoint;
}

net::InterfaceChoice parse_interface_option(const std::string& text, bool allow_all) {
  std::string error;
  const auto choice = net::parse_interface(text, allow_all, &error);
  if (!choice) throw UsageError("--interface: " + error);
  return *choice;
}

StopSignals::StopSignals(boost::asio::io_context& io, std::function<void(int)> on_stop)
    : signals_(io, SIGINT, SIGTERM) {
  signals_.async_wait(
      [on_stop = std::move(on_stop)](const boost::system::error_code& error, int signal) {
        if (!error) on_stop(signal);
      });
}

RepeatingTimer::RepeatingTimer(boost::asio::io_context& io,
                               std::chrono::steady_clock::duration period,
                               std::function<void()> tick)
    : timer_(io), period_(period), tick_(std::move(tick)) {
  arm();
}

void RepeatingTimer::cancel() { timer_.cancel(); }

void RepeatingTimer::arm() {
  timer_.expires_after(period_);
  timer_.async_wait([this](const boost::system::error_code& error) {
    if (error) return;  // cancelled
    tick_();
    arm();
  });
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
