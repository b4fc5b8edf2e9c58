// ssl-trainer: listens to the vision feed (or reads logs), samples the opponent's formations and
// counts state transitions (and the motion model's rows) into a table file that ssl-predictor
// reads. Wiring only: the work, and the options of the training modes, are in the trainer
// library (trainer/src).

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/trainer/trainer.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

int merge_main(int argc, const char* const argv[]) {
  std::vector<std::string> inputs;
  sf::app::OutputOptions output;
  double max_table_mb = sf::default_max_table_mb;
  po::options_description options("Options");
  sf::app::add_output_options(options, output, "the merged table file to write (required)");
  options.add_options()("input", po::value(&inputs)->multitoken(), "table files to add up");
  sf::app::add_max_table_option(options, max_table_mb);
  po::positional_options_description positional;
  positional.add("input", -1);
  if (!sf::app::parse_command_line(argc, argv, options, "ssl-trainer merge TABLE... -o OUT",
                                   "Adds up tables of the same grid, step and model into one.",
                                   &positional)) {
    return 0;
  }
  if (output.path.empty()) throw sf::app::UsageError("-o/--output TABLE is required");
  sf::app::check_output_free(output);
  (void)sf::app::table_budget_option(max_table_mb);  // refuses a bad one before any work
  sf::trainer::merge_tables(inputs, output.path, max_table_mb);
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
    if (!sf::trainer::parse_trainer_options(argc, argv, o)) return 0;
    sf::app::init_logging("ssl-trainer", o.verbose);
    sf::trainer::settle_trainer_options(o);
    if (!o.from_logs.empty()) return sf::trainer::run_offline(o);
    return sf::trainer::run_live(o);
  });
}
