#pragma once
// The live field view's server: HTTP for the page and its assets (built into the binary) and a
// WebSocket at /ws that pushes every message given to broadcast() to each connected page.
// Boost.Beast on the caller's io_context: no threads of its own, no blocking call.
//
// A page that reads slowly or not at all never holds up the caller: each client has a bounded
// send queue (when it is full the oldest queued prediction is dropped; a newer status replaces
// the queued one), a write that does not finish within write_timeout closes the client, and
// connections beyond max_clients are turned away.

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace ssl_formation::predictor::web {

struct FieldViewOptions {
  std::string address = "127.0.0.1";  // where to listen; loopback unless told otherwise
  std::uint16_t port = 0;             // 0: the kernel picks one (see FieldViewServer::port())
  // When `port` is taken: listen on one the kernel picks instead of failing (the default port,
  // where a second predictor on the machine should still show its view).
  bool any_port_if_taken = false;
  std::size_t max_clients = 64;          // connections at once, page loads and live views together
  std::size_t queue_limit = 8;           // messages waiting per live view
  std::size_t max_request_bytes = 8192;  // request line and headers; requests carry no body
  std::size_t max_client_message_bytes = 1024;       // what a page may send over its WebSocket
  std::chrono::milliseconds request_timeout{10000};  // to send a whole HTTP request
  std::chrono::milliseconds write_timeout{5000};     // a message not written by then: closed
  std::chrono::milliseconds idle_timeout{30000};     // no pong to our pings by then: closed
  int send_buffer_bytes = 0;  // SO_SNDBUF per connection; 0 keeps the kernel's (tests shrink it)
};

struct FieldViewCounters {
  std::uint64_t connections = 0;      // open now, page loads and live views
  std::uint64_t live_clients = 0;     // WebSocket clients now
  std::uint64_t accepted = 0;         // connections ever accepted
  std::uint64_t refused = 0;          // turned away: max_clients reached
  std::uint64_t dropped_frames = 0;   // messages dropped for slow clients
  std::uint64_t stalled_clients = 0;  // closed because a write took longer than write_timeout
  std::uint64_t bad_requests = 0;     // malformed, oversized or timed-out requests
  std::uint64_t broadcasts = 0;
};

enum class MessageKind { prediction, status };

class FieldViewHub;

class FieldViewServer {
 public:
  FieldViewServer(boost::asio::io_context& io, FieldViewOptions options);
  ~FieldViewServer();
  FieldViewServer(const FieldViewServer&) = delete;
  FieldViewServer& operator=(const FieldViewServer&) = delete;

  // Binds and starts accepting. Throws std::runtime_error naming the address and port (and the
  // likely cause) when it cannot listen.
  void start();
  // Closes the listener and every connection.
  void stop();

  // Queues `json` for every live view. A new view first receives the latest message of each
  // kind, so it draws at once.
  void broadcast(MessageKind kind, std::string json);
  // Runs `handler` each time a live view has connected, after it is counted in live_clients and
  // before it is sent the latest messages: a status broadcast from the handler reaches it first.
  void on_viewer_joined(std::function<void()> handler);

  std::uint16_t port() const;  // the port actually bound, after start()
  std::string url() const;     // "http://127.0.0.1:8080/"
  FieldViewCounters counters() const;

 private:
  std::shared_ptr<FieldViewHub> hub_;
};

}  // namespace ssl_formation::predictor::web
