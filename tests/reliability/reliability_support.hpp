#pragma once
// What the reliability tests share: the programs under test, a sender and a prediction listener
// on loopback multicast, status-line parsing, and the library's view of a packet stream (the
// reference every daemon result is compared with). Everything sends and joins on 127.0.0.1 with
// TTL 1, on a group of its own per test.

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <regex>
#include <span>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "child_process.hpp"
#include "pipeline_support.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/net/proto_multicast.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"
#include "status_lines.hpp"

namespace ssl_formation::reliability {

using namespace std::chrono_literals;

inline const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
inline const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
inline const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

using testing::last_status;
using testing::new_group;
using testing::PredictionListener;
using testing::received_or_dropped;
using testing::wait_for_status;
using testing::wait_for_status_where;

inline net::MulticastEndpoint endpoint_of(const std::string& group) {
  return net::parse_multicast_endpoint(group).value();
}

using Entries = testing::TableEntries;
const auto entries = testing::table_entries;

// The simulated producer's packets for `count` formations.
inline std::vector<SSL_WrapperPacket> simulated_packets(simulation::SimulationConfig config,
                                                        int count) {
  simulation::SimulatedVision vision(config);
  std::vector<SSL_WrapperPacket> packets;
  for (int i = 0; i < count; ++i) {
    for (auto& packet : vision.next().packets) packets.push_back(std::move(packet));
  }
  return packets;
}

// The simulated producer's opponent jumps from formation to formation every 2 s of data time: the
// paper's scenario, with nothing for the motion model to learn (no two frames close enough for a
// velocity). So every daemon these tests run on such streams is given --model paper, and the
// library references below are the paper's model too (Training without a motion table, step
// sampling every 2 s: SamplerConfig's defaults).

// The library's training on a stream: the reference for a trainer's table.
inline std::unique_ptr<Training> train(const std::vector<SSL_WrapperPacket>& packets,
                                       const SamplerConfig& config = {}) {
  auto training = std::make_unique<Training>(config, TransitionTable(config.grid));
  for (const auto& packet : packets) training->add(packet);
  return training;
}

// The library's predictions on a stream, encoded as ssl-predictor sends them.
inline std::vector<std::string> library_predictions(const std::vector<SSL_WrapperPacket>& packets,
                                                    const TransitionTable& table, int horizon = 2) {
  std::vector<std::string> out;
  PredictionConfig config;
  config.horizon = horizon;
  config.model = ModelKind::paper;  // as the daemons run: --model paper
  config.sampler = sampler_config_for(ModelKind::paper);
  PredictionPipeline pipeline(config, [&](const PredictedFormation& predicted) {
    std::string datagram;
    encode_prediction(predicted.formation(), predicted.prediction, predicted.context, datagram);
    out.push_back(std::move(datagram));
  });
  pipeline.set_table(std::make_shared<const StoredTable>(StoredTable{table, {}}));
  for (const auto& packet : packets) pipeline.add(packet);
  return out;
}

// Sends datagrams to one group from 127.0.0.1, TTL 1.
class Sender {
 public:
  explicit Sender(const std::string& group) : sender_(io_, endpoint_of(group)) { sender_.open(); }
  bool send(const std::string& bytes) {
    return sender_.send(std::as_bytes(std::span(bytes.data(), bytes.size())));
  }
  bool send(const google::protobuf::MessageLite& message) {
    return send(message.SerializeAsString());
  }
  std::uint64_t sent() const { return sender_.sent(); }

 private:
  boost::asio::io_context io_;
  net::MulticastSender sender_;
};

// Sends every item (bytes or a message) to `group`, 150 us apart: well within what the daemons
// keep up with, so what they count is what was sent.
template <class Items>
void send_paced(const std::string& group, const Items& items) {
  Sender sender(group);
  for (const auto& item : items) {
    ASSERT_TRUE(sender.send(item));
    std::this_thread::sleep_for(150us);  // the pace of the feed, not a wait for anything
  }
}

// A trainer and a predictor (reading `predictor_table`) on one fresh vision group, the predictions
// on another, both with --model paper and status lines every 0.1 s. ready() waits for both ready
// files: the sockets joined, and the predictor's table loaded.
struct RunningPipeline {
  RunningPipeline(const testing::TempDir& dir, const std::filesystem::path& predictor_table)
      : trainer(trainer_program,
                {"--vision-address", vision, "--table", (dir / "trainer.bin").string(),
                 "--status-interval", "0.1", "--flush-interval", "60", "--model", "paper"},
                dir.path(), "trainer", testing::Readiness::ready_file),
        predictor(
            predictor_program,
            {"--vision-address", vision, "--prediction-address", predictions, "--table",
             predictor_table.string(), "--quiet", "--status-interval", "0.1", "--model", "paper"},
            dir.path(), "predictor", testing::Readiness::ready_file) {}

  ::testing::AssertionResult ready() {
    if (!trainer.wait_until_ready(10s)) {
      return ::testing::AssertionFailure() << "trainer not ready:\n" << trainer.stderr_text();
    }
    if (!predictor.wait_until_ready(10s)) {
      return ::testing::AssertionFailure() << "predictor not ready:\n" << predictor.stderr_text();
    }
    if (predictor.ready_fact("table_loaded") != "1") {
      return ::testing::AssertionFailure() << "predictor ready without its table:\n"
                                           << predictor.stderr_text();
    }
    return ::testing::AssertionSuccess();
  }

  const std::string vision = new_group();
  const std::string predictions = new_group();
  testing::ChildProcess trainer;
  testing::ChildProcess predictor;
};

// Resident memory of a process, KiB (VmRSS in /proc/PID/status); 0 if unreadable.
inline std::uint64_t rss_kib(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6));
  }
  return 0;
}

}  // namespace ssl_formation::reliability
