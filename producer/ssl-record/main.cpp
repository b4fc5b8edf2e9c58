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
    sf::app::add_network_options(general, o.network, sf::app::FeedUse::record);
    sf::app::add_daemon_options(general, o.daemon);
    sf::app::OutputOptions output;
    sf::app::add_output_options(general, output,
                                "log file to write: FILE.log, or FILE.log.gz for gzip-compressed");
    // clang-format off
    general.add_options()
        ("duration", po::value(&o.duration_s)->default_value(o.duration_s),
         "seconds to record, then stop; 0 = until SIGINT/SIGTERM")
        ("count", po::value(&o.count)->default_value(o.count),
         "vision packets to record, then stop; 0 = no limit")
        ("index", po::bool_switch(&o.index),
         "end the file with an index message (as ssl-go-tools' indexer writes it)")
        ("receive-buffer",
         po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
         "SO_RCVBUF to request, bytes")
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr (recorded, bytes, skipped, kernel drops)")
        ("verbose", po::bool_switch(&o.verbose), "more logging");
    // clang-format on
    if (!sf::app::parse_command_line(
            argc, argv, general, "ssl-record --output FILE [options]",
            "Records a live SSL-Vision multicast feed, the referee and the trackers into an "
            "official "
            "SSL log file\n(types 4, 3 and 5 in the order received, receive time = Unix time in "
            "ns). Datagrams that are not\nwhat their group carries are counted, not recorded. "
            "SIGINT/SIGTERM, --duration or --count\n(vision packets) end it with a complete "
            "file.")) {
      return 0;
    }
    o.output = output.path;
    o.overwrite = output.overwrite;
    sf::app::check_output_free(output);
    sf::app::init_logging("ssl-record", o.verbose);
    return sf::recorder::run_record(o);
  });
}
