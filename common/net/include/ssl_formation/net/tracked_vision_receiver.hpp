#pragma once
// --vision-source tracked: receives a tracker's group (TrackerWrapperPacket, 224.5.23.2:10010)
// and hands on the followed tracker's frames as VisionFrames (TrackedVision), logging which
// tracker is followed and when another takes over.
//
//   net::TrackedVisionReceiver tracked(io, group, iface);
//   tracked.start([&](const VisionFrame& frame) { ... });

#include <functional>

#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/match/tracked_vision.hpp"

namespace ssl_formation::net {

class TrackedVisionReceiver {
 public:
  // frame is valid only during the call.
  using FrameHandler = std::function<void(const VisionFrame& frame)>;

  TrackedVisionReceiver(boost::asio::io_context& io, MulticastEndpoint endpoint,
                        InterfaceChoice interface = {},
                        int receive_buffer_bytes = kDefaultReceiveBufferBytes);

  // Opens, binds, joins and starts receiving; throws MulticastError on failure.
  void start(FrameHandler on_frame);
  void stop() { receiver_.stop(); }

  const TrackedVision& tracked() const { return tracked_; }
  const MulticastReceiver& bytes_receiver() const { return receiver_; }

 private:
  FrameHandler on_frame_;
  TrackedVision tracked_;
  VisionFrame frame_;  // reused
  // Declared last so it is destroyed (and stopped) first: no callback sees a dead member.
  MulticastReceiver receiver_;
};

}  // namespace ssl_formation::net
