// e2e_bench load: a high rate of 4-camera packets for the daemons to keep up with.
#include "e2e_modes.hpp"

namespace e2e {

int run_load(const LoadOptions& o) {
  if (!(o.rate > 0 && o.rate <= 200000)) throw sf::app::UsageError("--rate must be 0 to 200000");
  if (!(o.seconds > 0 && o.seconds <= 60)) throw sf::app::UsageError("--seconds must be 0 to 60");
  if (!(o.frame_dt_s > 0)) throw sf::app::UsageError("--frame-dt must be positive");
  const auto interface = interface_option(o.interface);
  const auto total = static_cast<std::size_t>(std::llround(o.rate * o.seconds));

  // Every packet is built and serialised before the clock starts: the sender only sends.
  sf::simulation::SimulationConfig simulation;
  simulation.seed = o.seed;
  simulation.step_s = o.frame_dt_s;
  simulation.start_time_s = o.start_time_s;
  simulation.cameras = o.cameras;
  // A geometry packet about every 3 s of wall time, as SSL-Vision does.
  simulation.geometry_interval_s = 3.0 * o.rate / o.cameras * o.frame_dt_s;
  sf::simulation::SimulatedVision vision(simulation);
  std::vector<std::vector<std::string>> frames;  // the packets of one instant, sent together
  std::size_t packets = 0;
  std::size_t detection_packets = 0;
  std::size_t complete_frames = 0;  // with a packet from every camera: each completes a formation
  std::uint32_t frame_number = 0;
  while (packets < total) {
    std::vector<std::string> burst;
    ++frame_number;
    int cameras_in_burst = 0;
    for (SSL_WrapperPacket& packet : vision.next().packets) {
      if (packets == total) break;  // exactly `total` packets: the last frame may be cut short
      if (packet.has_detection()) {
        packet.mutable_detection()->set_frame_number(frame_number);
        ++detection_packets;
        ++cameras_in_burst;
      }
      burst.push_back(packet.SerializeAsString());
      ++packets;
    }
    if (cameras_in_burst == o.cameras) ++complete_frames;
    frames.push_back(std::move(burst));
  }

  boost::asio::io_context io;
  sf::net::MulticastSender sender(io, group_option("vision-address", o.vision_address),
                                  interface.address);
  sender.open();
  tighten_timer_slack();
  // Bursts of one frame (one packet per camera) on a fixed schedule with absolute deadlines, so
  // a late wake-up is caught up, not carried forward.
  const double frame_period_ns = 1e9 * o.seconds / static_cast<double>(frames.size());
  const std::int64_t start = now_ns() + 50'000'000;
  std::int64_t worst_lag_ns = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const std::int64_t due =
        start + static_cast<std::int64_t>(static_cast<double>(f) * frame_period_ns);
    wait_until(due, 0);
    worst_lag_ns = std::max(worst_lag_ns, now_ns() - due);
    for (const std::string& packet : frames[f]) sender.send(bytes_of(packet));
  }
  const double elapsed_s = static_cast<double>(now_ns() - start) / 1e9;
  std::printf(
      "load sent=%llu send_errors=%llu detection_packets=%zu frames=%zu complete_frames=%zu "
      "cameras=%d seconds=%.3f achieved_pps=%.0f worst_lag_us=%.1f\n",
      static_cast<unsigned long long>(sender.sent()),
      static_cast<unsigned long long>(sender.send_errors()), detection_packets, frames.size(),
      complete_frames, o.cameras, elapsed_s, static_cast<double>(sender.sent()) / elapsed_s,
      static_cast<double>(worst_lag_ns) / 1000.0);
  std::fflush(stdout);
  return sender.send_errors() == 0 ? 0 : 1;
}

}  // namespace e2e
