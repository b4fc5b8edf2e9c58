// e2e_bench latency: the predictor and the echo timed side by side (e2e_bench.cpp).
#include "e2e_modes.hpp"

namespace e2e {

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

}  // namespace e2e
