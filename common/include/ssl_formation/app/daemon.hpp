#pragma once
// What the three daemons share around the core: logging, parsing the network options into
// endpoints, clean shutdown on SIGINT/SIGTERM through Asio's signal_set (no work inside a signal
// handler), and repeating timers.

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <functional>
#include <string>

#include "ssl_formation/net/multicast.hpp"

namespace ssl_formation::app {

// All log lines go to stderr through spdlog: "[23:14:05.123] ssl-trainer info: ...".
void init_logging(const std::string& program, bool verbose = false);

// Both throw UsageError naming the option.
net::MulticastEndpoint parse_group_option(const std::string& option, const std::string& text);
net::InterfaceChoice parse_interface_option(const std::string& text, bool allow_all);

// Calls `on_stop` once on the first SIGINT or SIGTERM, from the io_context's thread. A second
// signal leaves the default behaviour to the user: the handler is not re-armed.
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
  void cancel();

 private:
  void arm();
  boost::asio::steady_timer timer_;
  std::chrono::steady_clock::duration period_;
  std::function<void()> tick_;
};

std::chrono::steady_clock::duration seconds_option(const std::string& option, double seconds);

}  // namespace ssl_formation::app
