#include "ssl_formation/client/predictions.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "formation_prediction.pb.h"

namespace ssl_formation::client {

namespace {

std::runtime_error failure(const std::string& what) {
  return std::runtime_error("prediction receiver: " + what + ": " + std::strerror(errno));
}

// "a.b.c.d:port" into an address and a port.
void split_group(const std::string& text, in_addr& address, std::uint16_t& port) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos) {
    throw std::runtime_error("prediction receiver: '" + text + "' is not ADDRESS:PORT");
  }
  const std::string host = text.substr(0, colon);
  const int number = std::atoi(text.c_str() + colon + 1);
  if (::inet_pton(AF_INET, host.c_str(), &address) != 1 || number <= 0 || number > 65535) {
    throw std::runtime_error("prediction receiver: '" + text + "' is not ADDRESS:PORT");
  }
  port = static_cast<std::uint16_t>(number);
}

}  // namespace

std::optional<Prediction> decode_prediction(const void* data, std::size_t size) {
  proto::FormationPrediction message;
  if (!message.ParseFromArray(data, static_cast<int>(size))) return std::nullopt;
  Prediction out;
  out.frame_number = message.frame_number();
  out.t_capture = message.t_capture();
  out.model = message.model();
  out.game_state = message.game_state();
  out.opponent_color = message.opponent_color();
  out.grid_length = static_cast<int>(message.grid_length());
  out.grid_width = static_cast<int>(message.grid_width());
  out.step_s = message.step_seconds();
  for (const proto::PredictedStep& step : message.steps()) {
    PredictedStep s;
    s.step = static_cast<int>(step.step());
    s.horizon_s = step.has_horizon_seconds() ? step.horizon_seconds() : step.step() * out.step_s;
    s.formation_probability = step.formation_probability();
    for (const proto::PredictedRobot& robot : step.robots()) {
      PredictedRobot r;
      r.robot_id = robot.robot_id();
      const auto& at = robot.has_position() ? robot.position() : robot.cell_centre();
      r.x_mm = at.x();
      r.y_mm = at.y();
      r.has_radii = robot.has_radius_90_mm();
      r.radius_50_mm = robot.radius_50_mm();
      r.radius_90_mm = robot.radius_90_mm();
      r.probability = robot.probability();
      r.unseen = robot.unseen();
      s.robots.push_back(r);
    }
    out.steps.push_back(std::move(s));
  }
  return out;
}

PredictionReceiver::PredictionReceiver(const std::string& group, const std::string& interface)
    : buffer_(65536) {
  in_addr group_address{};
  std::uint16_t port = 0;
  split_group(group, group_address, port);
  in_addr interface_address{};
  if (::inet_pton(AF_INET, interface.c_str(), &interface_address) != 1) {
    throw std::runtime_error("prediction receiver: '" + interface + "' is not an IPv4 address");
  }
  socket_ = ::socket(AF_INET, SOCK_DGRAM, IPPROTO_UDP);
  if (socket_ < 0) throw failure("socket");
  const int yes = 1;
  ::setsockopt(socket_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  // Bound to the group, not to every address: only this group's datagrams on the port.
  sockaddr_in bound{};
  bound.sin_family = AF_INET;
  bound.sin_port = htons(port);
  bound.sin_addr = group_address;
  if (::bind(socket_, reinterpret_cast<const sockaddr*>(&bound), sizeof bound) != 0) {
    const auto error = failure("bind " + group);
    ::close(socket_);
    throw error;
  }
  ip_mreq membership{};
  membership.imr_multiaddr = group_address;
  membership.imr_interface = interface_address;
  if (::setsockopt(socket_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) != 0) {
    const auto error = failure("join " + group + " on " + interface);
    ::close(socket_);
    throw error;
  }
}

PredictionReceiver::~PredictionReceiver() {
  if (socket_ >= 0) ::close(socket_);
}

std::optional<Prediction> PredictionReceiver::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd ready{socket_, POLLIN, 0};
    const int events = ::poll(&ready, 1, static_cast<int>(std::max<long long>(0, left.count())));
    if (events < 0 && errno == EINTR) continue;
    if (events < 0) throw failure("poll");
    if (events == 0) return std::nullopt;
    const ssize_t size = ::recv(socket_, buffer_.data(), buffer_.size(), 0);
    if (size < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      throw failure("recv");
    }
    if (auto decoded = decode_prediction(buffer_.data(), static_cast<std::size_t>(size))) {
      return decoded;
    }
    ++undecodable_;
  }
}

}  // namespace ssl_formation::client
