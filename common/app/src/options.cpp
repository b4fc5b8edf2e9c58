#include "ssl_formation/app/options.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <vector>

#include "ssl_formation/models/table_file.hpp"

namespace ssl_formation::app {

Grid ModelOptions::parsed_grid() const {
  const auto parsed = Grid::parse(grid == "auto" ? default_grid : grid);
  if (!parsed) throw UsageError("--grid: " + parsed.error().message);
  return *parsed;
}

ModelKind ModelOptions::parsed_model() const {
  if (model == "auto") return default_model;
  const auto parsed = parse_model(model);
  if (!parsed)
    throw UsageError("--model must be one of " + model_names() + ", not '" + model + "'");
  return *parsed;
}

double ModelOptions::step() const {
  if (step_s == 0.0) return describe(parsed_model()).default_step_s;
  if (!std::isfinite(step_s) || step_s <= 0.0) {
    std::ostringstream text;
    text << "--step must be a positive number of seconds, not " << step_s;
    throw UsageError(text.str());
  }
  return step_s;
}

SamplerConfig ModelOptions::sampler_config() const {
  SamplerConfig config;
  config.grid = parsed_grid();
  config.step_s = step();
  const OpponentChoice choice = opponent_choice();
  // Until the referee says otherwise: the defaults, which are the behaviour without one.
  config.opponent_color = choice.color.value_or(TeamColor::yellow);
  config.infer_attacks = choice.infer_attacks;
  config.opponent_attacks = choice.attacks.value_or(AttackDirection::positive_x);
  const ModelKind kind = parsed_model();
  if (sampling == "auto") {
    config.sampling = sampler_config_for(kind).sampling;
  } else {
    const auto mode = parse_sampling(sampling);
    if (!mode) throw UsageError("--sampling must be auto, frame or step, not '" + sampling + "'");
    if (const auto problem = sampling_problem(kind, *mode)) throw UsageError(*problem);
    config.sampling = *mode;
  }
  config.field = FieldSize{field_length_mm, field_width_mm};
  if (!config.field.valid()) {
    throw UsageError("--field-length and --field-width must be positive millimetres");
  }
  config.use_geometry = !ignore_geometry;
  return config;
}

OpponentChoice ModelOptions::opponent_choice() const {
  OpponentChoice choice;
  if (opponent_color != "referee") {
    const auto color = parse_team_color(opponent_color);
    if (!color) {
      throw UsageError("--opponent-color must be yellow, blue or referee, not '" + opponent_color +
                       "'");
    }
    choice.color = *color;
  }
  if (opponent_attacks == "auto") {
    choice.infer_attacks = true;
  } else if (opponent_attacks != "referee") {
    const auto attacks = parse_attack_direction(opponent_attacks);
    if (!attacks) {
      throw UsageError("--opponent-attacks must be +x, -x, auto or referee, not '" +
                       opponent_attacks + "'");
    }
    choice.attacks = *attacks;
  }
  if (!our_team.empty() && !opponent_team.empty()) {
    throw UsageError("give --our-team or --opponent-team, not both");
  }
  choice.our_team = our_team;
  choice.opponent_team = opponent_team;
  return choice;
}

void add_prior_table_option(po::options_description& options, std::string& prior_table) {
  options.add_options()(
      "prior-table", po::value(&prior_table)->value_name("FILE"),
      "the motion model's prior: a table of every team (ssl-trainer --from-log LOGS "
      "--opponent-team all, then merge). The opponent's own rows take over from it as they fill; "
      "an opponent without a table yet is predicted from it alone");
}

void add_max_table_option(po::options_description& options, double& max_table_mb) {
  options.add_options()(
      "max-table-mb", po::value(&max_table_mb)->default_value(max_table_mb),
      "the largest table file to save, MB: the motion model's rows that say least over their "
      "coarser rows are folded into them until it fits (rows that say nothing always are); 0: no "
      "bound");
}

TableBudget table_budget_option(double max_table_mb) {
  if (!std::isfinite(max_table_mb) || max_table_mb < 0.0) {
    throw UsageError("--max-table-mb must be 0 (no bound) or more, not " +
                     std::to_string(max_table_mb));
  }
  return table_budget_mb(max_table_mb);
}

void take_table_settings(ModelOptions& model, const std::string& table_path) {
  if (table_path.empty() ||
      (model.grid != "auto" && model.step_s != 0.0 && model.model != "auto")) {
    return;
  }
  std::error_code error;
  if (!std::filesystem::is_regular_file(table_path, error)) return;
  const auto loaded = load_table(table_path);
  if (!loaded) return;  // the program's own load says why
  std::vector<std::string> taken;
  if (model.grid == "auto") {
    model.grid = loaded->table.grid().to_string();
    taken.push_back("--grid " + model.grid);
  }
  const ModelKind table_model = model_of_table(*loaded);
  if (model.model == "auto") {
    model.model = std::string(to_string(table_model));
    taken.push_back("--model " + model.model);
  }
  // The step of a table of another model than the one asked for means nothing to it.
  if (model.step_s == 0.0 && loaded->metadata.step_s > 0.0 && model.parsed_model() == table_model) {
    model.step_s = loaded->metadata.step_s;
    std::ostringstream step;
    step << "--step " << model.step_s;
    taken.push_back(step.str());
  }
  if (taken.empty()) return;
  std::string said;
  for (const std::string& option : taken) said += (said.empty() ? "" : ", ") + option;
  spdlog::info("{} from the table {} (give them to choose otherwise)", said, table_path);
}

std::shared_ptr<const MotionTable> loaded_prior_table(const std::string& path, double step_s) {
  if (path.empty()) return nullptr;
  auto loaded = load_table(path);
  if (!loaded) throw UsageError("--prior-table: " + loaded.error().message);
  if (!loaded->motion) {
    throw UsageError("--prior-table: " + path +
                     " holds only the paper's counts: train it with --model motion");
  }
  if (std::abs(loaded->motion->config().step_s - step_s) > 1e-9) {
    throw UsageError("--prior-table: " + path + " was trained with a step of " +
                     std::to_string(loaded->motion->config().step_s) + " s, not --step's " +
                     std::to_string(step_s) + " s");
  }
  return std::make_shared<const MotionTable>(std::move(*loaded->motion));
}

void add_learn_during_option(po::options_description& options, std::string& learn_during) {
  options.add_options()(
      "learn-during", po::value(&learn_during)->default_value(learn_during),
      "all: learn in every game state, each filed under its state (the motion model keeps "
      "HALT, STOP, placements, kick-offs and free kicks apart by team and by the seconds since "
      "the command); running: learn only from running play (after NORMAL_START or FORCE_START "
      "and in free kicks, until the next HALT, STOP, timeout, ball placement or kick-off or "
      "penalty preparation), nothing across a change of command. Without a referee feed "
      "everything is learned either way");
}

LearnDuring parsed_learn_during(const std::string& learn_during) {
  const auto parsed = parse_learn_during(learn_during);
  if (!parsed) {
    throw UsageError("--learn-during must be running or all, not '" + learn_during + "'");
  }
  return *parsed;
}

void add_model_options(po::options_description& options, ModelOptions& model) {
  options.add_options()("grid", po::value(&model.grid)->default_value(model.grid),
                        "grid LxW: L cells along the field length, W along its width; auto: the "
                        "table's where one is read, else 3x2")(
      "step", po::value(&model.step_s)->default_value(model.step_s, "auto"),
      "seconds of data time (t_capture) between two formations, the unit of --horizon; auto: "
      "0.5 for --model motion, 2 (the paper's) for --model paper")(
      "opponent-color", po::value(&model.opponent_color)->default_value(model.opponent_color),
      "the opponent's colour: yellow, blue, or referee (the team the referee's names make the "
      "opponent by --our-team or --opponent-team; yellow until then)")(
      "opponent-attacks", po::value(&model.opponent_attacks)->default_value(model.opponent_attacks),
      "the direction the opponent attacks in the feed's coordinates: +x, -x, referee (the side "
      "the referee gives it, following a change of ends; +x until it does) or auto (the referee's "
      "side, else from where its goalkeeper stands)")(
      "our-team", po::value(&model.our_team)->default_value(model.our_team, "none"),
      "our team's name as the game controller spells it (case aside): the opponent is the other "
      "team")("opponent-team",
              po::value(&model.opponent_team)->default_value(model.opponent_team, "none"),
              "the opponent's name as the game controller spells it (case aside)")(
      "model", po::value(&model.model)->default_value(model.model),
      "auto: the table's where one is read (motion, or paper for a table of the paper's counts "
      "only), else motion; motion: positions in mm with calibrated radii, learned from every frame "
      "(needs a "
      "version-3 table); paper: the paper's Markov model on cells; the baselines, which need no "
      "table: persistence, constant-velocity, constant-acceleration (and, in ssl-evaluate, "
      "damped-constant-velocity and damped-constant-acceleration, fitted on the training part)")(
      "sampling", po::value(&model.sampling)->default_value(model.sampling),
      "step: a formation every --step (the paper's protocol); frame: a formation at every frame, "
      "each robot's previous cell from --step earlier; auto: frame for --model motion, step for "
      "--model paper")("field-length",
                       po::value(&model.field_length_mm)->default_value(model.field_length_mm),
                       "field length in mm until a geometry packet says otherwise")(
      "field-width", po::value(&model.field_width_mm)->default_value(model.field_width_mm),
      "field width in mm until a geometry packet says otherwise")(
      "ignore-geometry", po::bool_switch(&model.ignore_geometry),
      "keep --field-length/--field-width even when geometry packets arrive");
}

void add_recalibration_option(po::options_description& options, double& half_life_s) {
  options.add_options()(
      "recalibration-half-life", po::value(&half_life_s)->default_value(half_life_s),
      "--model motion: seconds of the data clock over which the stated probabilities follow how "
      "often predictions like them came true lately (half the weight is older than this); 0 = "
      "off: as the table's calibration states them");
}

std::optional<OnlineCalibrationSettings> recalibration_settings(double half_life_s) {
  if (half_life_s == 0.0) return std::nullopt;
  OnlineCalibrationSettings settings;
  settings.half_life_s = half_life_s;
  if (!settings.valid()) {
    throw UsageError("--recalibration-half-life must be positive seconds, or 0 for off");
  }
  return settings;
}

void add_vision_source_option(po::options_description& options, NetworkOptions& network) {
  options.add_options()(
      "vision-source", po::value(&network.vision_source)->default_value(network.vision_source),
      "raw: SSL-Vision's detections (on --vision-address, or a log's type-4 messages); tracked: a "
      "tracker's filtered frames (TrackerWrapperPacket, positions in metres; on "
      "--tracker-address, or a log's type-5 messages) instead, one tracker followed by its uuid");
}

void add_network_options(po::options_description& options, NetworkOptions& network, FeedUse use) {
  const bool send = use == FeedUse::send;
  const char* vision = send                     ? "SSL-Vision multicast group:port to send to"
                       : use == FeedUse::record ? "SSL-Vision multicast group:port to record"
                                                : "SSL-Vision multicast group:port to listen on "
                                                  "(grSim: 224.5.23.2:10020)";
  const char* referee =
      send ? "where the simulated game controller's referee messages go, or with --replay the "
             "log's; none: not sent"
      : use == FeedUse::record
          ? "the game controller's referee group, recorded too; none: not recorded"
          : "the game controller's referee multicast group:port, joined on --interface too: the "
            "opponent's name, colour and side and the game state follow it; none: no referee feed";
  const char* tracker = send ? "--replay: where the log's tracked vision goes; none: not sent"
                        : use == FeedUse::record
                            ? "the trackers' group, recorded too; none: not recorded"
                            : "the trackers' multicast group:port (auto-referees such as TIGERs' "
                              "publish there)";
  const char* interface = send ? "IPv4 address of the interface to send from"
                               : "IPv4 address of the interface to join on, or 'all' for every "
                                 "interface";
  options.add_options()(
      "vision-address", po::value(&network.vision_address)->default_value(network.vision_address),
      vision)("referee-address",
              po::value(&network.referee_address)->default_value(network.referee_address), referee)(
      "tracker-address",
      po::value(&network.tracker_address)->default_value(network.tracker_address), tracker)(
      "interface", po::value(&network.interface)->default_value(network.interface), interface);
}

void add_vision_options(po::options_description& options, NetworkOptions& network) {
  add_vision_source_option(options, network);
  add_network_options(options, network, FeedUse::listen);
}

bool NetworkOptions::tracked() const {
  if (vision_source == "raw") return false;
  if (vision_source == "tracked") return true;
  throw UsageError("--vision-source must be raw or tracked, not '" + vision_source + "'");
}

void add_daemon_options(po::options_description& options, DaemonOptions& daemon) {
  options.add_options()(
      "ready-file", po::value(&daemon.ready_file)->value_name("PATH"),
      "write PATH (atomically) once the sockets are open and joined, as key=value lines "
      "(program, pid, ...); removed at exit. For scripts and tests that wait for the daemon");
}

void add_output_options(po::options_description& options, OutputOptions& output,
                        const std::string& what) {
  options.add_options()("output,o", po::value(&output.path)->value_name("PATH"), what.c_str())(
      "overwrite", po::bool_switch(&output.overwrite),
      "replace --output if it exists (it is replaced only when the run succeeds)");
}

namespace {
bool is_written_in_place(const std::string& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  return !error && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status) &&
         !std::filesystem::is_directory(status);
}
}  // namespace

void check_outputs_free(const std::vector<std::string>& paths, bool overwrite) {
  if (overwrite) return;
  for (const std::string& path : paths) {
    if (path.empty() || path == "-" || is_written_in_place(path)) continue;
    std::error_code error;
    if (std::filesystem::exists(path, error)) {
      throw UsageError(path + " exists: give --overwrite to replace it");
    }
  }
}

void check_output_free(const OutputOptions& output) {
  check_outputs_free({output.path}, output.overwrite);
}

void add_horizons_option(po::options_description& options, std::string& horizons,
                         const std::string& what) {
  options.add_options()("horizons", po::value(&horizons)->default_value(horizons),
                        ("seconds ahead, a whole number of --step: the longest horizon (of a "
                         "comma-separated list, the longest); " +
                         what)
                            .c_str());
}

int horizon_steps(const std::string& horizons, double step_s, int auto_steps) {
  if (horizons == "auto") return auto_steps;
  double longest = 0.0;
  std::stringstream list(horizons);
  std::string item;
  while (std::getline(list, item, ',')) {
    std::size_t used = 0;
    double seconds = 0.0;
    try {
      seconds = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(seconds) || seconds <= 0.0) {
      throw UsageError("--horizons takes positive seconds (0.5,1 or 1.5) or auto, not '" +
                       horizons + "'");
    }
    longest = std::max(longest, seconds);
  }
  if (longest <= 0.0) throw UsageError("--horizons takes positive seconds or auto");
  const double steps = longest / step_s;
  const double whole = std::round(steps);
  if (whole < 1.0 || std::abs(steps - whole) > 1e-6) {
    std::ostringstream text;
    text << "--horizons " << horizons << ": " << longest << " s is not a whole number of --step "
         << step_s << " s";
    throw UsageError(text.str());
  }
  return static_cast<int>(whole);
}

void OldSpellings::add(const std::string& old_name, const std::string& new_name,
                       po::value_semantic* value, const std::string& hint) {
  options_.add_options()(old_name.c_str(), value, "");
  renamed_.push_back({old_name, new_name, hint});
}

void OldSpellings::note_used(const std::string& program, const po::variables_map& values) const {
  for (const Renamed& renamed : renamed_) {
    if (values.count(renamed.old_name) == 0 || values[renamed.old_name].defaulted()) continue;
    std::cerr << program << ": note: --" << renamed.old_name << " is now " << renamed.new_name
              << (renamed.hint.empty() ? "" : " (" + renamed.hint + ")")
              << "; the old name works until the next release\n";
  }
}

bool parse_command_line(int argc, const char* const argv[], const po::options_description& options,
                        const std::string& usage_line, const std::string& description,
                        const po::positional_options_description* positional,
                        const OldSpellings* old_spellings) {
  po::options_description all(options);
  all.add_options()("help,h", "show this help with the defaults and exit");
  po::options_description parsed(all);
  if (old_spellings) parsed.add(old_spellings->options());
  po::variables_map values;
  try {
    po::command_line_parser parser(argc, argv);
    parser.options(parsed);
    if (positional) parser.positional(*positional);
    po::store(parser.run(), values);
    if (values.count("help")) {
      std::cout << "Usage: " << usage_line << "\n" << description << "\n\n" << all << "\n";
      return false;
    }
    po::notify(values);
  } catch (const po::error& e) {
    throw UsageError(e.what());
  }
  if (old_spellings) {
    // The program's name is the usage line's first word.
    old_spellings->note_used(usage_line.substr(0, usage_line.find(' ')), values);
  }
  return true;
}

int run_main(const char* program, const std::function<int()>& body) {
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << program << ": error: " << e.what() << " (see " << program << " --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace ssl_formation::app
