#include "ssl_formation/net/proto_multicast.hpp"

#include <spdlog/spdlog.h>

namespace ssl_formation::net::detail {

void log_parse_error(const MulticastReceiver& receiver, const std::string& type_name,
                     std::size_t size) {
  const auto errors = receiver.counters().parse_errors.load(std::memory_order_relaxed);
  if (errors <= 10 || errors % 1000 == 0) {
    spdlog::warn("multicast receiver {}: a {} byte datagram is not a valid {}; skipped (error {})",
                 receiver.endpoint().to_string(), size, type_name, errors);
  }
}

void log_encode_error(const MulticastSender& sender, const std::string& type_name, std::size_t size,
                      std::uint64_t errors) {
  if (errors <= 10 || errors % 1000 == 0) {
    spdlog::warn(
        "cannot encode a {} for {}: {} (error {})", type_name, sender.endpoint().to_string(),
        size > kMaxUdpPayload ? std::to_string(size) + " bytes do not fit in one datagram (max " +
                                    std::to_string(kMaxUdpPayload) + ")"
                              : std::string("a required field is missing"),
        errors);
  }
}

}  // namespace ssl_formation::net::detail
