// ssl-record: records a live vision feed into an official SSL log file. Options only: the work
// is in the recorder library (producer/src/recorder.cpp).

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/recorder/recorder.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-record", [&] {
    sf::recorder::RecordOptions o;
    po::options_description general("Options");
    // clang-format off
    general.add_options()
        ("vision-address", po::value(&o.network.vision_address)->default_value(o.network.vision_address),
         "SSL-Vision multicast group:port to record (type 4)")
        ("referee-address", po::value(&o.network.referee_address)->default_value(o.network.referee_address),
         "the game controller's referee group to record too (type 3); none: not recorded")
        ("tracker-address", po::value(&o.network.tracker_address)->default_value(o.network.tracker_address),
         "the trackers' group to record too (TrackerWrapperPacket, type 5); none: not recorded")
        ("interface", po::value(&o.network.interface)->default_value(o.network.interface),
         "IPv4 address of the interface to join on, or 'all' for every interface");
    // clang-format on
    sf::app::add_daemon_options(general, o.daemon);
    // clang-format off
    general.add_options()
        ("output,o", po::value(&o.output)->value_name("FILE"),
         "log file to write: FILE.log, or FILE.log.gz for gzip-compressed")
        ("overwrite", po::bool_switch(&o.overwrite), "replace --output if it exists")
        ("duration", po::value(&o.duration_s)->default_value(o.duration_s),
         "seconds to record, then stop; 0 = until SIGINT/SIGTERM")
        ("count", po::value(&o.count)->default_value(o.count),
         "vision packets to record, then stop; 0 = no limit")
        ("index", po::bool_switch(&o.index),
         "end the file with an index message (as ssl-go-tools' indexer writes it)")
        ("receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
         "SO_RCVBUF to request, bytes")
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr (recorded, bytes, skipped, kernel drops)")
        ("verbose", po::bool_switch(&o.verbose), "more logging");
    // clang-format on
    if (!sf::app::parse_command_line(
            argc, argv, general, "ssl-record --output FILE [options]",
            "Records a live SSL-Vision multicast feed, the referee and the trackers into an official "
            "SSL log file\n(types 4, 3 and 5 in the order received, receive time = Unix time in "
            "ns). Datagrams that are not\nwhat their group carries are counted, not recorded. "
            "SIGINT/SIGTERM, --duration or --count\n(vision packets) end it with a complete "
            "file.")) {
      return 0;
    }
    sf::app::init_logging("ssl-record", o.verbose);
    return sf::recorder::run_record(o);
  });
}
