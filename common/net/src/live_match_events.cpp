#include "ssl_formation/net/live_match_events.hpp"

namespace ssl_formation::net {

LiveMatchEvents::LiveMatchEvents(boost::asio::io_context& io, const LiveFeeds& feeds,
                                 std::function<double()> clock)
    : feeds_(feeds),
      clock_(std::move(clock)),
      vision_(io, feeds.vision, feeds.interface, feeds.receive_buffer_bytes) {
  if (feeds_.referee) {
    referee_.emplace(io, *feeds_.referee, feeds_.interface, feeds_.receive_buffer_bytes);
  }
  if (feeds_.tracker) {
    tracker_.emplace(io, *feeds_.tracker, feeds_.interface, feeds_.receive_buffer_bytes);
  }
}

void LiveMatchEvents::start(MatchEventSink& sink) {
  try {
    vision_.start([this, &sink](const VisionFrame& frame, const udp::endpoint&) {
      sink.on_event(MatchEvent::vision(frame, clock_()));
    });
    if (tracker_) {
      tracker_->start([this, &sink](std::span<const std::byte> datagram, const udp::endpoint&) {
        sink.on_event(MatchEvent::tracked_vision(as_text(datagram), clock_()));
      });
    }
    // The referee on the same thread as the vision: each command applies from the next frame.
    if (referee_) {
      referee_->start([this, &sink](std::span<const std::byte> datagram, const udp::endpoint&) {
        sink.on_event(MatchEvent::referee(as_text(datagram), clock_()));
      });
    }
  } catch (...) {
    stop();
    throw;
  }
}

void LiveMatchEvents::stop() {
  vision_.stop();
  if (tracker_) tracker_->stop();
  if (referee_) referee_->stop();
}

}  // namespace ssl_formation::net
