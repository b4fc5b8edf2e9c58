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
// bounded in count and time.

#include <spdlog/spdlog.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "formation_prediction.pb.h"
#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/app/options.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace sf = ssl_formation;
namespace po = boost::program_options;
using Clock = std::chrono::steady_clock;

namespace {

// Benchmark groups, apart from the defaults (10006, 10040) so a running demo does not interfere,
// and from the tests' 224.5.23.100-199.
constexpr const char* kVisionGroup = "224.5.23.210:10210";
constexpr const char* kPredictionGroup = "224.5.23.211:10211";
constexpr const char* kEchoInGroup = "224.5.23.212:10212";
constexpr const char* kEchoOutGroup = "224.5.23.213:10213";

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// Sleeps until `spin_ns` before the deadline, then spins: sleeping alone wakes tens of
// microseconds late, spinning alone would take a whole core from the daemons under test. The
// send time is recorded after this returns, so lateness shifts the schedule, never a latency.
void wait_until(std::int64_t deadline_ns, std::int64_t spin_ns) {
  for (;;) {
    const std::int64_t now = now_ns();
    if (now >= deadline_ns) return;
    if (deadline_ns - now > spin_ns) {
      // steady_clock is CLOCK_MONOTONIC on Linux.
      const std::int64_t wake = deadline_ns - spin_ns;
      timespec until{static_cast<time_t>(wake / 1'000'000'000),
                     static_cast<long>(wake % 1'000'000'000)};
      ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
    }
  }
}

// The default timer slack (50 us) would make every sleep that late.
void tighten_timer_slack() { ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); }

std::span<const std::byte> bytes_of(const std::string& text) {
  return std::as_bytes(std::span(text.data(), text.size()));
}

sf::net::MulticastEndpoint group_option(const std::string& name, const std::string& text) {
  return sf::app::parse_group_option(name, text);
}

// Only one interface address, never "all": this program sends and joins on one interface.
sf::net::InterfaceChoice interface_option(const std::string& text) {
  return sf::app::parse_interface_option(text, false);
}

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

// ---------------------------------------------------------------------------------------------
// latency

struct PathTimes {
  explicit PathTimes(std::size_t n) : sent(n), received(n) {
    for (auto& t : sent) t.store(0, std::memory_order_relaxed);
    for (auto& t : received) t.store(0, std::memory_order_relaxed);
  }
  // Written by the sending thread (before the send) and read by the receiving one.
  std::vector<std::atomic<std::int64_t>> sent;
  std::vector<std::atomic<std::int64_t>> received;
  std::atomic<std::uint64_t> unmatched{0};   // frame numbers never sent on this path
  std::atomic<std::uint64_t> duplicates{0};  // a second reply for the same frame

  void record(std::uint32_t frame_number, std::int64_t at_ns) {
    // Frame numbers start at 1.
    if (frame_number == 0 || frame_number > sent.size() ||
        sent[frame_number - 1].load(std::memory_order_acquire) == 0) {
      unmatched.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    std::int64_t expected = 0;
    if (!received[frame_number - 1].compare_exchange_strong(expected, at_ns,
                                                            std::memory_order_relaxed)) {
      duplicates.fetch_add(1, std::memory_order_relaxed);
    }
  }
};

struct Summary {
  std::size_t counted = 0;
  std::size_t lost = 0;
  double p50_us = 0, p90_us = 0, p99_us = 0, max_us = 0, mean_us = 0;
};

// Nearest-rank percentile of a sorted sample.
double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return std::nan("");
  const auto rank =
      static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

Summary summarise(const PathTimes& times, std::size_t skip) {
  Summary s;
  std::vector<double> latencies;
  latencies.reserve(times.sent.size());
  for (std::size_t i = skip; i < times.sent.size(); ++i) {
    const std::int64_t sent = times.sent[i].load();
    const std::int64_t received = times.received[i].load();
    if (sent == 0) continue;
    if (received == 0) {
      ++s.lost;
      continue;
    }
    latencies.push_back(static_cast<double>(received - sent) / 1000.0);
  }
  std::sort(latencies.begin(), latencies.end());
  s.counted = latencies.size();
  s.p50_us = percentile(latencies, 50);
  s.p90_us = percentile(latencies, 90);
  s.p99_us = percentile(latencies, 99);
  s.max_us = latencies.empty() ? std::nan("") : latencies.back();
  double sum = 0;
  for (double v : latencies) sum += v;
  s.mean_us = latencies.empty() ? std::nan("") : sum / static_cast<double>(latencies.size());
  return s;
}

void print_summary(const char* path, double rate, const Summary& s, const PathTimes& times) {
  std::printf(
      "latency path=%s rate=%g n=%zu lost=%zu unmatched=%llu duplicates=%llu p50_us=%.1f "
      "p90_us=%.1f p99_us=%.1f max_us=%.1f mean_us=%.1f\n",
      path, rate, s.counted, s.lost, static_cast<unsigned long long>(times.unmatched.load()),
      static_cast<unsigned long long>(times.duplicates.load()), s.p50_us, s.p90_us, s.p99_us,
      s.max_us, s.mean_us);
}

struct LatencyOptions {
  double rate = 60.0;
  double seconds = 10.0;
  std::size_t warmup = 10;
  std::string vision_address = kVisionGroup;
  std::string prediction_address = kPredictionGroup;
  std::string echo_in = kEchoInGroup;
  std::string echo_out = kEchoOutGroup;
  std::string interface = sf::app::default_interface;
  double step_s = 2.0;
  double start_time_s = 1000.0;
  std::uint64_t seed = 7;
  double spin_us = 30.0;
  double drain_s = 0.5;
  bool no_echo = false;
  bool no_predictor = false;
  // The table file the predictor follows, replaced during the run by a copy of replace_from
  // (of itself as it was at the start when empty); empty: never replaced.
  std::string replace_table;
  std::string replace_from;
  double replace_every_s = 2.0;
};

// Replaces a table file on a schedule of its own thread, as the trainer saves: the new file is
// written beside the old one, then renamed over it, so the predictor sees a new file each time.
class TableReplacer {
 public:
  TableReplacer(const std::string& target, const std::string& from, double every_s)
      : target_(target),
        // A copy taken now, so that replacing the file with itself changes nothing but its
        // identity.
        source_(from.empty() ? target + ".e2e-bench-source" : from),
        owns_source_(from.empty()),
        every_(
            std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(every_s))) {
    if (owns_source_) {
      std::filesystem::copy_file(target_, source_,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    thread_ = std::thread([this] { run(); });
  }
  TableReplacer(const TableReplacer&) = delete;
  TableReplacer& operator=(const TableReplacer&) = delete;
  ~TableReplacer() {
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    stop_.notify_all();
    thread_.join();
    std::error_code ignored;
    if (owns_source_) std::filesystem::remove(source_, ignored);
    std::filesystem::remove(target_ + ".e2e-bench-new", ignored);
  }
  std::uint64_t replacements() const { return replacements_.load(); }

 private:
  void run() {
    std::unique_lock lock(mutex_);
    for (Clock::time_point next = Clock::now() + every_;; next += every_) {
      if (stop_.wait_until(lock, next, [this] { return stopping_; })) return;
      // A failed copy (a full disk) leaves the file as it was: fewer replacements are counted.
      const std::string written = target_ + ".e2e-bench-new";
      std::error_code error;
      std::filesystem::copy_file(source_, written,
                                 std::filesystem::copy_options::overwrite_existing, error);
      if (!error) std::filesystem::rename(written, target_, error);
      if (!error) replacements_.fetch_add(1);
    }
  }

  std::string target_;
  std::string source_;
  bool owns_source_;
  Clock::duration every_;
  std::mutex mutex_;
  std::condition_variable stop_;
  bool stopping_ = false;
  std::atomic<std::uint64_t> replacements_{0};
  std::thread thread_;
};

// The longest time between two sends or two receptions of `times` (after `skip`).
double longest_gap_ms(const std::vector<std::atomic<std::int64_t>>& times, std::size_t skip) {
  std::vector<std::int64_t> at;
  for (std::size_t i = skip; i < times.size(); ++i) {
    if (const std::int64_t t = times[i].load(); t != 0) at.push_back(t);
  }
  std::sort(at.begin(), at.end());
  std::int64_t longest = 0;
  for (std::size_t i = 1; i < at.size(); ++i) longest = std::max(longest, at[i] - at[i - 1]);
  return static_cast<double>(longest) / 1e6;
}

// The longest time between two predictions received (after `skip`): how long the predictor
// stopped predicting, whatever stopped it. The sender's own longest gap goes with it: on a busy
// machine the sender itself is sometimes late by more than the predictor ever is.
void print_gaps(const PathTimes& times, std::size_t skip, std::uint64_t replacements) {
  std::printf("gaps path=predictor replacements=%llu longest_ms=%.2f sender_longest_ms=%.2f\n",
              static_cast<unsigned long long>(replacements), longest_gap_ms(times.received, skip),
              longest_gap_ms(times.sent, skip));
}

// One detection packet per formation of a one-camera simulated feed, t_capture advancing by one
// step each, so every packet completes one sample and the predictor answers every packet.
std::vector<std::string> latency_packets(const LatencyOptions& o, std::size_t count) {
  sf::simulation::SimulationConfig simulation;
  simulation.seed = o.seed;
  simulation.step_s = o.step_s;
  simulation.start_time_s = o.start_time_s;
  simulation.cameras = 1;
  sf::simulation::SimulatedVision vision(simulation);
  std::vector<std::string> packets;
  packets.reserve(count);
  while (packets.size() < count) {
    for (SSL_WrapperPacket& packet : vision.next().packets) {
      if (!packet.has_detection()) continue;  // geometry: the default field is the same
      packet.mutable_detection()->set_frame_number(static_cast<std::uint32_t>(packets.size() + 1));
      packets.push_back(packet.SerializeAsString());
    }
  }
  return packets;
}

int run_latency(const LatencyOptions& o) {
  if (!(o.rate > 0 && o.rate <= 100000)) throw sf::app::UsageError("--rate must be 0 to 100000");
  if (!(o.seconds > 0 && o.seconds <= 600)) throw sf::app::UsageError("--seconds must be 0 to 600");
  const auto count = static_cast<std::size_t>(std::llround(o.rate * o.seconds));
  if (count <= o.warmup) throw sf::app::UsageError("--rate * --seconds must exceed --warmup");
  if (!o.replace_table.empty() && !(o.replace_every_s >= 0.1 && o.replace_every_s <= 600)) {
    throw sf::app::UsageError("--replace-every must be 0.1 to 600 seconds");
  }
  const auto interface = interface_option(o.interface);
  const std::vector<std::string> packets = latency_packets(o, count);

  PathTimes predictor_times(count);
  PathTimes echo_times(count);

  boost::asio::io_context receive_io;  // run by the receiving thread
  boost::asio::io_context send_io;     // never run: the senders send synchronously
  sf::net::MulticastReceiver predictions(
      receive_io, group_option("prediction-address", o.prediction_address), interface);
  sf::net::MulticastReceiver echoes(receive_io, group_option("echo-out", o.echo_out), interface);
  sf::net::MulticastSender to_predictor(send_io, group_option("vision-address", o.vision_address),
                                        interface.address);
  sf::net::MulticastSender to_echo(send_io, group_option("echo-in", o.echo_in), interface.address);

  // The time is taken first, before decoding, so both paths pay the same for it.
  sf::proto::FormationPrediction prediction;
  SSL_WrapperPacket echoed;
  if (!o.no_predictor) {
    to_predictor.open();
    predictions.start([&](std::span<const std::byte> data, const sf::net::udp::endpoint&) {
      const std::int64_t at = now_ns();
      if (prediction.ParseFromArray(data.data(), static_cast<int>(data.size()))) {
        predictor_times.record(prediction.frame_number(), at);
      } else {
        predictor_times.unmatched.fetch_add(1, std::memory_order_relaxed);
      }
    });
  }
  if (!o.no_echo) {
    to_echo.open();
    echoes.start([&](std::span<const std::byte> data, const sf::net::udp::endpoint&) {
      const std::int64_t at = now_ns();
      if (echoed.ParseFromArray(data.data(), static_cast<int>(data.size())) &&
          echoed.has_detection()) {
        echo_times.record(echoed.detection().frame_number(), at);
      } else {
        echo_times.unmatched.fetch_add(1, std::memory_order_relaxed);
      }
    });
  }
  // Before the receiving thread: a table that cannot be copied ends the run here.
  std::optional<TableReplacer> replacer;
  if (!o.replace_table.empty()) {
    replacer.emplace(o.replace_table, o.replace_from, o.replace_every_s);
  }
  std::thread receiving([&] { receive_io.run(); });

  tighten_timer_slack();
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / o.rate));
  const auto spin_ns = static_cast<std::int64_t>(o.spin_us * 1000.0);
  const std::int64_t start = now_ns() + 100'000'000;  // 100 ms for the receivers to settle
  std::int64_t latest_start_ns = 0;
  // Each path's packets go one period apart, the two paths half a period apart: interleaved, so
  // both see the same machine, and apart, so neither queues behind the other. Which path goes on
  // the period and which half a period later swaps every kBlock packets, so that neither always
  // follows the other (whatever the other's wake-up leaves behind, warm or busy, both get it);
  // at each swap one path's packets come half a period apart, the other's one and a half.
  constexpr std::size_t kBlock = 100;
  const auto send = [&](PathTimes& times, sf::net::MulticastSender& to, std::size_t i,
                        std::int64_t due) {
    wait_until(due, spin_ns);
    const std::int64_t at = now_ns();
    latest_start_ns = std::max(latest_start_ns, at - due);
    times.sent[i].store(at, std::memory_order_release);
    to.send(bytes_of(packets[i]));
  };
  for (std::size_t i = 0; i < count; ++i) {
    const std::int64_t due = start + static_cast<std::int64_t>(i) * period_ns;
    const std::int64_t half_later = due + period_ns / 2;
    // One path alone keeps to the period: a swap would put one and a half periods between two
    // of its packets, which --replace-table would count as a gap.
    const bool predictor_on_the_period = o.no_echo || (!o.no_predictor && (i / kBlock) % 2 == 0);
    const std::int64_t predictor_due = predictor_on_the_period ? due : half_later;
    const std::int64_t echo_due = predictor_on_the_period ? half_later : due;
    if (predictor_on_the_period && !o.no_predictor) {
      send(predictor_times, to_predictor, i, predictor_due);
    }
    if (!o.no_echo) send(echo_times, to_echo, i, echo_due);
    if (!predictor_on_the_period && !o.no_predictor) {
      send(predictor_times, to_predictor, i, predictor_due);
    }
  }
  const double achieved_s = static_cast<double>(now_ns() - start) / 1e9;
  const std::uint64_t replacements = replacer ? replacer->replacements() : 0;
  replacer.reset();
  std::this_thread::sleep_for(std::chrono::duration<double>(o.drain_s));
  receive_io.stop();
  receiving.join();

  std::printf(
      "latency run rate=%g seconds=%.2f packets_per_path=%zu warmup=%zu latest_send_us=%.1f "
      "predictor_kernel_drops=%llu echo_kernel_drops=%llu\n",
      o.rate, achieved_s, count, o.warmup, static_cast<double>(latest_start_ns) / 1000.0,
      static_cast<unsigned long long>(predictions.counters().kernel_drops.load()),
      static_cast<unsigned long long>(echoes.counters().kernel_drops.load()));
  if (!o.no_echo) print_summary("floor", o.rate, summarise(echo_times, o.warmup), echo_times);
  if (!o.no_predictor) {
    print_summary("predictor", o.rate, summarise(predictor_times, o.warmup), predictor_times);
    if (!o.replace_table.empty()) print_gaps(predictor_times, o.warmup, replacements);
  }
  std::fflush(stdout);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// pipeline

int run_pipeline(const std::string& table_path, std::size_t count, double step_s,
                 std::uint64_t seed, double idle_s) {
  auto loaded = sf::load_table(table_path);
  if (!loaded) {
    std::cerr << "e2e_bench pipeline: " << loaded.error().message << '\n';
    return 1;
  }
  sf::StoredTable& stored = *loaded;
  LatencyOptions o;
  o.step_s = step_s;
  o.seed = seed;
  const std::vector<std::string> packets = latency_packets(o, 2 * count);

  // The predictor's per-packet path: net::VisionReceiver's decode, then the PredictionPipeline
  // and the encoding the daemon runs, with their buffers reused the same way.
  // The model the table serves (a version-3 table: the motion model, the daemon's default), at
  // the table's own step; `step_s` is the data-clock time between packets.
  sf::PredictionConfig config;
  config.sampler.grid = stored.table.grid();
  config.sampler.step_s = stored.metadata.step_s;
  config.model = stored.motion ? sf::ModelKind::motion : sf::ModelKind::paper;
  config.sampler.sampling = stored.motion ? sf::Sampling::frame : sf::Sampling::step;
  std::string encoded;
  encoded.reserve(2048);
  std::uint64_t predictions = 0;
  // Stage times of the current packet: decode, sample and predict, encode.
  std::array<std::int64_t, 4> marks{};
  sf::PredictionPipeline pipeline(config, [&](const sf::PredictedFormation& predicted) {
    marks[2] = now_ns();
    sf::encode_prediction(predicted.formation(), predicted.prediction, predicted.context, encoded);
    marks[3] = now_ns();
    ++predictions;
  });
  pipeline.set_table(std::make_shared<const sf::StoredTable>(std::move(stored)));
  // As net::VisionReceiver: detection packets decoded straight from the bytes, anything else
  // by protobuf.
  sf::VisionFrame frame;
  SSL_WrapperPacket parsed;
  std::array<std::vector<double>, 3> idle_stages;
  const auto one = [&](const std::string& bytes) {
    marks = {};
    marks[0] = now_ns();
    if (sf::read_vision_datagram(bytes_of(bytes), frame, parsed) != sf::VisionDatagram::invalid) {
      marks[1] = now_ns();
      pipeline.add(frame);
    }
    return static_cast<double>(now_ns() - marks[0]) / 1000.0;
  };
  // First every packet after sleeping as a daemon does between packets at 60 packets/s (its
  // caches and TLB go cold meanwhile: the machine runs other work), then as many back to back.
  std::vector<double> warm, idle;
  for (std::size_t i = 0; i < count; ++i) {
    std::this_thread::sleep_for(std::chrono::duration<double>(idle_s));
    idle.push_back(one(packets[i]));
    if (marks[3] != 0) {
      for (std::size_t k = 0; k < idle_stages.size(); ++k) {
        idle_stages[k].push_back(static_cast<double>(marks[k + 1] - marks[k]) / 1000.0);
      }
    }
  }
  for (std::size_t i = count; i < 2 * count; ++i) warm.push_back(one(packets[i]));
  std::sort(warm.begin(), warm.end());
  std::sort(idle.begin(), idle.end());
  std::printf(
      "pipeline packets=%zu predictions=%llu message_bytes=%zu warm_p50_us=%.2f warm_p99_us=%.2f "
      "idle_p50_us=%.2f idle_p99_us=%.2f idle_ms=%.1f\n",
      count, static_cast<unsigned long long>(predictions), encoded.size(), percentile(warm, 50),
      percentile(warm, 99), percentile(idle, 50), percentile(idle, 99), idle_s * 1000.0);
  const char* names[] = {"decode", "sample+predict", "encode"};
  std::printf("pipeline stage medians after idling (us):");
  for (std::size_t k = 0; k < idle_stages.size(); ++k) {
    std::sort(idle_stages[k].begin(), idle_stages[k].end());
    std::printf(" %s=%.2f", names[k], percentile(idle_stages[k], 50));
  }
  std::printf("\n");
  return 0;
}

// ---------------------------------------------------------------------------------------------
// load

struct LoadOptions {
  double rate = 20000.0;  // packets per second
  double seconds = 5.0;
  int cameras = 4;
  double frame_dt_s = 2.0;  // data-clock advance per camera frame
  std::string vision_address = kVisionGroup;
  std::string interface = sf::app::default_interface;
  std::uint64_t seed = 11;
  double start_time_s = 1000.0;
};

int run_load(const LoadOptions& o) {
  if (!(o.rate > 0 && o.rate <= 200000)) throw sf::app::UsageError("--rate must be 0 to 200000");
  if (!(o.seconds > 0 && o.seconds <= 60)) throw sf::app::UsageError("--seconds must be 0 to 60");
  if (!(o.frame_dt_s > 0)) throw sf::app::UsageError("--frame-dt must be positive");
  const auto interface = interface_option(o.interface);
  const auto total = static_cast<std::size_t>(std::llround(o.rate * o.seconds));

  // Every packet is built and serialised before the clock starts: the sender only sends.
  sf::simulation::SimulationConfig simulation;
  simulation.seed = o.seed;
  simulation.step_s = o.frame_dt_s;
  simulation.start_time_s = o.start_time_s;
  simulation.cameras = o.cameras;
  // A geometry packet about every 3 s of wall time, as SSL-Vision does.
  simulation.geometry_interval_s = 3.0 * o.rate / o.cameras * o.frame_dt_s;
  sf::simulation::SimulatedVision vision(simulation);
  std::vector<std::vector<std::string>> frames;  // the packets of one instant, sent together
  std::size_t packets = 0;
  std::size_t detection_packets = 0;
  std::size_t complete_frames = 0;  // with a packet from every camera: each completes a formation
  std::uint32_t frame_number = 0;
  while (packets < total) {
    std::vector<std::string> burst;
    ++frame_number;
    int cameras_in_burst = 0;
    for (SSL_WrapperPacket& packet : vision.next().packets) {
      if (packets == total) break;  // exactly `total` packets: the last frame may be cut short
      if (packet.has_detection()) {
        packet.mutable_detection()->set_frame_number(frame_number);
        ++detection_packets;
        ++cameras_in_burst;
      }
      burst.push_back(packet.SerializeAsString());
      ++packets;
    }
    if (cameras_in_burst == o.cameras) ++complete_frames;
    frames.push_back(std::move(burst));
  }

  boost::asio::io_context io;
  sf::net::MulticastSender sender(io, group_option("vision-address", o.vision_address),
                                  interface.address);
  sender.open();
  tighten_timer_slack();
  // Bursts of one frame (one packet per camera) on a fixed schedule with absolute deadlines, so
  // a late wake-up is caught up, not carried forward.
  const double frame_period_ns = 1e9 * o.seconds / static_cast<double>(frames.size());
  const std::int64_t start = now_ns() + 50'000'000;
  std::int64_t worst_lag_ns = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const std::int64_t due =
        start + static_cast<std::int64_t>(static_cast<double>(f) * frame_period_ns);
    wait_until(due, 0);
    worst_lag_ns = std::max(worst_lag_ns, now_ns() - due);
    for (const std::string& packet : frames[f]) sender.send(bytes_of(packet));
  }
  const double elapsed_s = static_cast<double>(now_ns() - start) / 1e9;
  std::printf(
      "load sent=%llu send_errors=%llu detection_packets=%zu frames=%zu complete_frames=%zu "
      "cameras=%d seconds=%.3f achieved_pps=%.0f worst_lag_us=%.1f\n",
      static_cast<unsigned long long>(sender.sent()),
      static_cast<unsigned long long>(sender.send_errors()), detection_packets, frames.size(),
      complete_frames, o.cameras, elapsed_s, static_cast<double>(sender.sent()) / elapsed_s,
      static_cast<double>(worst_lag_ns) / 1000.0);
  std::fflush(stdout);
  return sender.send_errors() == 0 ? 0 : 1;
}

}  // namespace

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
