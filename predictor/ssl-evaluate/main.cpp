// ssl-evaluate: how good are the predictions? Options only: the work is in the evaluate
// library (predictor/src/evaluate.cpp).

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/evaluate/evaluate.hpp"
#include "ssl_formation/files/real_log_shape.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-evaluate", [&] {
    sf::evaluate::EvaluateOptions o;
    std::string horizons = "0.2,0.5,1,2";
    const std::string mess_help = "as-real-log: none, all, or a comma-separated list of " +
                                  std::string(sf::real_log_mess_names) +
                                  ", written without spaces as in ghosts,cuts (ends: a change of "
                                  "ends at half time; noise: 0.3 mm, the real logs', or noise=MM)";
    po::options_description general("Options");
    general.add_options()("mode", po::value(&o.mode)->required(),
                          "paper, holdout, grid-sweep, as-real-log or score")(
        "seed", po::value(&o.seed)->default_value(o.seed),
        "seed of the simulated training stream; as-real-log: of the ghosts and the noise")(
        "test-seed", po::value(&o.test_seed)->default_value(o.test_seed),
        "seed of the simulated test stream (holdout) or of the random test formations (paper)")(
        "train-formations", po::value(&o.train_formations)->default_value(o.train_formations),
        "simulated training formations (one packet each with one camera; the paper used 15,000)")(
        "test-formations", po::value(&o.test_formations)->default_value(o.test_formations),
        "simulated test formations (holdout, grid-sweep)")(
        "tests", po::value(&o.tests)->default_value(o.tests), "paper mode: number of tests")(
        "train-log", po::value(&o.train_logs)->multitoken()->value_name("FILE..."),
        "train on these official logs (each its own stream) instead of the simulation")(
        "test-log", po::value(&o.test_logs)->multitoken()->value_name("FILE..."),
        "test on these official logs (each its own stream) instead of the simulation")(
        "split", po::value(&o.split)->default_value(o.split),
        "train on this first fraction of every --train-log and test on the rest of each")(
        "tune", po::bool_switch(&o.tune),
        "with --split F: the tuning split (docs/tuning.md): train on the first F of each log's "
        "first F and test on the rest of that; the last 1 - F, which reports, is not read")(
        "horizons", po::value(&horizons)->default_value(horizons),
        "holdout: horizons in seconds, each evaluated as a model of its own (step = horizon)")(
        "chain-steps", po::value(&o.chain_steps)->default_value(o.chain_steps),
        "holdout: also chains of 1 to this many steps of --step")(
        "velocity-window", po::value(&o.velocity_window_s)->default_value(o.velocity_window_s),
        "seconds: a robot's velocity (from its tracker) counts once its track has run half this "
        "long")("jitter-mm", po::value(&o.jitter_mm)->default_value(o.jitter_mm),
                "noise of the simulated vision, mm")(
        "cameras", po::value(&o.cameras)->default_value(o.cameras),
        "cameras of the simulated vision")(
        "grids", po::value(&o.grids)->multitoken()->default_value(o.grids, "3x2 6x4 9x6 12x9"),
        "grid-sweep: the grids to compare")(
        "write-samples", po::value(&o.write_samples)->value_name("FILE"),
        "holdout, grid-sweep: also write every scored robot to this CSV file, a line per robot, "
        "instant and horizon (where it was, where it went, every method's forecast; about 170 "
        "bytes a line, 1.4 million lines for the default simulated match)")(
        "bootstrap", po::value(&o.bootstrap)->default_value(o.bootstrap)->value_name("N"),
        "holdout, grid-sweep, score: a 95% interval for every mean error and every ratio to the "
        "best "
        "baseline, from N resamples of a block bootstrap over blocks of data time (a fixed seed; "
        "0: no intervals)")("bootstrap-block",
                            po::value(&o.bootstrap_block_s)->default_value(o.bootstrap_block_s),
                            "holdout, grid-sweep, score: the bootstrap's blocks, seconds of data "
                            "time (neighbouring frames "
                            "are nearly the same: a block holds what is independent of the next)")(
        "simulation", po::value(&o.simulation)->default_value(o.simulation),
        "holdout without logs: match (a simulated match with its referee, --train-seconds of "
        "--seed against --test-seconds of --test-seed), paper (the paper's simulated opponent, "
        "--train-formations and --test-formations) or auto (paper for --model paper, else match)")(
        "train-seconds", po::value(&o.train_seconds)->default_value(o.train_seconds),
        "holdout --simulation match: seconds of simulated match to train on")(
        "test-seconds", po::value(&o.test_seconds)->default_value(o.test_seconds),
        "holdout --simulation match: seconds of simulated match to test on")(
        "playbook", po::value(&o.playbook)->default_value(o.playbook),
        "holdout --simulation match: the opponent's playbook (a built-in name or a file)")(
        "from-log", po::value(&o.from_log)->value_name("FILE"),
        "the recording to read (an official log, .log or .log.gz): score: the match the "
        "predictions were made for; as-real-log: the clean recording to rewrite")(
        "mess", po::value(&o.mess)->default_value(o.mess), mess_help.c_str())(
        "report", po::value(&o.report)->value_name("FILE.html"),
        "holdout, score: also write one self-contained page to open: the table by game state "
        "with intervals, error against horizon, reliability diagrams, the radii's coverage, the "
        "error per robot id and a field heat map of where the model wins and loses (holdout: "
        "the chains of --step, the predictor's own figures)")(
        "predictions", po::value(&o.predictions)->value_name("CSV"),
        "score: the predictions, with the columns of ssl-predictor --from-log's CSV (at least "
        "t_capture, robot_id, horizon_s, predicted_feed_x_mm, predicted_feed_y_mm; radii, cells "
        "and probabilities if given); --train-log: where the damped baselines are fitted");
    sf::app::OutputOptions output;
    sf::app::add_output_options(general, output,
                                "paper, holdout, grid-sweep, score: a folder to write the tables "
                                "into as CSV files too (none without it); as-real-log: the log to "
                                "write (gzip if it ends in .gz). --overwrite also lets --report "
                                "and --write-samples replace their files");
    sf::app::add_model_options(general, o.model);
    sf::app::add_learn_during_option(general, o.learn_during);
    sf::app::add_vision_source_option(general, o.network);
    sf::app::add_recalibration_option(general, o.recalibration_half_life_s);
    sf::app::add_prior_table_option(general, o.prior_table);
    sf::app::add_max_table_option(general, o.max_table_mb);
    po::positional_options_description positional;
    positional.add("mode", 1);
    sf::app::OldSpellings old;
    std::string old_output_dir;
    std::string old_write_log;
    std::string old_log;
    old.add("output-dir", "-o/--output", po::value(&old_output_dir));
    old.add("write-log", "-o/--output", po::value(&old_write_log));
    old.add("log", "--from-log", po::value(&old_log));
    if (!sf::app::parse_command_line(
            argc, argv, general,
            "ssl-evaluate paper|holdout|grid-sweep|as-real-log|score [options]",
            "Evaluates the predictions: the paper's protocol, held-out "
            "accuracy against baselines, and a grid sweep; scores "
            "predictions made elsewhere; writes a recording the way "
            "real match logs come, to evaluate on.",
            &positional, &old)) {
      return 0;
    }
    if (!old_output_dir.empty() || !old_write_log.empty()) {
      if (!output.path.empty()) {
        throw sf::app::UsageError("give -o/--output or its old spelling, not both");
      }
      output = {old_output_dir.empty() ? old_write_log : old_output_dir, true};  // as they did
    }
    if (!old_log.empty()) {
      if (!o.from_log.empty()) throw sf::app::UsageError("give --from-log or --log, not both");
      o.from_log = old_log;
    }
    o.overwrite = output.overwrite;
    if (o.mode == "as-real-log") {
      o.write_log = output.path;
      sf::app::check_output_free(output);
    } else {
      o.output_dir = output.path;
      if (o.mode == "score") o.log = o.from_log;
    }
    sf::app::check_outputs_free({o.report, o.write_samples}, o.overwrite);
    if (o.tests < 1 || o.train_formations < 1 || o.test_formations < 1) {
      throw sf::app::UsageError(
          "--tests, --train-formations and --test-formations must be positive");
    }
    if (o.split < 0.0 || o.split >= 1.0) throw sf::app::UsageError("--split must be in [0, 1)");
    if (o.model.opponent_team == "all") {
      throw sf::app::UsageError(
          "--opponent-team all is for ssl-trainer --from-log: name the "
          "opponent");
    }
    (void)o.network.tracked();  // checked before any work
    o.horizons = sf::evaluate::parse_horizons(horizons);
    (void)sf::app::recalibration_settings(o.recalibration_half_life_s);  // checked before any work
    sf::app::init_logging("ssl-evaluate");
    if (!o.write_samples.empty() && o.mode != "holdout" && o.mode != "grid-sweep") {
      throw sf::app::UsageError("--write-samples is for holdout and grid-sweep, not " + o.mode);
    }
    if (o.bootstrap < 0 || o.bootstrap > 100000) {
      throw sf::app::UsageError("--bootstrap takes 0 (no intervals) to 100000 resamples");
    }
    if (!(o.bootstrap_block_s > 0.0)) {
      throw sf::app::UsageError("--bootstrap-block must be a positive number of seconds");
    }
    if (o.tune && o.mode != "holdout") {
      throw sf::app::UsageError("--tune is for holdout --split F, not " + o.mode);
    }
    if (!o.report.empty() && o.mode != "holdout" && o.mode != "score") {
      throw sf::app::UsageError("--report is for holdout and score, not " + o.mode);
    }
    for (int i = 0; i < argc; ++i) o.command_line += (i ? " " : "") + std::string(argv[i]);
    if (o.mode == "paper") return sf::evaluate::run_paper(o);
    if (o.mode == "holdout") {
      return sf::evaluate::run_holdout(o, {o.model.parsed_grid().to_string()});
    }
    if (o.mode == "grid-sweep") return sf::evaluate::run_holdout(o, o.grids);
    if (o.mode == "as-real-log") return sf::evaluate::run_as_real_log(o);
    if (o.mode == "score") return sf::evaluate::run_score(o);
    throw sf::app::UsageError(
        "mode must be paper, holdout, grid-sweep, as-real-log or score, not '" + o.mode + "'");
  });
}
