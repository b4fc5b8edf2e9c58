// ssl-trainer: listens to the vision feed (or reads logs), samples the opponent's formations and
// counts state transitions into a table file that ssl-predictor reads. Options only: the work
// is in the trainer library (trainer/src).

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

int merge_main(int argc, const char* const argv[]) {
  std::vector<std::string> inputs;
  std::string output;
  po::options_description options("Options");
  options.add_options()("output,o", po::value(&output)->required(),
                        "the merged table file to write (atomically)")(
      "input", po::value(&inputs)->multitoken(), "table files to add up");
  po::positional_options_description positional;
  positional.add("input", -1);
  if (!sf::app::parse_command_line(argc, argv, options, "ssl-trainer merge TABLE... -o OUT",
                                   "Adds up tables of the same grid and step into one.",
                                   &positional)) {
    return 0;
  }
  sf::trainer::merge_tables(inputs, output);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-trainer", [&] {
    if (argc > 1 && std::string_view(argv[1]) == "merge") {
      sf::app::init_logging("ssl-trainer");
      return merge_main(argc - 1, argv + 1);
    }
    sf::trainer::TrainerOptions o;
    po::options_description general("Options");
    // clang-format off
    general.add_options()
        ("table", po::value(&o.table)->default_value(o.table),
         "table file to resume and save (written atomically)")
        ("reset", po::bool_switch(&o.reset),
         "start an empty table even if --table holds one of another grid or step")
        ("flush-interval", po::value(&o.flush_interval_s)->default_value(o.flush_interval_s),
         "seconds between saves of the table (it is also saved on SIGINT/SIGTERM)")
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr")
        ("receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
         "socket receive buffer (SO_RCVBUF) to request, bytes")
        ("verbose", po::bool_switch(&o.verbose), "log every save")
        ("from-log", po::value(&o.from_logs)->multitoken(),
         "train from these official SSL log files (.log or .log.gz) instead of the network, "
         "save the table and exit")
        ("strict", po::bool_switch(&o.strict),
         "--from-log: exit 1 also when a log only ends inside its last message (by default that "
         "is a warning: a recorder killed mid-write leaves such files)");
    // clang-format on
    sf::app::add_vision_options(general, o.network);
    sf::app::add_model_options(general, o.model);
    sf::app::add_daemon_options(general, o.daemon);
    if (!sf::app::parse_command_line(
            argc, argv, general,
            "ssl-trainer [options]\n       ssl-trainer --from-log FILE... [options]\n"
            "       ssl-trainer merge TABLE... -o OUT",
            "Counts the opponent's formation transitions from the vision feed (or from logs) "
            "into a table file.")) {
      return 0;
    }
    sf::app::init_logging("ssl-trainer", o.verbose);
    if (!o.from_logs.empty()) return sf::trainer::run_offline(o);
    return sf::trainer::run_live(o);
  });
}
