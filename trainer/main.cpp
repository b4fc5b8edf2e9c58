// ssl-trainer: listens to the vision feed, samples the opponent's formations and counts state
// transitions into a table file that ssl-predictor reads.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "table_store.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

struct TrainerOptions {
  sf::app::ModelOptions model;
  sf::app::NetworkOptions network;
  std::string table = sf::app::default_table;
  double flush_interval_s = 10.0;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = sf::net::kDefaultReceiveBufferBytes;
  bool reset = false;
  bool verbose = false;
};

void log_status(const sf::Training& training, const sf::net::ReceiverCounters& net) {
  const sf::SamplerCounters& c = training.sampler().counters();
  spdlog::info(
      "status: packets={} parse_errors={} kernel_drops={} formations={} transitions={} "
      "table_transitions={} states_seen={} rejected_robots={} late_frames={}",
      net.datagrams.load(), net.parse_errors.load(), net.kernel_drops.load(), c.samples,
      c.transitions, training.table().transitions(), training.table().rows_seen(),
      c.robots_non_finite + c.robots_out_of_range + c.robots_bad_id, c.frames_late);
}

int run_live(const TrainerOptions& options) {
  const sf::SamplerConfig config = options.model.sampler_config();
  const auto group = sf::app::parse_group_option("vision-address", options.network.vision_address);
  const auto interface = sf::app::parse_interface_option(options.network.interface, true);
  const auto flush_period = sf::app::seconds_option("flush-interval", options.flush_interval_s);
  const auto status_period = sf::app::seconds_option("status-interval", options.status_interval_s);

  const std::filesystem::path table_path = options.table;
  std::unique_ptr<sf::Training> training = sf::trainer::open_training(table_path, config, options.reset);

  boost::asio::io_context io;
  sf::net::ProtoMulticastReceiver<SSL_WrapperPacket> receiver(io, group, interface,
                                                             options.receive_buffer_bytes);
  receiver.start([&](const SSL_WrapperPacket& packet, const sf::net::udp::endpoint&) {
    training->add(packet);
  });
  spdlog::info("listening on {} (interface {}, receive buffer {} bytes); opponent {} attacking {}; "
               "grid {}, step {} s; table {}",
               group.to_string(), interface.to_string(), receiver.granted_receive_buffer(),
               sf::to_string(config.opponent_color), sf::to_string(config.opponent_attacks),
               config.grid.to_string(), config.step_s, table_path.string());

  sf::app::RepeatingTimer flush(io, flush_period, [&] {
    if (training->changed_since_save()) sf::trainer::save_training(table_path, *training);
  });
  sf::app::RepeatingTimer status(io, status_period,
                                 [&] { log_status(*training, receiver.counters()); });
  bool saved_on_exit = true;
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: saving and stopping", signal);
    receiver.stop();
    flush.cancel();
    status.cancel();
    saved_on_exit = sf::trainer::save_training(table_path, *training);
    io.stop();
  });
  io.run();
  log_status(*training, receiver.counters());
  return saved_on_exit ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-trainer", [&] {
    TrainerOptions options;
    po::options_description general("Options");
    general.add_options()
        ("table", po::value(&options.table)->default_value(options.table),
         "table file to resume and save (written atomically)")
        ("reset", po::bool_switch(&options.reset),
         "start an empty table even if --table holds one of another grid or step")
        ("flush-interval", po::value(&options.flush_interval_s)->default_value(options.flush_interval_s),
         "seconds between saves of the table (it is also saved on SIGINT/SIGTERM)")
        ("status-interval", po::value(&options.status_interval_s)->default_value(options.status_interval_s),
         "seconds between status lines on stderr")
        ("receive-buffer", po::value(&options.receive_buffer_bytes)->default_value(options.receive_buffer_bytes),
         "socket receive buffer (SO_RCVBUF) to request, bytes")
        ("verbose", po::bool_switch(&options.verbose), "log every save");
    sf::app::add_vision_options(general, options.network);
    sf::app::add_model_options(general, options.model);
    if (!sf::app::parse_command_line(argc, argv, general, "ssl-trainer [options]",
                                     "Counts the opponent's formation transitions from the vision "
                                     "feed into a table file.")) {
      return 0;
    }
    sf::app::init_logging("ssl-trainer", options.verbose);
    return run_live(options);
  });
}
