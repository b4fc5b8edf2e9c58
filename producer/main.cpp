// ssl-producer: SSL-Vision-style packets on multicast. By default a simulated match: a team
// running a playbook at 60 frames a second, what the default motion model learns from;
// --simulation paper the paper's simulated vision (three plays and random formations), one
// formation every --period seconds. Either with a simulated game controller's referee messages
// on the referee group. With -o it writes the same packets to an official SSL log instead; with
// --replay it sends a log's vision packets with their recorded timing, and its referee messages
// and tracked vision to their groups.

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/producer/producer_options.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-producer", [&] {
    sf::producer::ProducerOptions o;
    po::options_description network("Network (the live simulation and --replay)");
    sf::app::NetworkOptions addresses;
    sf::app::add_network_options(network, addresses, sf::app::FeedUse::send);
    network.add_options()("ttl", po::value(&o.ttl)->default_value(o.ttl),
                          "multicast TTL (1 keeps packets on the link)");
    po::options_description simulation("Simulation (live and --write-log)");
    // clang-format off
    simulation.add_options()
        ("simulation", po::value(&o.simulation)->default_value(o.simulation),
         "paper: the paper's opponent, jumping between the formations of three plays every "
         "--step seconds; match: a team running a playbook with real motion, 60 frames a "
         "second, against our marking team")
        ("division", po::value(&o.division)->default_value(o.division),
         "match: A (11 robots a team, 12 x 9 m) or B (6, 9 x 6 m)")
        ("frame-rate", po::value(&o.frame_rate_hz)->default_value(o.frame_rate_hz),
         "match: frames a second, per camera (also the live feed's rate)")
        ("playbook", po::value(&o.playbook)->default_value(o.playbook),
         "match: the opponent's set plays, a built-in playbook (wings, centre) or a file "
         "(format in the README)")
        ("duration", po::value(&o.duration_s)->default_value(o.duration_s),
         "seconds of data time to send or write, then exit; 0 = no limit (or --count)")
        ("period", po::value(&o.period_s)->default_value(o.period_s),
         "paper: wall-clock seconds between formations; 0 = as fast as possible (not used by "
         "--write-log)")
        ("step", po::value(&o.step_s)->default_value(o.step_s, "auto"),
         "paper: data-clock seconds (t_capture) between formations; auto: 2, the paper's")
        ("count", po::value(&o.count)->default_value(o.count),
         "formations (paper) or frames (match) to send or write, then exit; 0 = no limit. With "
         "--replay: packets to send")
        ("seed", po::value(&o.seed)->default_value(o.seed),
         "random seed: the same seed sends the same packets")
        ("cameras", po::value(&o.cameras)->default_value(o.cameras),
         "cameras the field is split among (1-8); robots in overlaps are reported by both")
        ("camera-overlap", po::value(&o.camera_overlap_mm)->default_value(o.camera_overlap_mm),
         "overlap between neighbouring cameras, mm")
        ("jitter-mm", po::value(&o.jitter_mm)->default_value(o.jitter_mm),
         "standard deviation of Gaussian noise on detected positions, mm")
        ("drop-rate", po::value(&o.drop_rate)->default_value(o.drop_rate),
         "probability that a camera's packet is lost (0-1)")
        ("opponent-color", po::value(&o.opponent_color)->default_value(o.opponent_color),
         "colour of the simulated opponent: yellow or blue")
        ("opponent-attacks", po::value(&o.opponent_attacks)->default_value(o.opponent_attacks),
         "direction the simulated opponent attacks in the feed's coordinates in the first half: "
         "+x or -x (the teams change ends at half time when the game controller runs)")
        ("field-length", po::value(&o.field_length_mm)->default_value(o.field_length_mm),
         "paper: field length, mm (plays are drawn for 9000 and stretched; the match's field "
         "is its division's)")
        ("field-width", po::value(&o.field_width_mm)->default_value(o.field_width_mm),
         "paper: field width, mm (plays are drawn for 6000 and stretched)")
        ("start-time", po::value(&o.start_time_s)->default_value(o.start_time_s),
         "t_capture of the first formation, seconds");
    // clang-format on
    po::options_description game("Simulated game controller (live and --write-log)");
    // clang-format off
    game.add_options()
        ("referee", po::value(&o.referee)->default_value(o.referee, "on"),
         "on: referee messages go with the simulation, as at a match (team names, kick-offs, "
         "stoppages and free kicks, two halves with a change of ends), to --referee-address or "
         "into --write-log; off: vision only, the paper's protocol")
        ("our-team", po::value(&o.our_team)->default_value(o.our_team),
         "the name the referee gives our team (give the daemons the same --our-team)")
        ("opponent-team", po::value(&o.opponent_team)->default_value(o.opponent_team),
         "the name the referee gives the simulated opponent")
        ("half-length", po::value(&o.half_length_s)->default_value(o.half_length_s),
         "seconds of data time (t_capture) in each half; half time is 20 s");
    // clang-format on
    po::options_description logs("Log files (official SSL format; .log.gz is gzip-compressed)");
    sf::app::OutputOptions output;
    sf::app::add_output_options(logs, output,
                                "write the simulated feed to this log (.log or .log.gz) as fast as "
                                "possible, no network; receive time = t_capture in ns; needs "
                                "--count or --duration");
    // clang-format off
    logs.add_options()
        ("replay", po::value(&o.replay)->value_name("FILE"),
         "send FILE's vision packets (types 4 and 2) with their recorded timing, and its referee "
         "messages and tracked vision to --referee-address and --tracker-address, instead of the "
         "simulation; the simulation options are ignored")
        ("speed", po::value(&o.speed)->default_value(o.speed),
         "replay speed: 1 = as recorded, 10 = ten times faster, 0 = as fast as possible")
        ("loop", po::bool_switch(&o.loop),
         "replay: start over at the end (until a signal or --count)")
        ("start", po::value(&o.replay_start_s)->default_value(o.replay_start_s),
         "replay: seconds from the log's first packet to start at")
        ("end", po::value(&o.replay_end_s)->default_value(o.replay_end_s),
         "replay: seconds from the log's first packet to stop at; 0 = the end of the log");
    // clang-format on
    po::options_description general("Options");
    // clang-format off
    general.add_options()
        ("status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
         "seconds between status lines on stderr")
        ("verbose", po::bool_switch(&o.verbose), "log every formation or frame sent");
    // clang-format on
    sf::app::add_daemon_options(general, o.daemon);
    general.add(network).add(simulation).add(game).add(logs);
    sf::app::OldSpellings old;
    std::string old_write_log;
    old.add("write-log", "-o/--output", po::value(&old_write_log),
            "which refuses a file that exists unless --overwrite");
    if (!sf::app::parse_command_line(
            argc, argv, general,
            "ssl-producer [options]\n"
            "       ssl-producer --simulation paper [--period S] [--step S]\n"
            "       ssl-producer -o FILE --count N|--duration S [simulation options]\n"
            "       ssl-producer --replay FILE [--speed X] [--loop] [--start S] [--end S] "
            "[--vision-address G:P]",
            "Sends SSL-Vision packets of a simulated opponent on multicast, with a game "
            "controller's referee messages:\nthe paper's (three plays and random formations) or "
            "a match (a team running a playbook, 60 frames a\nsecond). Writes them to an "
            "official SSL log instead (-o), or replays a log with its recorded\ntiming "
            "(--replay).",
            nullptr, &old)) {
      return 0;
    }
    o.vision_address = addresses.vision_address;
    o.referee_address = addresses.referee_address;
    o.tracker_address = addresses.tracker_address;
    o.interface = addresses.interface;
    if (!output.path.empty() && !old_write_log.empty()) {
      throw sf::app::UsageError("give -o/--output or its old name --write-log, not both");
    }
    if (!old_write_log.empty()) {
      // The old spelling replaced a file that existed, as it always did.
      output = {old_write_log, true};
    }
    o.write_log = output.path;
    if (!o.write_log.empty() && !o.replay.empty()) {
      throw sf::app::UsageError("-o/--output and --replay exclude each other");
    }
    sf::app::check_output_free(output);
    sf::app::init_logging("ssl-producer", o.verbose);
    if (!o.write_log.empty()) return sf::producer::run_write_log(o);
    if (!o.replay.empty()) return sf::producer::run_replay(o);
    return sf::producer::run_simulation(o);
  });
}
