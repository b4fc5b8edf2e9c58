#pragma once
// Plain blocking TCP clients for the field view tests, with time limits on every wait: what a
// browser does (HTTP requests, the WebSocket handshake) and what a bad client does (never read,
// stop half way, vanish).

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

namespace ssl_formation::web_testing {

class RawClient {
 public:
  // Connects to 127.0.0.1:port; receive_buffer > 0 shrinks SO_RCVBUF before connecting.
  explicit RawClient(std::uint16_t port, int receive_buffer = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (receive_buffer > 0)
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    timeval timeout{5, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(port);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  }
  ~RawClient() { close(); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;

  bool connected() const { return connected_; }
  int fd() const { return fd_; }

  bool send(std::string_view bytes) {
    while (!bytes.empty()) {
      const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
      if (n <= 0) return false;
      bytes.remove_prefix(static_cast<std::size_t>(n));
    }
    return true;
  }

  // Reads until `until` appears, the peer closes, or `timeout` passes.
  std::string read_until(std::string_view until, std::chrono::milliseconds timeout) {
    std::string text = std::exchange(unread_, {});  // what came with the handshake's answer
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    char buffer[16384];
    while (until.empty() || text.find(until) == std::string::npos) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) break;
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n <= 0) {
        peer_closed_ = true;
        break;
      }
      text.append(buffer, static_cast<std::size_t>(n));
    }
    return text;
  }
  std::string read_to_close(std::chrono::milliseconds timeout) { return read_until("", timeout); }
  bool peer_closed() const { return peer_closed_; }

  // The WebSocket handshake for /ws; true when the server switched protocols.
  bool upgrade() {
    if (!send("GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")) {
      return false;
    }
    std::string answer = read_until("\r\n\r\n", std::chrono::seconds(5));
    // The server may send its first messages right behind the answer, in the same read.
    const std::size_t end = answer.find("\r\n\r\n");
    if (end != std::string::npos) unread_ = answer.substr(end + 4);
    return answer.starts_with("HTTP/1.1 101");
  }
  // Sends only the upgrade request and never reads anything.
  bool upgrade_without_reading() {
    return send(
        "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
  }

  // Closes with a reset (SO_LINGER 0), as a crashed client does.
  void reset() {
    linger l{1, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_LINGER, &l, sizeof l);
    close();
  }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
  bool peer_closed_ = false;
  std::string unread_;  // read past the handshake's answer, not handed out yet
};

// GET (or another method) over a fresh connection; the whole response.
inline std::string http_request(std::uint16_t port, const std::string& method,
                                const std::string& target) {
  RawClient client(port);
  if (!client.connected()) return {};
  const std::string body_header = method == "POST" ? "Content-Length: 0\r\n" : "";
  client.send(method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + body_header +
              "Connection: close\r\n\r\n");
  return client.read_to_close(std::chrono::seconds(5));
}

}  // namespace ssl_formation::web_testing
