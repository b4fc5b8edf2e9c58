// The field view server in-process, on 127.0.0.1 with a kernel-picked port: pages, bad requests,
// the client limit, and live views that read slowly, never, or vanish mid-frame.

#include "field_view_server.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <cstdio>
#include <future>
#include <thread>

#include "raw_client.hpp"

namespace ssl_formation::predictor::web {
namespace {

using namespace std::chrono_literals;
using web_testing::http_request;
using web_testing::RawClient;
namespace asio = boost::asio;
namespace beast = boost::beast;

// The server on an io_context thread of its own, as in the daemon.
class RunningServer {
 public:
  explicit RunningServer(FieldViewOptions options = {})
      : guard_(io_.get_executor()), server_(io_, options) {
    server_.start();
    thread_ = std::thread([this] { io_.run(); });
  }
  // Runs `f` on the io thread and returns its result.
  template <class F>
  auto on_io(F f) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto result = task.get_future();
    asio::post(io_, [&task] { task(); });
    return result.get();
  }

  ~RunningServer() {
    on_io([this] { server_.stop(); });
    guard_.reset();
    io_.stop();
    thread_.join();
  }

  std::uint16_t port() const { return server_.port(); }
  FieldViewCounters counters() {
    return on_io([this] { return server_.counters(); });
  }
  void broadcast(MessageKind kind, std::string text) {
    on_io([&] { server_.broadcast(kind, std::move(text)); });
  }
  FieldViewServer& server() { return server_; }

  // Waits until `condition(counters())` holds.
  template <class Condition>
  bool wait_for(Condition condition, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (condition(counters())) return true;
      std::this_thread::sleep_for(10ms);
    }
    return condition(counters());
  }

 private:
  asio::io_context io_;
  asio::executor_work_guard<asio::io_context::executor_type> guard_;
  FieldViewServer server_;
  std::thread thread_;
};

// A well-behaved live view: a Beast WebSocket client reading on a thread of its own.
class LiveViewClient {
 public:
  explicit LiveViewClient(std::uint16_t port) : ws_(io_) {
    auto& socket = ws_.next_layer();
    socket.connect({asio::ip::make_address("127.0.0.1"), port});
    timeval timeout{5, 0};
    ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    ws_.handshake("127.0.0.1", "/ws");
    thread_ = std::thread([this] {
      beast::flat_buffer buffer;
      beast::error_code ec;
      while (!ec) {
        ws_.read(buffer, ec);
        if (ec) break;
        std::lock_guard lock(mutex_);
        messages_.push_back(beast::buffers_to_string(buffer.data()));
        buffer.clear();
      }
    });
  }
  ~LiveViewClient() {
    beast::error_code ignored;
    ws_.next_layer().shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
    thread_.join();
  }
  std::vector<std::string> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  bool wait_for_message(const std::string& text, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      {
        std::lock_guard lock(mutex_);
        for (const auto& m : messages_) {
          if (m == text) return true;
        }
      }
      std::this_thread::sleep_for(5ms);
    }
    return false;
  }

 private:
  asio::io_context io_;
  beast::websocket::stream<asio::ip::tcp::socket> ws_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<std::string> messages_;
};

TEST(FieldViewServer, ServesThePageAndItsAssetsBuiltIn) {
  RunningServer server;
  ASSERT_NE(server.port(), 0);
  EXPECT_EQ(server.server().url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/");

  const std::string page = http_request(server.port(), "GET", "/");
  EXPECT_TRUE(page.starts_with("HTTP/1.1 200 OK")) << page.substr(0, 200);
  EXPECT_NE(page.find("Content-Type: text/html; charset=utf-8"), std::string::npos);
  EXPECT_NE(page.find("<svg id=\"field\""), std::string::npos);
  EXPECT_NE(page.find("<script src=\"field.js\"></script>"), std::string::npos);
  // Nothing from elsewhere: no CDN, no web fonts.
  EXPECT_EQ(page.find("https://"), std::string::npos);

  const std::string script = http_request(server.port(), "GET", "/field.js?v=1");
  EXPECT_TRUE(script.starts_with("HTTP/1.1 200 OK"));
  EXPECT_NE(script.find("Content-Type: text/javascript"), std::string::npos);
  EXPECT_NE(script.find("new WebSocket("), std::string::npos);
  EXPECT_NE(http_request(server.port(), "GET", "/style.css").find("Content-Type: text/css"),
            std::string::npos);

  const std::string head = http_request(server.port(), "HEAD", "/index.html");
  EXPECT_TRUE(head.starts_with("HTTP/1.1 200 OK"));
  EXPECT_EQ(head.find("<svg"), std::string::npos);
  EXPECT_NE(head.find("Content-Length: " + std::to_string(page.size() - page.find("\r\n\r\n") - 4)),
            std::string::npos);

  EXPECT_TRUE(http_request(server.port(), "GET", "/secret").starts_with("HTTP/1.1 404"));
  EXPECT_TRUE(http_request(server.port(), "GET", "/../../etc/passwd").starts_with("HTTP/1.1 404"));
  EXPECT_TRUE(http_request(server.port(), "POST", "/").starts_with("HTTP/1.1 405"));
}

TEST(FieldViewServer, KeepAliveServesSeveralRequestsOnOneConnection) {
  RunningServer server;
  RawClient client(server.port());
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(client.send("GET /style.css HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
    const std::string response = client.read_until("--grass", 5s);
    EXPECT_TRUE(response.starts_with("HTTP/1.1 200 OK")) << i;
  }
}

TEST(FieldViewServer, RefusesOversizedAndMalformedRequestsAndGoesOn) {
  FieldViewOptions options;
  options.max_request_bytes = 4096;
  RunningServer server(options);
  {
    RawClient client(server.port());
    client.send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Padding: " + std::string(20000, 'a') +
                "\r\n\r\n");
    const std::string response = client.read_to_close(5s);
    EXPECT_TRUE(response.empty() || response.starts_with("HTTP/1.1 400"))
        << response.substr(0, 100);
  }
  {
    RawClient client(server.port());
    client.send("NOT HTTP AT ALL\r\n\r\n");
    EXPECT_TRUE(client.read_to_close(5s).starts_with("HTTP/1.1 400"));
  }
  EXPECT_TRUE(server.wait_for(
      [](const FieldViewCounters& c) { return c.bad_requests == 2 && c.connections == 0; }, 5s));
  EXPECT_TRUE(http_request(server.port(), "GET", "/").starts_with("HTTP/1.1 200 OK"));
}

TEST(FieldViewServer, ClosesARequestThatNeverEnds) {
  FieldViewOptions options;
  options.request_timeout = 300ms;
  RunningServer server(options);
  RawClient client(server.port());
  client.send("GET / HT");  // and then nothing
  const auto start = std::chrono::steady_clock::now();
  client.read_to_close(5s);
  EXPECT_TRUE(client.peer_closed());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 3s);
  EXPECT_TRUE(server.wait_for([](const FieldViewCounters& c) { return c.connections == 0; }, 2s));
}

TEST(FieldViewServer, TurnsAwayConnectionsBeyondTheLimit) {
  FieldViewOptions options;
  options.max_clients = 3;
  RunningServer server(options);
  std::vector<std::unique_ptr<RawClient>> idle;
  for (int i = 0; i < 3; ++i) idle.push_back(std::make_unique<RawClient>(server.port()));
  ASSERT_TRUE(server.wait_for([](const FieldViewCounters& c) { return c.connections == 3; }, 2s));
  {
    RawClient extra(server.port());
    EXPECT_TRUE(extra.read_to_close(5s).starts_with("HTTP/1.1 503"));
  }
  EXPECT_EQ(server.counters().refused, 1u);
  idle.pop_back();
  ASSERT_TRUE(server.wait_for([](const FieldViewCounters& c) { return c.connections == 2; }, 2s));
  EXPECT_TRUE(http_request(server.port(), "GET", "/").starts_with("HTTP/1.1 200 OK"));
}

TEST(FieldViewServer, ANewViewGetsTheLatestMessagesThenEveryBroadcast) {
  RunningServer server;
  server.broadcast(MessageKind::status, R"({"type":"status","n":1})");
  server.broadcast(MessageKind::prediction, R"({"type":"prediction","n":1})");
  server.broadcast(MessageKind::status, R"({"type":"status","n":2})");
  LiveViewClient view(server.port());
  ASSERT_TRUE(view.wait_for_message(R"({"type":"prediction","n":1})", 5s));
  server.broadcast(MessageKind::prediction, R"({"type":"prediction","n":2})");
  ASSERT_TRUE(view.wait_for_message(R"({"type":"prediction","n":2})", 5s));
  const auto messages = view.messages();
  ASSERT_EQ(messages.size(), 3u);
  EXPECT_EQ(messages[0], R"({"type":"status","n":2})");
  EXPECT_EQ(server.counters().live_clients, 1u);
}

TEST(FieldViewServer, AClientThatNeverReadsIsBoundedThenClosedAndOthersKeepUp) {
  FieldViewOptions options;
  options.send_buffer_bytes = 4096;
  options.queue_limit = 4;
  options.write_timeout = 500ms;
  RunningServer server(options);
  RawClient stuck(server.port(), 4096);
  ASSERT_TRUE(stuck.upgrade_without_reading());
  LiveViewClient view(server.port());
  ASSERT_TRUE(server.wait_for([](const FieldViewCounters& c) { return c.live_clients == 2; }, 5s));

  // 300 messages of 64 KiB: far more than the stuck client's buffers hold.
  const auto start = std::chrono::steady_clock::now();
  std::string last;
  for (int i = 0; i < 300; ++i) {
    std::string text = std::to_string(i) + ":" + std::string(65536, 'x');
    if (i == 299) last = text;
    server.broadcast(MessageKind::prediction, std::move(text));
  }
  const auto broadcasting = std::chrono::steady_clock::now() - start;
  EXPECT_LT(broadcasting, 1s) << "broadcast must never wait for a client";
  EXPECT_TRUE(view.wait_for_message(last, 10s))
      << "the reading client still gets the newest message";
  // The stuck client's queue stayed bounded (frames dropped), and it was closed for stalling.
  EXPECT_TRUE(server.wait_for(
      [](const FieldViewCounters& c) { return c.stalled_clients == 1 && c.live_clients == 1; }, 5s))
      << "live=" << server.counters().live_clients
      << " stalled=" << server.counters().stalled_clients;
  EXPECT_GT(server.counters().dropped_frames, 250u);
}

TEST(FieldViewServer, ClientsThatVanishMidFrameAreForgotten) {
  RunningServer server;
  {
    // Half a WebSocket frame header, then gone.
    RawClient half_frame(server.port());
    ASSERT_TRUE(half_frame.upgrade());
    half_frame.send(std::string("\x81\xfe\x10", 3));
  }
  {
    // Reset while the server is writing to it.
    RawClient reset(server.port(), 4096);
    ASSERT_TRUE(reset.upgrade());
    for (int i = 0; i < 20; ++i)
      server.broadcast(MessageKind::prediction, std::string(100000, 'y'));
    reset.reset();
  }
  {
    // Half an HTTP request, then gone.
    RawClient half_request(server.port());
    half_request.send("GET /ind");
  }
  EXPECT_TRUE(server.wait_for(
      [](const FieldViewCounters& c) { return c.connections == 0 && c.live_clients == 0; }, 5s))
      << "connections=" << server.counters().connections;
  server.broadcast(MessageKind::prediction, "after");
  LiveViewClient view(server.port());
  EXPECT_TRUE(view.wait_for_message("after", 5s));
}

std::string fmt_message(int i) {
  char text[16];
  std::snprintf(text, sizeof text, "p%d", i);
  return text;
}

TEST(FieldViewServer, FiftyViewsAtOnceEachGetEveryMessage) {
  RunningServer server;
  std::vector<std::unique_ptr<LiveViewClient>> views;
  for (int i = 0; i < 50; ++i) views.push_back(std::make_unique<LiveViewClient>(server.port()));
  ASSERT_TRUE(server.wait_for([](const FieldViewCounters& c) { return c.live_clients == 50; }, 5s));
  for (int i = 0; i < 20; ++i) {
    server.broadcast(MessageKind::prediction, fmt_message(i));
    std::this_thread::sleep_for(2ms);  // the predictor's pace, not a wait: none may be dropped
  }
  for (auto& view : views) EXPECT_TRUE(view->wait_for_message("p19", 5s));
  EXPECT_EQ(server.counters().dropped_frames, 0u);
}

TEST(FieldViewServer, ReportsAPortInUse) {
  RunningServer first;
  boost::asio::io_context io;
  FieldViewOptions options;
  options.port = first.port();
  FieldViewServer second(io, options);
  try {
    second.start();
    FAIL() << "a second server on the same port must not start";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("127.0.0.1:" + std::to_string(first.port())),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--http-port"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ssl_formation::predictor::web
