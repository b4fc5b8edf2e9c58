// ssl-predictor: samples the opponent's formations from the vision feed, predicts the next ones
// from the trainer's table and multicasts them (or, with --from-log, writes what it would have
// predicted during recorded logs as CSV). Options only: the work is in the predictor library.

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/predictor/predictor_options.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-predictor", [&] {
    sf::predictor::PredictorOptions o;
    po::options_description general("Options");
    general.add_options()("list-states", po::bool_switch(&o.list_states),
                          "print every state of --grid, one per line, and exit")(
        "table-dir", po::value(&o.table_dir)->value_name("DIR"),
        "instead of --table: the table of the current opponent in DIR, as ssl-trainer --table-dir "
        "keeps them (named after the team as the referee names it); a new opponent's is loaded "
        "when the referee names it")(
        "table", po::value(&o.table)->default_value(o.table),
        "table file written by ssl-trainer; reloaded whenever it is replaced")(
        "prediction-address", po::value(&o.prediction_address)->default_value(o.prediction_address),
        "multicast group:port the FormationPrediction messages go to")(
        "prediction-interface",
        po::value(&o.prediction_interface)->default_value("", "as --interface"),
        "IPv4 address of the interface to send predictions from (127.0.0.1 when --interface all)")(
        "ttl", po::value(&o.ttl)->default_value(o.ttl), "multicast TTL of the predictions")(
        "reload-interval", po::value(&o.reload_interval_s)->default_value(o.reload_interval_s),
        "seconds between checks of the table file")(
        "status-interval", po::value(&o.status_interval_s)->default_value(o.status_interval_s),
        "seconds between status lines on stderr")(
        "receive-buffer", po::value(&o.receive_buffer_bytes)->default_value(o.receive_buffer_bytes),
        "socket receive buffer (SO_RCVBUF) to request, bytes")("quiet", po::bool_switch(&o.quiet),
                                                               "no prediction lines on stdout")(
        "print-predictions", po::bool_switch(&o.print_predictions),
        "every prediction's full line on stdout (default: one short line a second)")(
        "warm-up-lead", po::value(&o.warm_up_lead_ms)->default_value(o.warm_up_lead_ms),
        "milliseconds before the next frame is due at which the last prediction is rehearsed "
        "(nothing sent) to bring the model back into the CPU caches; 0 = off")(
        "http-port",
        po::value(&o.http_port)
            ->default_value(o.http_port, std::to_string(o.default_http_port) + " (or a free one)"),
        "TCP port of the live field view (http://ADDRESS:PORT/, printed at start); by default "
        "another free port when 8080 is taken; 0 = off")(
        "http-address", po::value(&o.http_address)->default_value(o.http_address),
        "address the field view listens on (keep 127.0.0.1 unless others must see it)")(
        "http-max-clients", po::value(&o.http_max_clients)->default_value(o.http_max_clients),
        "connections the field view serves at once (page loads and live views); more are refused")(
        "http-status-interval",
        po::value(&o.http_status_interval_s)->default_value(o.http_status_interval_s),
        "seconds between status messages to the field view")(
        "http-send-buffer",
        po::value(&o.http_send_buffer_bytes)->default_value(o.http_send_buffer_bytes),
        "socket send buffer (SO_SNDBUF) per field view connection, bytes; 0 = the system's")(
        "verbose", po::bool_switch(&o.verbose), "more log lines")(
        "from-log", po::value(&o.from_logs)->multitoken()->value_name("FILE..."),
        "predict from these official SSL log files (.log or .log.gz) as fast as possible, "
        "no network: every prediction as CSV to --output, then exit");
    sf::app::OutputOptions output;
    sf::app::add_output_options(general, output,
                                "--from-log: the CSV file to write; - (the default) = standard "
                                "output");
    sf::app::add_horizons_option(general, o.horizons,
                                 "auto: 2 steps, 0.5 and 1 s at the default --step");
    sf::app::add_vision_options(general, o.network);
    sf::app::add_model_options(general, o.model);
    sf::app::add_recalibration_option(general, o.recalibration_half_life_s);
    sf::app::add_prior_table_option(general, o.prior_table);
    sf::app::add_daemon_options(general, o.daemon);
    sf::app::OldSpellings old;
    old.add("horizon", "--horizons", po::value(&o.old_horizon_steps),
            "in seconds: --horizon 2 at a 0.5 s step is --horizons 1");
    if (!sf::app::parse_command_line(argc, argv, general,
                                     "ssl-predictor [options]\n       ssl-predictor --from-log "
                                     "FILE... [-o PATH] [options]",
                                     "Predicts the opponent's next formations from the table "
                                     "ssl-trainer writes, and multicasts them.",
                                     nullptr, &old)) {
      return 0;
    }
    if (o.list_states) return sf::predictor::list_states(o.model.parsed_grid());
    o.output = output.path;
    o.overwrite = output.overwrite;
    sf::app::init_logging("ssl-predictor", o.verbose);
    sf::predictor::settle_predictor_options(o);
    if (!o.from_logs.empty()) return sf::predictor::run_from_log(o);
    return sf::predictor::run_daemon(o);
  });
}
