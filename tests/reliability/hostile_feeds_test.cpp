// A tournament's referee and tracker groups are shared by every team's computers, game
// controllers in test mode and half-configured tools. These tests follow a live match while a
// flood of hostile datagrams goes to one of those groups for a bounded time: random bytes,
// truncated messages, varints that never end, messages of a command nobody knows, other game
// controllers and trackers, 60,000-character names with control characters, the followed game
// controller's own messages replayed, and spoofed team names in its name. The daemons must stay
// up, keep learning and predicting, count what they refused, keep their logs short, and never
// follow a spoofed name.

#include <signal.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <sstream>

#include "reliability_support.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper_tracked.pb.h"
#include "tracked_frames.hpp"

namespace ssl_formation::reliability {
namespace {

using testing::ChildProcess;
using testing::Readiness;
using testing::TempDir;

constexpr auto hostile_for = 10s;
constexpr int hostile_per_second = 800;

// What a program wrote to stderr while the flood lasted: the lines, and the longest of all.
struct LogFigures {
  std::size_t lines = 0;
  std::size_t longest_line = 0;
  bool protobuf_lines = false;
};

LogFigures log_figures(const std::string& all, std::size_t from) {
  LogFigures f;
  std::istringstream text(all);
  std::size_t at = 0;
  for (std::string line; std::getline(text, line);) {
    if (at >= from) ++f.lines;
    at += line.size() + 1;
    f.longest_line = std::max(f.longest_line, line.size());
    if (line.find("libprotobuf") != std::string::npos) f.protobuf_lines = true;
  }
  return f;
}

void expect_quiet_logs(const ChildProcess& process, std::size_t from, const char* name) {
  const LogFigures f = log_figures(process.stderr_text(), from);
  // "At most a few hundred lines a minute": the flood lasts a sixth of one, with status lines
  // every second.
  EXPECT_LE(f.lines, 60U) << name << ":\n" << process.stderr_text().substr(from);
  EXPECT_LE(f.longest_line, 1000U) << name;
  EXPECT_FALSE(f.protobuf_lines) << name << ": libprotobuf wrote to stderr itself";
}

// The referee group's real messages as the test hears them: the first ones (to replay later)
// and the newest (to spoof names in).
class RefereeTap {
 public:
  explicit RefereeTap(const std::string& group) {
    receiver_ = std::make_unique<net::ProtoMulticastReceiver<Referee>>(io_, endpoint_of(group));
    receiver_->start([this](const Referee& message, const net::udp::endpoint&) {
      std::lock_guard lock(mutex_);
      // Only the real game controller's: the flood's own messages in its name carry a spoofed
      // name.
      if (message.source_identifier() != "ssl-producer" ||
          message.yellow().name().starts_with("Spoof") ||
          message.blue().name().starts_with("Spoof")) {
        return;
      }
      if (first_.size() < 200) first_.push_back(message);
      if (heard_ > 0 && message.command() != newest_.command()) ++command_changes_;
      newest_ = message;
      ++heard_;
    });
    thread_ = std::thread([this] { io_.run(); });
  }
  ~RefereeTap() {
    io_.stop();
    thread_.join();
  }
  std::uint64_t heard() {
    std::lock_guard lock(mutex_);
    return heard_;
  }
  std::vector<Referee> first() {
    std::lock_guard lock(mutex_);
    return first_;
  }
  Referee newest() {
    std::lock_guard lock(mutex_);
    return newest_;
  }
  // How often the real game controller's command changed so far.
  std::uint64_t command_changes() {
    std::lock_guard lock(mutex_);
    return command_changes_;
  }

 private:
  boost::asio::io_context io_;
  std::unique_ptr<net::ProtoMulticastReceiver<Referee>> receiver_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<Referee> first_;
  Referee newest_;
  std::uint64_t heard_ = 0;
  std::uint64_t command_changes_ = 0;
};

std::string random_bytes(std::mt19937_64& random) {
  std::string bytes(std::uniform_int_distribution<int>(1, 1400)(random), '\0');
  for (char& c : bytes) c = static_cast<char>(random());
  return bytes;
}

// A field whose varint never ends within ten bytes, or a length far beyond the datagram.
std::string huge_varints(int which) {
  return which == 0 ? std::string("\x08\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\x01", 12)
                    : std::string("\x3a\xff\xff\xff\xff\x0f", 6);
}

// The kinds of garbage every group gets, by `kind` 0 to 2: random bytes, `valid` cut short, and
// varints that never end. None for another kind.
std::optional<std::string> malformed(int kind, const std::string& valid, std::mt19937_64& random) {
  switch (kind) {
    case 0:
      return random_bytes(random);
    case 1:
      return valid.substr(0,
                          std::uniform_int_distribution<std::size_t>(1, valid.size() - 1)(random));
    case 2:
      return huge_varints(static_cast<int>(random() % 2));
    default:
      return std::nullopt;
  }
}

std::string spoofed_name(int k) {
  std::string name = "Spoof " + std::to_string(k) + " \x1b[2J\n";
  if (k % 5 == 0) name += std::string(59814, 'Y');
  return name;
}

struct HostileCounts {
  std::uint64_t sent = 0;
  std::uint64_t replays = 0;        // the followed game controller's old messages
  std::uint64_t spoofed_names = 0;  // its newest message with other names
};

// The referee kinds in turn, for `duration` at `per_second`.
HostileCounts flood_referee(const std::string& group, RefereeTap& tap,
                            std::chrono::steady_clock::duration duration, int per_second) {
  Sender sender(group);
  std::mt19937_64 random(31);
  const std::vector<Referee> early = tap.first();
  HostileCounts counts;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; std::chrono::steady_clock::now() - start < duration; ++k) {
    Referee m = tap.newest();
    std::string bytes = malformed(k % 8, m.SerializeAsString(), random).value_or("");
    switch (k % 8) {
      case 0:
      case 1:
      case 2:
        break;
      case 3:  // a command number the wire format does not define
        m.clear_command();
        bytes = m.SerializePartialAsString() + std::string("\x20\x63", 2);
        break;
      case 4:  // another game controller, with names no team has
        m.set_source_identifier("test-mode-gc");
        m.mutable_yellow()->set_name(spoofed_name(k));
        m.set_command(Referee::HALT);
        bytes = m.SerializeAsString();
        break;
      case 5:  // the followed game controller's first messages again (the kick-off's)
        m = early[static_cast<std::size_t>(k / 8) % early.size()];
        m.mutable_blue()->set_name(spoofed_name(k));
        bytes = m.SerializeAsString();
        ++counts.replays;
        break;
      case 6:  // its newest message with the opponent's name spoofed
        m.mutable_yellow()->set_name(spoofed_name(k));
        bytes = m.SerializeAsString();
        ++counts.spoofed_names;
        break;
      default:  // odd content from nobody in particular: a placement to nowhere
        m.clear_source_identifier();
        m.set_command(Referee::BALL_PLACEMENT_YELLOW);
        m.mutable_designated_position()->set_x(std::numeric_limits<float>::quiet_NaN());
        m.mutable_designated_position()->set_y(1e30F);
        bytes = m.SerializeAsString();
        break;
    }
    if (sender.send(bytes)) ++counts.sent;
    const auto due = start + std::chrono::microseconds(1'000'000LL * (k + 1) / per_second);
    std::this_thread::sleep_until(due);
  }
  return counts;
}

// Waits until the trainer's status line shows 150 formations more than `before`: what a second
// and a half of the 60 frames/s feed gives, and what each test expects at the end.
bool learned_on(ChildProcess& trainer, const testing::Status& before,
                std::chrono::milliseconds timeout) {
  const std::uint64_t from = before.at("formations");
  return testing::wait_for_status_where(
      trainer,
      [from](const testing::Status& status) { return status.at("formations") > from + 150; },
      timeout);
}

TEST(HostileFeeds, ARefereeGroupFloodNeitherStallsFloodsNorSteersTheDaemons) {
  TempDir dir;
  const std::string vision = new_group();
  const std::string referee = new_group();
  const std::string predictions = new_group();
  const std::string tables = (dir / "tables").string();
  RefereeTap tap(referee);
  ChildProcess trainer(
      trainer_program,
      {"--vision-address", vision, "--referee-address", referee, "--our-team", "ssl-formation",
       "--table-dir", tables, "--status-interval", "1", "--flush-interval", "1"},
      dir.path(), "trainer", Readiness::ready_file);
  ChildProcess predictor(
      predictor_program,
      {"--vision-address", vision, "--referee-address", referee, "--our-team", "ssl-formation",
       "--table-dir", tables, "--prediction-address", predictions, "--status-interval", "1",
       "--reload-interval", "0.5", "--quiet"},
      dir.path(), "predictor", Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  // A simulated match with its game controller, on groups of this test.
  ChildProcess producer(
      producer_program,
      {"--simulation", "match", "--vision-address", vision, "--referee-address", referee,
       "--our-team", "ssl-formation", "--cameras", "1", "--status-interval", "100"},
      dir.path(), "producer");
  PredictionListener listener(predictions);
  // Until the predictor predicts from the trainer's table.
  for (const auto deadline = std::chrono::steady_clock::now() + 60s;
       listener.count() < 60 && std::chrono::steady_clock::now() < deadline;) {
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_GE(listener.count(), 60U) << trainer.stderr_text() << predictor.stderr_text();
  ASSERT_GT(tap.heard(), 0U);

  const std::size_t trainer_log_from = trainer.stderr_text().size();
  const std::size_t predictor_log_from = predictor.stderr_text().size();
  const auto before = last_status(trainer.stderr_text());
  const std::size_t predictions_before = listener.count();
  const std::uint64_t real_changes_before = tap.command_changes();
  const HostileCounts sent = flood_referee(referee, tap, hostile_for, hostile_per_second);
  const std::size_t predictions_during = listener.count() - predictions_before;
  // A status line after the flood that shows the trainer learning on.
  EXPECT_TRUE(learned_on(trainer, before, 30s)) << trainer.stderr_text();
  const std::uint64_t real_changes = tap.command_changes() - real_changes_before;
  ASSERT_TRUE(trainer.running()) << trainer.stderr_text();
  ASSERT_TRUE(predictor.running()) << predictor.stderr_text();
  expect_quiet_logs(trainer, trainer_log_from, "trainer");
  expect_quiet_logs(predictor, predictor_log_from, "predictor");
  // The counters from the lines each daemon logs as it stops: they hold every one, where a
  // periodic line crowded with problems leaves details out.
  producer.signal(SIGTERM);
  trainer.signal(SIGTERM);
  predictor.signal(SIGTERM);
  EXPECT_EQ(trainer.wait(10s), 0) << trainer.stderr_text();
  EXPECT_EQ(predictor.wait(10s), 0) << predictor.stderr_text();
  producer.wait(10s);
  const auto after = last_status(trainer.stderr_text());
  const auto predictor_after = last_status(predictor.stderr_text());

  // About 60 predictions a second went on (at least a quarter of them, on a busy machine).
  EXPECT_GE(predictions_during, 150U);
  // Learning went on: the match kept running for the trainer.
  EXPECT_GT(after.at("motion_instances"), before.at("motion_instances"));
  EXPECT_GT(after.at("formations"), before.at("formations") + 150);
  // What was refused was counted: the replays as stale, the spoofed names as refused
  // switches, the rest as unused. (A busy machine's socket may drop some of the flood's large
  // datagrams: half of each kind must have arrived and been counted.)
  const std::uint64_t heard = after.at("referee_messages") - before.at("referee_messages");
  EXPECT_GE(heard, sent.sent / 2) << "of " << sent.sent << " sent";
  EXPECT_GE(after.at("referee_stale"), sent.replays / 2);
  EXPECT_GE(after.at("name_switches_refused"), sent.spoofed_names / 2);
  EXPECT_GE(after.at("referee_unused") - before.at("referee_unused"), sent.sent * 3 / 10);
  EXPECT_GE(predictor_after.at("referee_stale"), sent.replays / 2);
  // No spoofed name took over: the only tables are the real opponent's.
  for (const auto& entry : std::filesystem::directory_iterator(tables)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "simulated_opponent.bin" || name == ".ssl-trainer.lock" ||
                name.starts_with("simulated_opponent.bin.tmp-"))  // a save under way
        << name;
  }
  // The game state followed the real game controller only: as many changes as it made (give or
  // take the one under way at either end of the flood), not one per replayed kick-off.
  for (const ChildProcess* process : {&trainer, &predictor}) {
    const std::string during =
        process->stderr_text().substr(process == &trainer ? trainer_log_from : predictor_log_from);
    std::size_t changes = 0;
    for (std::size_t at = during.find("referee: game "); at != std::string::npos;
         at = during.find("referee: game ", at + 1)) {
      ++changes;
    }
    EXPECT_LE(changes, real_changes + 2) << during;
  }
  std::cout << "[ figures  ] referee flood: sent=" << sent.sent << " heard=" << heard
            << " replays=" << sent.replays << " spoofed_names=" << sent.spoofed_names
            << " trainer_referee_stale=" << after.at("referee_stale")
            << " trainer_name_switches_refused=" << after.at("name_switches_refused")
            << " trainer_referee_unused="
            << after.at("referee_unused") - before.at("referee_unused")
            << " predictions_during=" << predictions_during
            << " trainer_log_lines=" << log_figures(trainer.stderr_text(), trainer_log_from).lines
            << " predictor_log_lines="
            << log_figures(predictor.stderr_text(), predictor_log_from).lines << "\n";
}

// The tracker group: the daemons follow tracker "a" while the flood comes.
TEST(HostileFeeds, ATrackerGroupFloodNeitherStallsNorFloodsTheDaemons) {
  TempDir dir;
  const std::string tracker = new_group();
  const std::string predictions = new_group();
  const std::filesystem::path table = dir / "table.bin";
  const std::vector<std::string> tracked{
      "--vision-source",   "tracked",   "--tracker-address", tracker,
      "--referee-address", new_group(), "--status-interval", "1"};
  std::vector<std::string> trainer_args = tracked;
  trainer_args.insert(trainer_args.end(), {"--table", table.string(), "--flush-interval", "1"});
  std::vector<std::string> predictor_args = tracked;
  predictor_args.insert(predictor_args.end(), {"--table", table.string(), "--prediction-address",
                                               predictions, "--reload-interval", "0.5", "--quiet"});
  ChildProcess trainer(trainer_program, trainer_args, dir.path(), "trainer", Readiness::ready_file);
  ChildProcess predictor(predictor_program, predictor_args, dir.path(), "predictor",
                         Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  ASSERT_TRUE(predictor.wait_until_ready(10s)) << predictor.stderr_text();
  PredictionListener listener(predictions);

  // The real tracker at 60 frames a second, in a thread of its own; the flood in this one.
  std::atomic<bool> stop{false};
  std::atomic<int> frames{0};
  std::thread real([&] {
    Sender sender(tracker);
    const auto start = std::chrono::steady_clock::now();
    for (int f = 0; !stop; ++f) {
      sender.send(testing::tracked_frame_of_six(f, 100.0, "a", 7));
      frames = f + 1;
      std::this_thread::sleep_until(start + std::chrono::microseconds(1'000'000LL * (f + 1) / 60));
    }
  });
  for (const auto deadline = std::chrono::steady_clock::now() + 30s;
       listener.count() < 60 && std::chrono::steady_clock::now() < deadline;) {
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_GE(listener.count(), 60U) << trainer.stderr_text() << predictor.stderr_text();

  const std::size_t trainer_log_from = trainer.stderr_text().size();
  const std::size_t predictor_log_from = predictor.stderr_text().size();
  const auto before = last_status(trainer.stderr_text());
  const std::size_t predictions_before = listener.count();
  std::uint64_t sent = 0;
  {
    Sender sender(tracker);
    std::mt19937_64 random(32);
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; std::chrono::steady_clock::now() - start < hostile_for; ++k) {
      // The real tracker's newest instant, so that no datagram of the flood is a later frame
      // (a forger who also runs the tracker's clock ahead is beyond what this guards against).
      TrackerWrapperPacket packet;
      packet.ParseFromString(testing::tracked_frame_of_six(std::max(0, frames - 1), 100.0, "a", 7));
      std::string bytes = malformed(k % 6, packet.SerializeAsString(), random).value_or("");
      switch (k % 6) {
        case 0:
        case 1:
        case 2:
          break;
        case 3:  // no uuid, which is required: libprotobuf complains of each
          packet.clear_uuid();
          bytes = packet.SerializePartialAsString();
          break;
        case 4:  // another tracker with a name of 60,000 characters and control characters
          packet.set_uuid("b\n" + std::to_string(k));
          packet.set_source_name(spoofed_name(k));
          bytes = packet.SerializeAsString();
          break;
        default:  // the followed tracker's uuid with coordinates that are no coordinates
          for (auto& robot : *packet.mutable_tracked_frame()->mutable_robots()) {
            robot.mutable_pos()->set_x(std::numeric_limits<float>::quiet_NaN());
            robot.mutable_pos()->set_y(1e30F);
          }
          bytes = packet.SerializeAsString();
          break;
      }
      if (sender.send(bytes)) ++sent;
      std::this_thread::sleep_until(
          start + std::chrono::microseconds(1'000'000LL * (k + 1) / hostile_per_second));
    }
  }
  const std::size_t predictions_during = listener.count() - predictions_before;
  EXPECT_TRUE(learned_on(trainer, before, 30s)) << trainer.stderr_text();
  stop = true;
  real.join();
  ASSERT_TRUE(trainer.running()) << trainer.stderr_text();
  ASSERT_TRUE(predictor.running()) << predictor.stderr_text();
  expect_quiet_logs(trainer, trainer_log_from, "trainer");
  expect_quiet_logs(predictor, predictor_log_from, "predictor");
  // The counters from the lines the trainer logs as it stops: they hold every one.
  trainer.signal(SIGTERM);
  predictor.signal(SIGTERM);
  EXPECT_EQ(trainer.wait(10s), 0) << trainer.stderr_text();
  EXPECT_EQ(predictor.wait(10s), 0) << predictor.stderr_text();
  const auto after = last_status(trainer.stderr_text());

  EXPECT_GE(predictions_during, 150U);
  EXPECT_GT(after.at("formations"), before.at("formations") + 150);
  EXPECT_GE(after.at("tracker_undecodable") - before.at("tracker_undecodable"), sent / 4);
  EXPECT_GE(after.at("tracker_other_source") - before.at("tracker_other_source"), sent / 6 / 2);
  // The tracker followed is still "a".
  EXPECT_EQ(trainer.stderr_text().find("following tracker 'b"), std::string::npos);
  std::cout << "[ figures  ] tracker flood: sent=" << sent << " real_frames=" << frames
            << " predictions_during=" << predictions_during << " trainer_tracker_undecodable="
            << after.at("tracker_undecodable") - before.at("tracker_undecodable")
            << " trainer_tracker_other_source="
            << after.at("tracker_other_source") - before.at("tracker_other_source")
            << " trainer_log_lines=" << log_figures(trainer.stderr_text(), trainer_log_from).lines
            << " predictor_log_lines="
            << log_figures(predictor.stderr_text(), predictor_log_from).lines << "\n";
}

}  // namespace
}  // namespace ssl_formation::reliability
