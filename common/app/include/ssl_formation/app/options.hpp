#pragma once
// One option parser for every program (Boost.Program_options), so the same thing has the same
// name everywhere: --vision-address, --interface, --table, --grid, --step, --opponent-color,
// --opponent-attacks, --field-length, --field-width.

#include <boost/program_options.hpp>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/match/match.hpp"
#include "ssl_formation/models/model_factory.hpp"
#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/motion_model/online_calibration.hpp"
#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation::app {

namespace po = boost::program_options;

// Thrown for a bad option value; main() prints it as one line and exits with 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline constexpr const char* default_vision_address = "224.5.23.2:10006";
inline constexpr const char* default_referee_address = "224.5.23.1:10003";
inline constexpr const char* default_tracker_address = "224.5.23.2:10010";
inline constexpr const char* default_prediction_address = "224.5.23.4:10040";
inline constexpr const char* default_interface = "127.0.0.1";
inline constexpr const char* default_table = "formation-table.bin";

// The model's options: what the sampler and the table need to agree on.
struct ModelOptions {
  // "auto": the table's grid where a table is read (take_table_settings), else 3x2.
  std::string grid = "auto";
  // 0: the model's own (ModelDescription::default_step_s): 0.5 s, the paper's 2 s for paper.
  double step_s = 0.0;
  double step() const;  // the effective step; throws UsageError
  // "referee": from the referee feed (the colour by the team names and --our-team or
  // --opponent-team, the side by blue_team_on_positive_half); yellow attacking +x until it says.
  std::string opponent_color = "referee";
  std::string opponent_attacks = "referee";
  std::string our_team;
  std::string opponent_team;
  double field_length_mm = 9000.0;
  double field_width_mm = 6000.0;
  bool ignore_geometry = false;
  // "auto": the table's model where a table is read (take_table_settings), else the default.
  std::string model = "auto";
  // "auto": what the model needs, frame for motion and step (the paper's protocol) for paper.
  std::string sampling = "auto";

  Grid parsed_grid() const;              // throws UsageError
  ModelKind parsed_model() const;        // throws UsageError
  SamplerConfig sampler_config() const;  // validates everything; throws UsageError
  // Who the opponent is by these options (the referee fills in what they leave open).
  OpponentChoice opponent_choice() const;  // throws UsageError
};
// The grid and the model without a table to take them from.
inline constexpr const char* default_grid = "3x2";
// Fills the grid, the step and the model that the options leave on auto from the table at
// `table_path` (its grid, its step, and the motion model or the paper's by what it holds), and
// says so once. Options given keep their values: a table that disagrees is refused where it is
// loaded, with the option to give. Nothing happens without a readable table there.
void take_table_settings(ModelOptions& model, const std::string& table_path);
void add_model_options(po::options_description& options, ModelOptions& model);

// --recalibration-half-life, for the programs that predict (ssl-predictor, ssl-evaluate): how
// fast the motion model's stated probabilities follow what the play lately did
// (OnlineCalibration); 0 turns that off.
void add_recalibration_option(po::options_description& options, double& half_life_s);
// The settings a --recalibration-half-life asks for; none for 0. Throws UsageError for a
// negative or non-finite one.
std::optional<OnlineCalibrationSettings> recalibration_settings(double half_life_s);

// --prior-table, for the programs that predict with the motion model (ssl-predictor,
// ssl-evaluate): every team's table, under the opponent's own rows (MotionModel).
void add_prior_table_option(po::options_description& options, std::string& prior_table);
// The prior's motion rows; none for an empty path. Throws UsageError, saying why, for a file
// that does not load, holds no motion rows, or was trained with another step than `step_s`.
std::shared_ptr<const MotionTable> loaded_prior_table(const std::string& path, double step_s);

// --max-table-mb, for the programs that save a trained table (ssl-trainer and its merge) and the
// one that scores the table as they would save it (ssl-evaluate).
void add_max_table_option(po::options_description& options, double& max_table_mb);
// The budget a --max-table-mb asks for. Throws UsageError for a negative or non-finite one.
TableBudget table_budget_option(double max_table_mb);

// --learn-during, for the program that trains from the referee (ssl-trainer).
void add_learn_during_option(po::options_description& options, std::string& learn_during);
LearnDuring parsed_learn_during(const std::string& learn_during);  // throws UsageError

struct NetworkOptions {
  std::string vision_address = default_vision_address;
  // The game controller's group, joined on the same interface; "none": no referee feed.
  std::string referee_address = default_referee_address;
  // "raw": SSL-Vision's detections on vision_address; "tracked": a tracker's frames
  // (TrackerWrapperPacket) on tracker_address instead.
  std::string vision_source = "raw";
  std::string tracker_address = default_tracker_address;
  std::string interface = default_interface;
  bool tracked() const;  // throws UsageError for a --vision-source other than raw or tracked
};
// What a program does with the feeds' groups, which words their --help uses.
enum class FeedUse {
  listen,  // ssl-trainer, ssl-predictor: join and read
  record,  // ssl-record: join and write to a log
  send,    // ssl-producer: send (the simulation or a replayed log)
};
// --vision-address, --referee-address, --tracker-address and --interface: one declaration for
// every program, so that the names and defaults cannot drift apart.
void add_network_options(po::options_description& options, NetworkOptions& network, FeedUse use);
// The network options of a program that listens, and --vision-source.
void add_vision_options(po::options_description& options, NetworkOptions& network);
// --vision-source alone, for the programs that read logs only (ssl-evaluate).
void add_vision_source_option(po::options_description& options, NetworkOptions& network);

// What every long-running program offers its supervisor (a script, a test, systemd).
struct DaemonOptions {
  // Written once the program is ready (see app::ReadyFile); empty: none.
  std::string ready_file;
};
void add_daemon_options(po::options_description& options, DaemonOptions& daemon);

// -o/--output and --overwrite, for every program that writes a file or a folder of them.
struct OutputOptions {
  std::string path;  // empty: not given; "-": standard output, where the program allows it
  bool overwrite = false;
};
// `what` ends the option's help: "the CSV file to write; - = standard output".
void add_output_options(po::options_description& options, OutputOptions& output,
                        const std::string& what);
// Refuses a file that exists (with the option that allows it) unless --overwrite: checked before
// any work, so that a long run does not end by refusing its own output. Standard output ("-")
// and devices (/dev/null) are always written.
void check_output_free(const OutputOptions& output);
// The same for several files a program writes into one folder.
void check_outputs_free(const std::vector<std::string>& paths, bool overwrite);

// --horizons, in seconds, for the programs that learn or predict a number of steps ahead
// (ssl-trainer, ssl-predictor; ssl-evaluate takes a list of them): "auto", or the longest horizon
// in seconds (of a list, the longest), which must be a whole number of steps.
void add_horizons_option(po::options_description& options, std::string& horizons,
                         const std::string& what);
// An int option's value before the command line gives one (an old spelling that may be 0).
inline constexpr int not_given = std::numeric_limits<int>::min();
// The steps --horizons asks for at `step_s`; `auto_steps` for "auto". Throws UsageError.
int horizon_steps(const std::string& horizons, double step_s, int auto_steps);

// Old spellings of renamed options, kept for a release: parsed like the new ones, left out of
// --help, and noted once on stderr when given.
class OldSpellings {
 public:
  // `value` stores where the program reads the new option from; `hint` is added to the note.
  void add(const std::string& old_name, const std::string& new_name, po::value_semantic* value,
           const std::string& hint = "");
  const po::options_description& options() const { return options_; }
  // Prints "PROGRAM: note: --OLD is now NEW ..." for each old spelling given.
  void note_used(const std::string& program, const po::variables_map& values) const;

 private:
  struct Renamed {
    std::string old_name, new_name, hint;
  };
  po::options_description options_;
  std::vector<Renamed> renamed_;
};

// Parses argv. Prints --help (with defaults) and returns false when the program should exit 0.
// Throws UsageError for anything wrong, with one line of explanation.
bool parse_command_line(int argc, const char* const argv[], const po::options_description& options,
                        const std::string& usage_line, const std::string& description,
                        const po::positional_options_description* positional = nullptr,
                        const OldSpellings* old_spellings = nullptr);

// Runs `body` and turns an exception into one line "PROGRAM: error: ..." on stderr: exit code 2
// for a UsageError (which also points to --help), 1 for any other.
int run_main(const char* program, const std::function<int()>& body);

}  // namespace ssl_formation::app
