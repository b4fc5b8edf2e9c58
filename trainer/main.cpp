// ssl-trainer: listens to the vision feed, samples the opponent's formations and counts state
// transitions into a table file that ssl-predictor reads.

#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>

#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/app/progress.hpp"
#include "ssl_formation/log_file.hpp"
#include "ssl_formation/net/vision_receiver.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "table_store.hpp"

namespace sf = ssl_formation;
namespace po = boost::program_options;

namespace {

struct TrainerOptions {
  sf::app::ModelOptions model;
  sf::app::NetworkOptions network;
  std::string table = sf::app::default_table;
  double flush_interval_s = 10.0;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = sf::net::kDefaultReceiveBufferBytes;
  bool reset = false;
  bool verbose = false;
  std::vector<std::string> from_logs;
};

// Logs above this size get a progress bar.
constexpr std::uint64_t progress_bar_bytes = 4 << 20;

// One status line, then a warning for each kind of bad input that arrived since the last one.
void log_status(const sf::Training& training, const sf::net::ReceiverCounters& net,
                sf::SamplerCounters& reported) {
  const sf::SamplerCounters& c = training.sampler().counters();
  spdlog::info(
      "status: packets={} parse_errors={} kernel_drops={} formations={} transitions={} "
      "table_transitions={} states_seen={} rejected_robots={} late_frames={} | {}",
      net.datagrams.load(), net.parse_errors.load(), net.kernel_drops.load(), c.samples,
      c.transitions, training.table().transitions(), training.table().rows_seen(),
      c.robots_non_finite + c.robots_out_of_range + c.robots_bad_id, c.frames_late,
      sf::describe_rejections(c));
  for (const std::string& line : sf::new_rejections(reported, c)) spdlog::warn("input: {}", line);
  reported = c;
}

int run_live(const TrainerOptions& options) {
  const sf::SamplerConfig config = options.model.sampler_config();
  const auto group = sf::app::parse_group_option("vision-address", options.network.vision_address);
  const auto interface = sf::app::parse_interface_option(options.network.interface, true);
  const auto flush_period = sf::app::seconds_option("flush-interval", options.flush_interval_s);
  const auto status_period = sf::app::seconds_option("status-interval", options.status_interval_s);

  const std::filesystem::path table_path = options.table;
  std::unique_ptr<sf::Training> training =
      sf::trainer::open_training(table_path, config, options.reset);

  boost::asio::io_context io;
  sf::net::VisionReceiver receiver(io, group, interface, options.receive_buffer_bytes);
  receiver.start(
      [&](const sf::VisionFrame& frame, const sf::net::udp::endpoint&) { training->add(frame); });
  spdlog::info("training: opponent {} attacking {}; grid {}, step {} s; table {} saved every {} s",
               sf::to_string(config.opponent_color), sf::to_string(config.opponent_attacks),
               config.grid.to_string(), config.step_s, table_path.string(),
               options.flush_interval_s);

  sf::app::RepeatingTimer flush(io, flush_period, [&] {
    if (training->changed_since_save()) sf::trainer::save_training(table_path, *training);
  });
  sf::SamplerCounters reported;
  sf::app::RepeatingTimer status(io, status_period,
                                 [&] { log_status(*training, receiver.counters(), reported); });
  bool saved_on_exit = true;
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: saving and stopping", signal);
    receiver.stop();
    flush.cancel();
    status.cancel();
    saved_on_exit = sf::trainer::save_training(table_path, *training);
    io.stop();
  });
  io.run();
  log_status(*training, receiver.counters(), reported);
  return saved_on_exit ? 0 : 1;
}

// Trains from official log files without the network, through the same Training the live path
// uses. Everything read before a damaged part of a file is kept; the exit status says so.
int run_offline(const TrainerOptions& options) {
  const sf::SamplerConfig config = options.model.sampler_config();
  const std::filesystem::path table_path = options.table;
  std::unique_ptr<sf::Training> training =
      sf::trainer::open_training(table_path, config, options.reset);
  bool every_file_whole = true;
  SSL_WrapperPacket packet;
  for (const std::string& file : options.from_logs) {
    std::string error;
    std::optional<sf::LogReader> reader = sf::LogReader::open(file, &error);
    if (!reader) {
      spdlog::error("{}", error);
      every_file_whole = false;
      continue;
    }
    training->start_new_stream();
    const std::uint64_t transitions_before = training->table().transitions();
    const std::uint64_t samples_before = training->samples();
    std::optional<sf::app::ProgressBar> bar;
    if (reader->compressed_size() > progress_bar_bytes)
      bar.emplace("training from " + file, reader->compressed_size());
    std::uint64_t frames = 0;
    while (reader->next_vision(packet)) {
      training->add(packet);
      if ((++frames & 4095) == 0 && bar) bar->update(reader->compressed_offset(), frames);
    }
    if (bar) bar->finish(frames);
    const sf::LogReadCounters& c = reader->counters();
    spdlog::info(
        "{}: {} vision packets ({} parse errors), skipped {} referee, {} tracker, {} other; "
        "{} formations, {} transitions",
        file, frames, c.parse_errors, c.referee, c.tracker, c.unknown + c.blank + c.legacy_unusable,
        training->samples() - samples_before, training->table().transitions() - transitions_before);
    if (!reader->error().empty()) {
      spdlog::error("{}; the {} vision packets before it were used", reader->error(), frames);
      every_file_whole = false;
    }
  }
  if (!sf::trainer::save_training(table_path, *training)) return 1;
  spdlog::info("saved {}: {} transitions from {} formations, {} states seen", table_path.string(),
               training->table().transitions(), training->samples(), training->table().rows_seen());
  return every_file_whole ? 0 : 1;
}

// ssl-trainer merge A B ... -o OUT: adds up tables of the same grid and step.
int run_merge(int argc, const char* const argv[]) {
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
  if (inputs.empty()) throw sf::app::UsageError("merge needs at least one input table");
  sf::TableLoadResult first = sf::load_table(inputs.front());
  if (!first) throw std::runtime_error(first.message);
  sf::StoredTable merged = std::move(*first.stored);
  for (std::size_t i = 1; i < inputs.size(); ++i) {
    sf::TableLoadResult next = sf::load_table(inputs[i], merged.table.grid());
    if (!next) {
      throw std::runtime_error(
          next.message +
          (next.error == sf::TableFileError::wrong_grid
               ? " (the grid of " + inputs.front() + "): tables of different grids cannot be merged"
               : std::string()));
    }
    if (next.stored->metadata.step_s != merged.metadata.step_s) {
      throw std::runtime_error(fmt::format(
          "{} was trained with a step of {} s, {} with {} s: their transitions cannot be added up",
          inputs[i], next.stored->metadata.step_s, inputs.front(), merged.metadata.step_s));
    }
    merged.table.merge(next.stored->table);
    merged.metadata.samples += next.stored->metadata.samples;
  }
  const sf::TableSaveResult saved = sf::save_table(output, merged.table, merged.metadata);
  if (!saved) throw std::runtime_error(saved.message);
  spdlog::info("merged {} tables into {}: grid {}, {} transitions from {} formations",
               inputs.size(), output, merged.table.grid().to_string(), merged.table.transitions(),
               merged.metadata.samples);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sf::app::run_main("ssl-trainer", [&] {
    if (argc > 1 && std::string_view(argv[1]) == "merge") {
      sf::app::init_logging("ssl-trainer");
      return run_merge(argc - 1, argv + 1);
    }
    TrainerOptions options;
    po::options_description general("Options");
    general.add_options()("table", po::value(&options.table)->default_value(options.table),
                          "table file to resume and save (written atomically)")(
        "reset", po::bool_switch(&options.reset),
        "start an empty table even if --table holds one of another grid or step")(
        "flush-interval",
        po::value(&options.flush_interval_s)->default_value(options.flush_interval_s),
        "seconds between saves of the table (it is also saved on SIGINT/SIGTERM)")(
        "status-interval",
        po::value(&options.status_interval_s)->default_value(options.status_interval_s),
        "seconds between status lines on stderr")(
        "receive-buffer",
        po::value(&options.receive_buffer_bytes)->default_value(options.receive_buffer_bytes),
        "socket receive buffer (SO_RCVBUF) to request, bytes")(
        "verbose", po::bool_switch(&options.verbose), "log every save")(
        "from-log", po::value(&options.from_logs)->multitoken(),
        "train from these official SSL log files (.log or .log.gz) instead of the network, "
        "save the table and exit");
    sf::app::add_vision_options(general, options.network);
    sf::app::add_model_options(general, options.model);
    if (!sf::app::parse_command_line(
            argc, argv, general,
            "ssl-trainer [options]\n       ssl-trainer --from-log FILE... [options]\n"
            "       ssl-trainer merge TABLE... -o OUT",
            "Counts the opponent's formation transitions from the vision feed (or from logs) "
            "into a table file.")) {
      return 0;
    }
    sf::app::init_logging("ssl-trainer", options.verbose);
    if (!options.from_logs.empty()) return run_offline(options);
    return run_live(options);
  });
}
