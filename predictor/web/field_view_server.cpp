#include "field_view_server.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <deque>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "web_assets.hpp"

namespace ssl_formation::predictor::web {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;
using SharedText = std::shared_ptr<const std::string>;

class LiveSession;

// The server's state, shared with every connection so that a connection that outlives the
// server (its handler still queued in the io_context) never touches freed memory.
class FieldViewHub : public std::enable_shared_from_this<FieldViewHub> {
 public:
  FieldViewHub(asio::io_context& io, FieldViewOptions options)
      : io_(io), options_(std::move(options)), acceptor_(io), retry_(io), watchdog_(io) {}

  void start();
  void stop();
  void broadcast(MessageKind kind, std::string json);
  // A live view's handshake is done: counts it in, runs the joined handler, and sends it what it
  // has not been sent yet of the latest messages.
  void join(const std::shared_ptr<LiveSession>& session);
  void on_joined(std::function<void()> handler) { on_joined_ = std::move(handler); }
  void prepare(tcp::socket& socket) const;

  const FieldViewOptions& options() const { return options_; }
  FieldViewCounters& counters() { return counters_; }
  std::uint16_t port() const { return port_; }
  bool stopped() const { return stopped_; }
  FieldViewCounters snapshot();

 private:
  void accept();
  void on_accept(const beast::error_code& ec, tcp::socket socket);
  void arm_watchdog();
  void check_stalled();
  template <class F>
  void for_each_live(F&& f);

  asio::io_context& io_;
  FieldViewOptions options_;
  tcp::acceptor acceptor_;
  asio::steady_timer retry_;
  asio::steady_timer watchdog_;
  std::vector<std::weak_ptr<LiveSession>> live_;
  SharedText latest_prediction_;
  SharedText latest_status_;
  std::function<void()> on_joined_;
  std::uint64_t status_broadcasts_ = 0;
  FieldViewCounters counters_;
  std::uint16_t port_ = 0;
  bool stopped_ = true;
};

namespace {

// Counts one open connection for as long as it lives, page load or live view.
class ConnectionSlot {
 public:
  explicit ConnectionSlot(std::shared_ptr<FieldViewHub> hub) : hub_(std::move(hub)) {
    ++hub_->counters().connections;
  }
  ConnectionSlot(ConnectionSlot&& other) noexcept = default;
  ConnectionSlot& operator=(ConnectionSlot&&) = delete;
  ~ConnectionSlot() {
    if (hub_) --hub_->counters().connections;
  }
  FieldViewHub& hub() const { return *hub_; }
  const std::shared_ptr<FieldViewHub>& shared_hub() const { return hub_; }

 private:
  std::shared_ptr<FieldViewHub> hub_;
};

std::string endpoint_text(const std::string& address, std::uint16_t port) {
  return address + ":" + std::to_string(port);
}

}  // namespace

// One live view: a WebSocket that receives the broadcasts.
class LiveSession : public std::enable_shared_from_this<LiveSession> {
 public:
  LiveSession(tcp::socket socket, ConnectionSlot slot)
      : ws_(std::move(socket)), slot_(std::move(slot)) {}

  ~LiveSession() { --slot_.hub().counters().live_clients; }

  void run(http::request<http::empty_body> request) {
    ++slot_.hub().counters().live_clients;
    const FieldViewOptions& options = slot_.hub().options();
    // The WebSocket's own timeouts replace the TCP stream's.
    beast::get_lowest_layer(ws_).expires_never();
    websocket::stream_base::timeout timeouts{};
    timeouts.handshake_timeout = options.request_timeout;
    timeouts.idle_timeout = options.idle_timeout;
    timeouts.keep_alive_pings = true;
    ws_.set_option(timeouts);
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& response) {
      response.set(http::field::server, "ssl-predictor");
    }));
    ws_.read_message_max(options.max_client_message_bytes);
    ws_.text(true);
    ws_.async_accept(request, [self = shared_from_this()](const beast::error_code& ec) {
      if (ec) return;  // a failed handshake: nothing was registered, the session just ends
      self->open_ = true;
      self->slot_.hub().join(self);
      self->read();
    });
  }

  void send(const SharedText& text, MessageKind kind) {
    if (!open_) return;
    // The front message is being written while `writing_`: never touch it.
    const std::size_t first_free = writing_ ? 1 : 0;
    if (kind == MessageKind::status) {
      for (std::size_t i = first_free; i < queue_.size(); ++i) {
        if (queue_[i].kind == MessageKind::status) {
          queue_[i].text = text;  // the newer status supersedes the queued one
          return;
        }
      }
    }
    const std::size_t limit = std::max<std::size_t>(slot_.hub().options().queue_limit, 2);
    if (queue_.size() >= limit) {
      // Drop the oldest waiting prediction (or, failing that, the oldest waiting message).
      auto victim =
          std::find_if(queue_.begin() + static_cast<std::ptrdiff_t>(first_free), queue_.end(),
                       [](const Outgoing& o) { return o.kind == MessageKind::prediction; });
      if (victim == queue_.end()) victim = queue_.begin() + static_cast<std::ptrdiff_t>(first_free);
      queue_.erase(victim);
      ++slot_.hub().counters().dropped_frames;
    }
    queue_.push_back(Outgoing{text, kind});
    if (!writing_) write_next();
  }

  // Closes the connection if a write has been pending longer than `limit`.
  void close_if_stalled(Clock::time_point now, Clock::duration limit) {
    if (writing_ && now - write_started_ > limit) {
      ++slot_.hub().counters().stalled_clients;
      abort();
    }
  }

  void abort() {
    open_ = false;
    queue_.clear();
    writing_ = false;
    beast::get_lowest_layer(ws_).close();  // cancels the pending read and write
  }

 private:
  struct Outgoing {
    SharedText text;
    MessageKind kind;
  };

  void read() {
    // The page sends nothing we need; reading keeps pongs and the close handshake working.
    ws_.async_read(read_buffer_,
                   [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                     if (ec) {
                       self->open_ = false;
                       self->queue_.clear();
                       return;
                     }
                     self->read_buffer_.clear();
                     self->read();
                   });
  }

  void write_next() {
    writing_ = true;
    write_started_ = Clock::now();
    // The shared text stays alive in queue_.front() until the write completes.
    ws_.async_write(asio::buffer(*queue_.front().text),
                    [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                      self->on_write(ec);
                    });
  }

  void on_write(const beast::error_code& ec) {
    if (!writing_) return;  // aborted meanwhile
    writing_ = false;
    if (ec) {
      open_ = false;
      queue_.clear();
      return;
    }
    queue_.pop_front();
    if (open_ && !queue_.empty()) write_next();
  }

  websocket::stream<beast::tcp_stream> ws_;
  ConnectionSlot slot_;
  beast::flat_buffer read_buffer_;
  std::deque<Outgoing> queue_;
  bool writing_ = false;
  bool open_ = false;
  Clock::time_point write_started_;
};

namespace {

// One HTTP connection: serves the page and its assets, or hands the socket to a LiveSession on
// a WebSocket upgrade of /ws.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, ConnectionSlot slot)
      : stream_(std::move(socket)),
        slot_(std::move(slot)),
        buffer_(slot_.hub().options().max_request_bytes) {}

  void run() { read(); }

 private:
  void read() {
    const FieldViewOptions& options = slot_.hub().options();
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(options.max_request_bytes));
    parser_->body_limit(0);
    stream_.expires_after(options.request_timeout);
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                       self->on_read(ec);
                     });
  }

  void on_read(const beast::error_code& ec) {
    if (ec == http::error::end_of_stream || ec == asio::error::eof) {
      beast::error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
      return;
    }
    if (ec) {
      // Oversized, malformed or too slow: answer if the request was HTTP at all, then close.
      if (ec == beast::error::timeout ||
          ec.category() == beast::error_code(http::error::header_limit).category() ||
          ec == http::error::buffer_overflow) {
        ++slot_.hub().counters().bad_requests;
        if (ec != beast::error::timeout) {
          respond(http::status::bad_request, "text/plain; charset=utf-8", "bad request\n", false,
                  11);
        }
      }
      return;
    }
    http::request<http::empty_body>& request = parser_->get();
    if (websocket::is_upgrade(request)) {
      const std::string_view target(request.target().data(), request.target().size());
      if (target == "/ws" || target.starts_with("/ws?")) {
        std::make_shared<LiveSession>(stream_.release_socket(), std::move(slot_))
            ->run(parser_->release());
        return;
      }
      respond(http::status::not_found, "text/plain; charset=utf-8", "not found\n", false, 11);
      return;
    }
    const bool keep_alive = request.keep_alive();
    version_ = request.version();
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      respond(http::status::method_not_allowed, "text/plain; charset=utf-8", "only GET\n",
              keep_alive, 11);
      return;
    }
    const WebAsset* asset =
        find_web_asset(std::string_view(request.target().data(), request.target().size()));
    if (!asset) {
      respond(http::status::not_found, "text/plain; charset=utf-8", "not found\n", keep_alive,
              version_);
      return;
    }
    respond(http::status::ok, asset->content_type,
            request.method() == http::verb::head ? "" : asset->body, keep_alive, version_,
            asset->body.size());
  }

  void respond(http::status status, std::string_view type, std::string_view body, bool keep_alive,
               unsigned version, std::optional<std::size_t> length = std::nullopt) {
    response_.emplace(status, version);
    response_->set(http::field::server, "ssl-predictor");
    response_->set(http::field::content_type, beast::string_view(type.data(), type.size()));
    response_->set(http::field::cache_control, "no-cache");
    response_->set("X-Content-Type-Options", "nosniff");
    response_->set("Content-Security-Policy",
                   "default-src 'self'; connect-src 'self'; img-src 'self' data:");
    response_->body() = http::span_body<const char>::value_type(body.data(), body.size());
    response_->keep_alive(keep_alive);
    response_->content_length(length.value_or(body.size()));
    stream_.expires_after(slot_.hub().options().request_timeout);
    http::async_write(
        stream_, *response_,
        [self = shared_from_this(), keep_alive](const beast::error_code& ec, std::size_t) {
          if (ec) return;
          if (!keep_alive || self->slot_.hub().stopped()) {
            beast::error_code ignored;
            self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
            return;
          }
          self->read();
        });
  }

  beast::tcp_stream stream_;
  ConnectionSlot slot_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  std::optional<http::response<http::span_body<const char>>> response_;
  unsigned version_ = 11;
};

}  // namespace

void FieldViewHub::start() {
  beast::error_code ec;
  const auto address = asio::ip::make_address(options_.address, ec);
  if (ec) {
    throw std::runtime_error("bad --http-address '" + options_.address + "': " + ec.message());
  }
  const tcp::endpoint endpoint(address, options_.port);
  const std::string where = endpoint_text(options_.address, options_.port);
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (ec == asio::error::address_in_use && options_.any_port_if_taken) {
    spdlog::warn("the field view's port {} is taken: listening on another one", options_.port);
    ec.clear();
    acceptor_.bind(tcp::endpoint(address, 0), ec);
  }
  if (ec) {
    std::string hint;
    if (ec == asio::error::address_in_use)
      hint = "; another program uses the port: pick another --http-port";
    if (ec == boost::system::errc::address_not_available)
      hint = "; --http-address must be an address of this machine";
    if (ec == asio::error::access_denied) hint = "; ports below 1024 need root";
    acceptor_.close();
    throw std::runtime_error("cannot listen for the field view on " + where + ": " + ec.message() +
                             hint);
  }
  acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec)
    throw std::runtime_error("cannot listen for the field view on " + where + ": " + ec.message());
  port_ = acceptor_.local_endpoint().port();
  stopped_ = false;
  accept();
  arm_watchdog();
}

void FieldViewHub::stop() {
  stopped_ = true;
  beast::error_code ignored;
  acceptor_.close(ignored);
  retry_.cancel();
  watchdog_.cancel();
  for_each_live([](LiveSession& session) { session.abort(); });
  live_.clear();
}

void FieldViewHub::accept() {
  acceptor_.async_accept(
      [self = shared_from_this()](const beast::error_code& ec, tcp::socket socket) {
        self->on_accept(ec, std::move(socket));
      });
}

void FieldViewHub::on_accept(const beast::error_code& ec, tcp::socket socket) {
  if (stopped_ || ec == asio::error::operation_aborted) return;
  if (ec) {
    // Out of file descriptors or the like: log, wait a little and go on accepting.
    spdlog::warn("field view: cannot accept a connection on {}: {}",
                 endpoint_text(options_.address, port_), ec.message());
    retry_.expires_after(std::chrono::milliseconds(100));
    retry_.async_wait([self = shared_from_this()](const beast::error_code& wait_ec) {
      if (!wait_ec && !self->stopped_) self->accept();
    });
    return;
  }
  ++counters_.accepted;
  if (counters_.connections >= options_.max_clients) {
    ++counters_.refused;
    // The socket is new, so this short non-blocking write fits its send buffer.
    static constexpr std::string_view busy =
        "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nContent-Length: 17\r\n"
        "Connection: close\r\n\r\ntoo many clients\n";
    beast::error_code ignored;
    socket.non_blocking(true, ignored);
    socket.write_some(asio::buffer(busy.data(), busy.size()), ignored);
    socket.shutdown(tcp::socket::shutdown_both, ignored);
    socket.close(ignored);
  } else {
    prepare(socket);
    std::make_shared<HttpSession>(std::move(socket), ConnectionSlot(shared_from_this()))->run();
  }
  accept();
}

void FieldViewHub::prepare(tcp::socket& socket) const {
  beast::error_code ignored;
  socket.set_option(tcp::no_delay(true), ignored);
  if (options_.send_buffer_bytes > 0) {
    socket.set_option(asio::socket_base::send_buffer_size(options_.send_buffer_bytes), ignored);
  }
}

void FieldViewHub::arm_watchdog() {
  const auto period = std::clamp<Clock::duration>(
      options_.write_timeout / 4, std::chrono::milliseconds(20), std::chrono::milliseconds(500));
  watchdog_.expires_after(period);
  watchdog_.async_wait([self = shared_from_this()](const beast::error_code& ec) {
    if (ec || self->stopped_) return;
    self->check_stalled();
    self->arm_watchdog();
  });
}

void FieldViewHub::check_stalled() {
  const auto now = Clock::now();
  for_each_live(
      [&](LiveSession& session) { session.close_if_stalled(now, options_.write_timeout); });
}

template <class F>
void FieldViewHub::for_each_live(F&& f) {
  std::erase_if(live_, [](const std::weak_ptr<LiveSession>& w) { return w.expired(); });
  // Copies, so that `f` may close sessions (and so shrink live_) safely.
  std::vector<std::shared_ptr<LiveSession>> sessions;
  sessions.reserve(live_.size());
  for (const auto& weak : live_) {
    if (auto session = weak.lock()) sessions.push_back(std::move(session));
  }
  for (const auto& session : sessions) f(*session);
}

void FieldViewHub::join(const std::shared_ptr<LiveSession>& session) {
  live_.push_back(session);
  const std::uint64_t statuses_before = status_broadcasts_;
  if (on_joined_) on_joined_();
  // A status the handler broadcast has reached this session already.
  if (status_broadcasts_ == statuses_before && latest_status_) {
    session->send(latest_status_, MessageKind::status);
  }
  if (latest_prediction_) session->send(latest_prediction_, MessageKind::prediction);
}

void FieldViewHub::broadcast(MessageKind kind, std::string json) {
  if (stopped_) return;
  ++counters_.broadcasts;
  auto text = std::make_shared<const std::string>(std::move(json));
  (kind == MessageKind::prediction ? latest_prediction_ : latest_status_) = text;
  if (kind == MessageKind::status) ++status_broadcasts_;
  for (auto it = live_.begin(); it != live_.end();) {
    if (auto session = it->lock()) {
      session->send(text, kind);
      ++it;
    } else {
      it = live_.erase(it);
    }
  }
}

FieldViewCounters FieldViewHub::snapshot() { return counters_; }

FieldViewServer::FieldViewServer(asio::io_context& io, FieldViewOptions options)
    : hub_(std::make_shared<FieldViewHub>(io, std::move(options))) {}

FieldViewServer::~FieldViewServer() {
  // stop() cancels timers, whose cancel() throws on failure, and allocates a list of the live
  // sessions; an exception leaving a destructor ends the program. Whatever stop() did not close
  // is closed by the destructors of the sockets and timers, which never throw.
  try {
    hub_->stop();
  } catch (const std::exception& e) {
    spdlog::warn("field view: stopping the server: {}", e.what());
  } catch (...) {
    spdlog::warn("field view: stopping the server failed");
  }
}

void FieldViewServer::start() { hub_->start(); }
void FieldViewServer::stop() { hub_->stop(); }
void FieldViewServer::broadcast(MessageKind kind, std::string json) {
  hub_->broadcast(kind, std::move(json));
}
void FieldViewServer::on_viewer_joined(std::function<void()> handler) {
  hub_->on_joined(std::move(handler));
}
std::uint16_t FieldViewServer::port() const { return hub_->port(); }
std::string FieldViewServer::url() const {
  const std::string& address = hub_->options().address;
  const bool v6 = address.find(':') != std::string::npos;
  return "http://" + (v6 ? "[" + address + "]" : address) + ":" + std::to_string(hub_->port()) +
         "/";
}
FieldViewCounters FieldViewServer::counters() const { return hub_->snapshot(); }

}  // namespace ssl_formation::predictor::web
