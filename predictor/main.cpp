// ssl-predictor: predicts the opponent's next formations from the trained table.
// --list-states prints the state space (the paper's statesList).

#include <iostream>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/state.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

int list_states(const sf::Grid& grid) {
  const sf::StateCodec codec(grid);
  std::string out;
  for (sf::StateIndex index = 0; index < codec.state_count(); ++index) {
    out += codec.describe(index);
    out += '\n';
    if (out.size() > (1 << 20)) {
      std::cout << out;
      out.clear();
    }
  }
  std::cout << out << std::flush;
  return std::cout ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-predictor", [&] {
    sf::app::ModelOptions model;
    sf::app::NetworkOptions network;
    bool list = false;
    po::options_description options("Options");
    options.add_options()("list-states", po::bool_switch(&list),
                          "print every state of the grid, one per line, and exit");
    sf::app::add_model_options(options, model);
    sf::app::add_vision_options(options, network);
    if (!sf::app::parse_command_line(argc, argv, options, "ssl-predictor [options]",
                                     "Predicts the opponent's next formations from the table.")) {
      return 0;
    }
    const sf::Grid grid = model.parsed_grid();
    if (list) return list_states(grid);
    model.sampler_config();  // validates every option before anything starts
    throw sf::app::UsageError("nothing to do yet: use --list-states");
  });
}
