// e2e_bench: the end-to-end benchmark of the daemons (issue 3), driven by scripts/bench-e2e.sh.
// A standalone program, not Google Benchmark: it drives processes and sockets. Modes:
//
//   make-table  trains a table from the simulated vision (the library's own code path) and saves
//               it, so the predictor has something to predict from.
//   echo        the floor's "daemon": receives datagrams on one group and re-sends each,
//               unchanged, to another, through the same MulticastReceiver/MulticastSender path
//               the predictor uses, doing no work in between.
//   latency     the producer and the listener: sends SSL_WrapperPackets at a fixed rate to the
//               predictor and, half a period apart, the same packet to the echo (which of the two
//               goes first swaps every 100 packets). Each is timed from just before its send to
//               the reception of the matching prediction (by frame_number) or echoed datagram.
//               Both paths run interleaved in the same run, so they see the same machine.
//               With --replace-table, the table file the predictor follows is replaced every
//               --replace-every seconds meanwhile, as the trainer saves, and the longest gap
//               between two predictions received is reported: a predictor that loads its table
//               on the prediction's path stops predicting for as long as a load takes.
//   pipeline    times, in this process, the work ssl-predictor does for one packet (decode,
//               sample, predict, encode the message: net::VisionReceiver and predictor/main.cpp's
//               on_sample), back to back and after sleeping --idle seconds before each packet, as
//               the daemon does between packets at 60 packets/s: meanwhile the machine runs other
//               work and the caches and TLB go cold, which is most of the daemon's cost.
//   load        sends 4-camera, 6+6-robot packets at a high rate to the vision group, for the
//               trainer and the predictor to keep up with.
//
// Everything sends and joins on 127.0.0.1 (the --interface default) with TTL 1, and every run is

#include "e2e/e2e_modes.hpp"

namespace e2e {

// ---------------------------------------------------------------------------------------------
// make-table

// The paper's model: a formation every `step_s` of the simulated opponent, a version-1 table.
// The motion model (what the predictor runs by default): the same opponent sampled at 60 Hz, a
// formation per frame, into a version-3 table of the predictor's default motion step.
int make_table(const std::string& path, std::uint64_t formations, std::uint64_t seed, double step_s,
               sf::ModelKind model) {
  const bool motion = model == sf::ModelKind::motion;
  sf::simulation::SimulationConfig simulation;
  simulation.seed = seed;
  simulation.step_s = motion ? 1.0 / 60.0 : step_s;
  sf::simulation::SimulatedVision vision(simulation);
  sf::SamplerConfig config;
  config.step_s = motion ? sf::describe(sf::ModelKind::motion).default_step_s : step_s;
  config.field = simulation.field;
  std::optional<sf::MotionTable> motion_table;
  if (motion) {
    config.sampling = sf::Sampling::frame;
    sf::MotionConfig motion_config;
    motion_config.step_s = config.step_s;
    motion_table.emplace(motion_config);
  }
  sf::Training training(config, sf::TransitionTable(config.grid), 0, std::move(motion_table));
  for (std::uint64_t i = 0; i < formations; ++i) {
    for (const SSL_WrapperPacket& packet : vision.next().packets) training.add(packet);
  }
  sf::TableMetadata metadata;
  metadata.field = training.sampler().field();
  metadata.step_s = config.step_s;
  metadata.samples = training.samples();
  const auto saved = sf::save_table(path, training.stored_table(metadata));
  if (!saved) {
    std::cerr << "e2e_bench make-table: " << saved.error().message << '\n';
    return 1;
  }
  if (!saved->durable) std::cerr << "e2e_bench make-table: " << saved->warning << '\n';
  std::cout << "make-table path=" << path << " model=" << sf::to_string(model)
            << " formations=" << training.samples()
            << " transitions=" << training.table_summary().transitions
            << " states_seen=" << training.table_summary().states_seen << " motion_instances="
            << (training.table_summary().motion ? training.table_summary().motion->instances : 0)
            << '\n';
  return 0;
}

// ---------------------------------------------------------------------------------------------
// echo

int run_echo(const std::string& in, const std::string& out, const std::string& interface_text,
             double seconds, int receive_buffer) {
  const auto interface = interface_option(interface_text);
  const auto in_group = group_option("echo-in", in);
  const auto out_group = group_option("echo-out", out);
  // Echoing into its own group would loop for ever.
  if (in_group == out_group) throw sf::app::UsageError("--echo-in and --echo-out must differ");
  boost::asio::io_context io;
  sf::net::MulticastSender sender(io, out_group, interface.address, sf::net::kDefaultMulticastTtl);
  sender.open();
  sf::net::MulticastReceiver receiver(io, in_group, interface, receive_buffer);
  receiver.start(
      [&](std::span<const std::byte> data, const sf::net::udp::endpoint&) { sender.send(data); });
  boost::asio::steady_timer deadline(io, sf::app::seconds_option("seconds", seconds));
  deadline.async_wait([&](const boost::system::error_code& error) {
    if (error) return;
    spdlog::info("--seconds {} reached: stopping", seconds);
    receiver.stop();
    io.stop();
  });
  sf::app::StopSignals signals(io, [&](int signal) {
    spdlog::info("signal {}: stopping", signal);
    receiver.stop();
    deadline.cancel();
    io.stop();
  });
  io.run();
  spdlog::info("status: packets={} kernel_drops={} sent={} send_errors={}",
               receiver.counters().datagrams.load(), receiver.counters().kernel_drops.load(),
               sender.sent(), sender.send_errors());
  return 0;
}

}  // namespace e2e

using namespace e2e;

int main(int argc, char** argv) {
  return sf::app::run_main("e2e_bench", [&]() -> int {
    std::string mode;
    std::string table = "e2e-bench-table.bin";
    std::uint64_t formations = 3000;
    std::uint64_t seed = 0;
    double step_s = 2.0;
    std::string model = "motion";
    std::string echo_in = kEchoInGroup;
    std::string echo_out = kEchoOutGroup;
    double seconds = 0.0;
    int receive_buffer = sf::net::kDefaultReceiveBufferBytes;
    LatencyOptions latency;
    LoadOptions load;
    std::string interface = sf::app::default_interface;
    std::string vision_address = kVisionGroup;
    double rate = 0.0;
    bool verbose = false;
    std::size_t pipeline_packets = 300;
    double idle_s = 1.0 / 60.0;

    po::options_description general("Options (each mode uses the ones that concern it)");
    general.add_options()("mode", po::value(&mode)->required(),
                          "make-table, echo, latency, pipeline or load")(
        "interface", po::value(&interface)->default_value(interface),
        "IPv4 address to send from and join on")(
        "vision-address", po::value(&vision_address)->default_value(vision_address),
        "latency, load: group:port the daemons read vision from")(
        "prediction-address",
        po::value(&latency.prediction_address)->default_value(latency.prediction_address),
        "latency: group:port the predictor sends to")("echo-in",
                                                      po::value(&echo_in)->default_value(echo_in),
                                                      "echo, latency: group:port the echo reads")(
        "echo-out", po::value(&echo_out)->default_value(echo_out),
        "echo, latency: group:port the echo sends to")(
        "rate", po::value(&rate),
        "latency: packets/s per path (default 60); load: packets/s (default 20000)")(
        "seconds", po::value(&seconds),
        "latency: sending time (default 10); load: sending time (default 5); echo: lifetime "
        "(default 300)")("warmup", po::value(&latency.warmup)->default_value(latency.warmup),
                         "latency: first packets of each path left out of the figures")(
        "step", po::value(&step_s)->default_value(step_s),
        "latency, pipeline: data-clock seconds between packets (1/60 for the motion model's "
        "frames; the predictor's --step for the paper's); make-table --model paper: the "
        "table's step")(
        "model", po::value(&model)->default_value(model),
        "make-table: motion (a version-3 table at the predictor's default motion step, trained "
        "on 60 Hz frames) or paper (a version-1 table)")(
        "spin-us", po::value(&latency.spin_us)->default_value(latency.spin_us),
        "latency: microseconds spun before each send instead of slept")(
        "drain", po::value(&latency.drain_s)->default_value(latency.drain_s),
        "latency: seconds to wait for the last replies")(
        "no-echo", po::bool_switch(&latency.no_echo), "latency: time the predictor alone")(
        "no-predictor", po::bool_switch(&latency.no_predictor), "latency: time the echo alone")(
        "replace-table", po::value(&latency.replace_table)->value_name("FILE"),
        "latency: the table file the predictor follows, replaced during the run (written "
        "beside it, then renamed over it, as ssl-trainer saves); prints the longest gap "
        "between two predictions")(
        "replace-from", po::value(&latency.replace_from)->value_name("FILE"),
        "latency: the table written over --replace-table (default: --replace-table as it was "
        "at the start)")(
        "replace-every",
        po::value(&latency.replace_every_s)->default_value(latency.replace_every_s),
        "latency: seconds between two replacements of --replace-table")(
        "packets", po::value(&pipeline_packets)->default_value(pipeline_packets),
        "pipeline: packets to time each way")("idle",
                                              po::value(&idle_s)->default_value(idle_s, "1/60"),
                                              "pipeline: seconds slept before each timed packet")(
        "cameras", po::value(&load.cameras)->default_value(load.cameras), "load: cameras")(
        "frame-dt", po::value(&load.frame_dt_s)->default_value(load.frame_dt_s),
        "load: data-clock seconds per camera frame (2 = the predictor's step: every frame "
        "completes a formation)")("table", po::value(&table)->default_value(table),
                                  "make-table: file to write; pipeline: table to predict from")(
        "formations", po::value(&formations)->default_value(formations),
        "make-table: formations to train on")("seed", po::value(&seed), "simulated vision seed")(
        "receive-buffer", po::value(&receive_buffer)->default_value(receive_buffer),
        "echo: SO_RCVBUF to request, bytes")("verbose", po::bool_switch(&verbose),
                                             "more log lines");
    po::positional_options_description positional;
    positional.add("mode", 1);
    if (!sf::app::parse_command_line(argc, argv, general, "e2e_bench MODE [options]",
                                     "End-to-end benchmark helper for scripts/bench-e2e.sh.",
                                     &positional)) {
      return 0;
    }
    sf::app::init_logging("e2e_bench", verbose);
    if (!verbose) spdlog::set_level(spdlog::level::warn);

    if (mode == "make-table") {
      const auto kind = sf::parse_model(model);
      if (!kind) throw sf::app::UsageError("--model must be motion or paper, not '" + model + "'");
      return make_table(table, formations, seed ? seed : 1, step_s, *kind);
    }
    if (mode == "pipeline") {
      if (pipeline_packets < 1 || pipeline_packets > 100000)
        throw sf::app::UsageError("--packets must be 1 to 100000");
      if (!(idle_s >= 0 && idle_s <= 1)) throw sf::app::UsageError("--idle must be 0 to 1");
      return run_pipeline(table, pipeline_packets, step_s, seed ? seed : 7, idle_s);
    }
    if (mode == "echo") {
      spdlog::set_level(spdlog::level::info);  // the script waits for "listening on"
      return run_echo(echo_in, echo_out, interface, seconds > 0 ? seconds : 300.0, receive_buffer);
    }
    if (mode == "latency") {
      latency.interface = interface;
      latency.vision_address = vision_address;
      latency.echo_in = echo_in;
      latency.echo_out = echo_out;
      latency.step_s = step_s;
      if (rate > 0) latency.rate = rate;
      if (seconds > 0) latency.seconds = seconds;
      if (seed) latency.seed = seed;
      return run_latency(latency);
    }
    if (mode == "load") {
      load.interface = interface;
      load.vision_address = vision_address;
      if (rate > 0) load.rate = rate;
      if (seconds > 0) load.seconds = seconds;
      if (seed) load.seed = seed;
      if (load.cameras < 1 || load.cameras > 8)
        throw sf::app::UsageError("--cameras must be 1 to 8");
      return run_load(load);
    }
    throw sf::app::UsageError("unknown mode '" + mode +
                              "': make-table, echo, latency, pipeline or load");
  });
}
