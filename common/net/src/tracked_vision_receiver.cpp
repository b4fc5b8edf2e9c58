#include "ssl_formation/net/tracked_vision_receiver.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <string_view>
#include <utility>

namespace ssl_formation::net {

TrackedVisionReceiver::TrackedVisionReceiver(boost::asio::io_context& io,
                                             MulticastEndpoint endpoint, InterfaceChoice interface,
                                             int receive_buffer_bytes)
    : receiver_(io, endpoint, interface, receive_buffer_bytes) {}

void TrackedVisionReceiver::start(FrameHandler on_frame) {
  receiver_.start([this](std::span<const std::byte> data, const udp::endpoint&) {
    const double now_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    const std::string_view payload = as_text(data);
    const std::uint64_t switches = tracked_.counters().source_switches;
    const bool got = tracked_.add(payload, now_s, frame_);
    if (tracked_.take_source_change()) {
      spdlog::info("tracked vision: following tracker '{}' (uuid {}){}", tracked_.source_name(),
                   tracked_.source_uuid(),
                   tracked_.counters().source_switches > switches
                       ? ": the one followed before fell silent"
                       : "");
    }
    if (got && on_frame_) on_frame_(frame_);
  });
  on_frame_ = std::move(on_frame);
}

}  // namespace ssl_formation::net
