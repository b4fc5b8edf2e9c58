#pragma once
// The match's event stream (match/match_event.hpp) from the network: the vision group, the
// referee group and the trackers' group, each a receiver on one io_context, handed on in the
// order they arrive, stamped with the receiver's clock. What the daemons consume; a log file
// (files/log_events.hpp) and the simulations produce the same stream.
//
//   net::LiveMatchEvents events(io, feeds, clock);
//   events.start(sink);  // sink.on_event(...) runs on the io_context's thread

#include <boost/asio/io_context.hpp>
#include <functional>
#include <optional>

#include "ssl_formation/match/match_event.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/net/vision_receiver.hpp"

namespace ssl_formation::net {

struct LiveFeeds {
  MulticastEndpoint vision;
  std::optional<MulticastEndpoint> referee;  // none: no referee feed
  std::optional<MulticastEndpoint> tracker;  // none: no tracked vision
  InterfaceChoice interface;
  int receive_buffer_bytes = kDefaultReceiveBufferBytes;
};

class LiveMatchEvents {
 public:
  // `clock`: the receive time of each event in seconds (a steady clock).
  LiveMatchEvents(boost::asio::io_context& io, const LiveFeeds& feeds,
                  std::function<double()> clock);
  LiveMatchEvents(const LiveMatchEvents&) = delete;
  LiveMatchEvents& operator=(const LiveMatchEvents&) = delete;

  // Opens, binds and joins every group, then hands each datagram to `sink` as an event. Throws
  // MulticastError naming the group that failed (the others are stopped again).
  void start(MatchEventSink& sink);
  void stop();

  const LiveFeeds& feeds() const { return feeds_; }
  const VisionReceiver& vision() const { return vision_; }
  const MulticastReceiver* referee() const { return referee_ ? &*referee_ : nullptr; }
  const MulticastReceiver* tracker() const { return tracker_ ? &*tracker_ : nullptr; }

 private:
  LiveFeeds feeds_;
  std::function<double()> clock_;
  VisionReceiver vision_;
  std::optional<MulticastReceiver> referee_;
  std::optional<MulticastReceiver> tracker_;
};

}  // namespace ssl_formation::net
