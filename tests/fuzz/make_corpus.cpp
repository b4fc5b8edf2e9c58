// Writes the seed corpus of the fuzz targets (tests/fuzz/corpus/{sampler,log,table,referee,
// tracker}/): a few real grSim packets from tests/data, small simulated streams (clean and
// hostile), small logs (plain, gzip, indexed), dense and sparse table files, and scripted
// referee and tracker feeds (a match's commands, name switches, two sources, stale and hostile
// messages). Built only with SSLF_FUZZ=ON.
//
//   make_corpus GRSIM_LOG OUTPUT_DIR
//
// The corpus is committed; rerun this only to change it, and keep it small (< 300 KB).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fuzz_paths.hpp"
#include "match_logs.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "tracked_frames.hpp"

namespace fs = std::filesystem;
using namespace ssl_formation;

namespace {

// A sampler input: the config selector, then length-prefixed packets (fuzz_paths.hpp).
class SamplerInput {
 public:
  explicit SamplerInput(std::uint8_t selector) { bytes_.push_back(static_cast<char>(selector)); }
  void add(const SSL_WrapperPacket& packet) { add_raw(packet.SerializePartialAsString()); }
  void add_raw(const std::string& packet) {
    const std::size_t n = std::min<std::size_t>(packet.size(), 0xFFFE);
    bytes_.push_back(static_cast<char>(n & 0xff));
    bytes_.push_back(static_cast<char>(n >> 8));
    bytes_.append(packet, 0, n);
  }
  void new_stream() { bytes_.append("\xff\xff", 2); }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

// A referee or tracker input: timed datagrams (fuzz_paths.hpp), the receive clock kept here.
class TimedInput {
 public:
  // `datagram` received `step_s` after the one before (before it, if negative: the clock went
  // back); steps are whole milliseconds of at most 32.767 s.
  void add(const std::string& datagram, double step_s) {
    const long ms = std::min(std::lround(std::abs(step_s) * 1000.0), 0x7FFFL);
    now_s_ += static_cast<double>(step_s < 0 ? -ms : ms) / 1000.0;
    const std::size_t n = std::min<std::size_t>(datagram.size(), 0xFFFE);
    put16(static_cast<std::uint16_t>(n));
    put16(static_cast<std::uint16_t>(ms | (step_s < 0 ? fuzz::clock_back_bit : 0)));
    bytes_.append(datagram, 0, n);
  }
  void new_stream() { bytes_.append("\xff\xff", 2); }
  // The receive time of the last datagram, which the scripts also use as the sender's clock.
  double now_s() const { return now_s_; }
  const std::string& bytes() const { return bytes_; }

 private:
  void put16(std::uint16_t v) {
    bytes_.push_back(static_cast<char>(v & 0xff));
    bytes_.push_back(static_cast<char>(v >> 8));
  }
  std::string bytes_;
  double now_s_ = 0.0;
};

void write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::vector<RobotDetection> team(int n, double t, double x0, std::uint32_t first_id) {
  std::vector<RobotDetection> robots;
  for (int i = 0; i < n; ++i) {
    RobotDetection r;
    r.robot_id = first_id + static_cast<std::uint32_t>(i);
    r.position = Point{x0 + 400.0 * t * (i % 2 == 0 ? 1 : -1) + 300.0 * i, -2000.0 + 900.0 * i};
    robots.push_back(r);
  }
  return robots;
}

// Two cameras splitting the field at x = 0, `robots` per team moving along x.
std::vector<SSL_WrapperPacket> simulated_stream(double duration_s, double frame_s, int robots) {
  std::vector<SSL_WrapperPacket> packets{make_geometry_packet(FieldSize{9000, 6000})};
  std::uint32_t frame = 0;
  for (double t = 0.0; t <= duration_s + 1e-9; t += frame_s) {
    for (std::uint32_t camera = 0; camera < 2; ++camera) {
      DetectionFrameSpec spec;
      spec.camera_id = camera;
      spec.frame_number = frame++;
      spec.t_capture = 100.0 + t;
      const double x0 = camera == 0 ? -3000.0 : 1000.0;
      spec.yellow = team(robots, t, x0, camera * 4);
      spec.blue = team(robots, t, -x0, camera * 4);
      spec.balls = {Point{10.0 * t, 0.0}};
      packets.push_back(make_detection_packet(spec));
    }
  }
  return packets;
}

void write_sampler_corpus(const fs::path& dir, const std::vector<SSL_WrapperPacket>& grsim) {
  // Real grSim packets, one per file: a detection and the one with geometry.
  for (const auto& packet : grsim) {
    if (packet.has_geometry()) {
      SamplerInput one(0x02);
      one.add(packet);
      write(dir / "grsim-geometry-packet", one.bytes());
      break;
    }
  }
  SamplerInput single(0x00);
  single.add(grsim.front());
  write(dir / "grsim-detection-packet", single.bytes());

  // Real grSim stream: every packet of the first 0.5 s of simulator time whose camera is 0 or 1,
  // 12x9 grid at a 0.1 s step, so samples and transitions come out.
  SamplerInput stream(0x22);
  const double t0 = grsim.front().detection().t_capture();
  for (const auto& packet : grsim) {
    if (!packet.has_detection()) continue;
    if (packet.detection().t_capture() > t0 + 0.5) break;
    if (packet.detection().camera_id() > 1) continue;
    SSL_WrapperPacket detection_only = packet;
    detection_only.clear_geometry();
    stream.add(detection_only);
  }
  write(dir / "grsim-stream-12x9-0.1s", stream.bytes());

  // Simulated: 3x2 at 2 s over 10 s, 3 robots per team per camera.
  SamplerInput sim(0x00);
  for (const auto& packet : simulated_stream(10.0, 0.5, 3)) sim.add(packet);
  write(dir / "sim-3x2-2s", sim.bytes());

  // Simulated: blue attacking -x, 1/60 s step, 16x16, geometry ignored.
  SamplerInput fast(0x40 | 0x10 | 0x08 | 0x04 | 0x03);
  for (const auto& packet : simulated_stream(0.2, 1.0 / 60.0, 2)) fast.add(packet);
  write(dir / "sim-16x16-60hz-blue-minus-x", fast.bytes());

  // Hostile: everything the sampler must refuse or survive, between valid frames.
  SamplerInput hostile(0x21);
  const auto frame = [](std::uint32_t camera, double t, std::vector<RobotDetection> yellow) {
    DetectionFrameSpec spec;
    spec.camera_id = camera;
    spec.frame_number = static_cast<std::uint32_t>(t * 60);
    spec.t_capture = t;
    spec.yellow = std::move(yellow);
    return make_detection_packet(spec);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  hostile.add(frame(0, 1.0, team(3, 0, 0, 0)));
  hostile.add(
      frame(0, 1.2, {{1, {0, 0}, 0, 0.5F}, {1, {100, 0}, 0, 0.9F}, {2, {nan, 0}, 0, 0.9F}}));
  hostile.add(
      frame(0, 1.3, {{3, {2e5, 0}, 0, 0.9F}, {5000, {0, 0}, 0, 0.9F}, {4, {0, inf}, 0, 0.9F}}));
  hostile.add(frame(64, 1.4, team(3, 0, 0, 0)));
  hostile.add(frame(0, nan, team(3, 0, 0, 0)));
  hostile.add(frame(1, 1.5, team(33, 0, 0, 0)));
  hostile.add(frame(0, 1.6, team(3, 1, 0, 0)));
  hostile.add(frame(0, 1.05, team(3, 1, 0, 0)));  // late
  hostile.add(frame(0, 0.1, team(3, 1, 0, 0)));   // clock reset
  hostile.add(frame(0, 0.3, team(3, 1, 0, 0)));
  hostile.add(make_geometry_packet(FieldSize{12000, 9000}));
  hostile.add(make_geometry_packet(FieldSize{-1, 0}));
  hostile.add(frame(0, 0.45, team(3, 2, 0, 0)));
  hostile.new_stream();
  hostile.add(frame(0, 1e15, team(3, 2, 0, 0)));
  hostile.add(frame(0, -1e15, team(3, 2, 0, 0)));
  hostile.add(frame(0, 1e15 + 0.5, team(3, 2, 0, 0)));
  hostile.add_raw("\x0a\x02\x08");  // truncated
  SSL_WrapperPacket missing_required;
  missing_required.mutable_detection()->set_camera_id(0);
  hostile.add(missing_required);
  write(dir / "sim-hostile-1x1-0.1s", hostile.bytes());
}

void write_log_corpus(const fs::path& dir, const std::vector<SSL_WrapperPacket>& grsim) {
  const auto write_log = [&](const fs::path& path, bool indexed) {
    auto writer = LogWriter::create(path);
    if (!writer) throw std::runtime_error(writer.error().message);
    std::int64_t t = 1'000'000'000;
    for (std::size_t i = 0; i < 4; ++i) writer->write_vision(grsim[i], t += 16'000'000);
    for (const auto& packet : simulated_stream(1.0, 0.5, 2))
      writer->write_vision(packet, t += 1'000'000);
    writer->write(3, t, std::string("\x08\x01\x10\x02", 4));  // a referee message (not parsed)
    // A legacy (2010) packet: today's detection decodes; then one without a frame number.
    DetectionFrameSpec spec;
    spec.t_capture = 5.0;
    spec.yellow = team(2, 0, 0, 0);
    writer->write(2, t, make_detection_packet(spec).SerializeAsString());
    SSL_WrapperPacket unusable;
    unusable.mutable_detection()->set_camera_id(1);
    writer->write(2, t, unusable.SerializePartialAsString());
    writer->write(4, t, "\x0a\x05garbage");  // does not parse
    writer->write(0, t, "");
    writer->write(5, t, "tracker");
    writer->write(42, t, "unknown type");
    if (!writer->close(indexed)) throw std::runtime_error(writer->error());
  };
  write_log(dir / "mixed.log", false);
  write_log(dir / "mixed-indexed.log", true);
  write_log(dir / "mixed.log.gz", false);
  write(dir / "header-only.log", std::string("SSL_LOG_FILE\0\0\0\1", 16));
  std::string cut = fuzz::read_bytes(dir / "mixed.log");
  write(dir / "truncated.log", cut.substr(0, cut.size() / 2));
}

void save(const fs::path& path, const TransitionTable& table, std::uint64_t samples) {
  const auto result = save_table(path, table, TableMetadata{FieldSize{}, 2.0, samples});
  if (!result) throw std::runtime_error(result.error().message);
}

void write_table_corpus(const fs::path& dir, const std::vector<SSL_WrapperPacket>& grsim) {
  TransitionTable one(Grid(1, 1), TableStorage::dense);
  one.add(0, 0, 7);
  save(dir / "dense-1x1.sslft", one, 8);

  TransitionTable two(Grid(2, 1), TableStorage::dense);
  two.add(0, 3, 2);
  two.add(5, 1);
  two.add(7, 7, TransitionTable::max_count);
  save(dir / "dense-2x1.sslft", two, 4);

  // Trained tables: the simulated stream on dense 2x2 and sparse 3x2, grSim on sparse 12x9.
  const auto train = [](const SamplerConfig& config, TransitionTable table,
                        const std::vector<SSL_WrapperPacket>& packets) {
    Training training(config, std::move(table));
    for (const auto& packet : packets) training.add(packet);
    return TransitionTable(training.stored_table().table);
  };
  SamplerConfig config;
  config.step_s = 0.5;
  const auto sim = simulated_stream(10.0, 0.25, 3);
  config.grid = Grid(2, 2);
  save(dir / "dense-2x2.sslft",
       train(config, TransitionTable(config.grid, TableStorage::dense), sim), 20);
  config.grid = Grid(3, 2);
  save(dir / "sparse-3x2.sslft",
       train(config, TransitionTable(config.grid, TableStorage::sparse), sim), 20);
  config.grid = Grid(12, 9);
  config.step_s = 0.2;
  save(dir / "sparse-12x9-grsim.sslft", train(config, TransitionTable(config.grid), grsim), 50);
  save(dir / "sparse-4x4-empty.sslft", TransitionTable(Grid(4, 4), TableStorage::sparse), 0);
}

// ---- Referee feeds

using testing::referee_payload;
using testing::RefereeSpec;

// The game controller's message for `spec`, sent `step_s` after the last one (its packet
// timestamp on the receive clock, plus an offset as real senders have).
void send(TimedInput& in, const RefereeSpec& spec, double step_s) {
  in.add(referee_payload(spec, 1000.0 + in.now_s() + step_s), step_s);
}

RefereeSpec named(Referee::Command command, std::uint32_t counter) {
  RefereeSpec spec;
  spec.command = command;
  spec.command_counter = counter;
  spec.yellow = "TIGERs Mannheim";
  spec.blue = "ER-Force";
  spec.blue_on_positive_half = true;
  return spec;
}

void write_referee_corpus(const fs::path& dir) {
  // A stretch of a first half at the game controller's 10 Hz: kick-off, play, a free kick, a
  // ball placement to its designated position, a stop; each command repeated as it is sent.
  TimedInput match;
  std::uint32_t counter = 0;
  const auto command = [&](Referee::Command c, int repeats, std::optional<Point> at = {}) {
    RefereeSpec spec = named(c, ++counter);
    spec.designated_position = at;
    for (int i = 0; i < repeats; ++i) send(match, spec, 0.1);
  };
  command(Referee::HALT, 3);
  command(Referee::STOP, 3);
  command(Referee::PREPARE_KICKOFF_YELLOW, 3);
  command(Referee::NORMAL_START, 5);
  command(Referee::DIRECT_FREE_BLUE, 3);
  command(Referee::STOP, 2);
  command(Referee::BALL_PLACEMENT_BLUE, 4, Point{-1250.0, 870.5});
  command(Referee::DIRECT_FREE_BLUE, 2);
  command(Referee::STOP, 2);
  write(dir / "match-first-half", match.bytes());

  // Every command once (the deprecated ones too), through every stage, sides both ways and not
  // said at all, as an older game controller without a source identifier sends them.
  TimedInput commands;
  for (int c = Referee::HALT; c <= Referee::BALL_PLACEMENT_BLUE; ++c) {
    RefereeSpec spec = named(static_cast<Referee::Command>(c), static_cast<std::uint32_t>(c));
    spec.stage = static_cast<Referee::Stage>(c % (Referee::POST_GAME + 1));
    spec.blue_on_positive_half = c % 3 == 0 ? std::nullopt : std::optional(c % 3 == 1);
    spec.source = "";
    send(commands, spec, 0.25);
  }
  write(dir / "every-command-and-stage", commands.bytes());

  // Single messages, the smallest seeds to mutate.
  TimedInput halt;
  send(halt, named(Referee::HALT, 0), 0.0);
  write(dir / "one-halt", halt.bytes());
  TimedInput one_placement;
  RefereeSpec to_spot = named(Referee::BALL_PLACEMENT_YELLOW, 12);
  to_spot.blue_on_positive_half = false;
  to_spot.designated_position = Point{0.0, 0.0};
  send(one_placement, to_spot, 0.0);
  write(dir / "one-placement", one_placement.bytes());

  // An older game controller: no team names, no source identifier, no sides.
  TimedInput older;
  RefereeSpec bare_spec;
  bare_spec.source = "";
  for (const auto c : {Referee::STOP, Referee::NORMAL_START, Referee::HALT}) {
    bare_spec.command = c;
    ++bare_spec.command_counter;
    for (int i = 0; i < 3; ++i) send(older, bare_spec, 0.1);
  }
  write(dir / "older-game-controller", older.bytes());

  // Ball placements: to a point, to a point with a coordinate that is not finite, to none.
  TimedInput placement;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RefereeSpec place = named(Referee::BALL_PLACEMENT_YELLOW, 1);
  place.designated_position = Point{3000.0, -2000.0};
  send(placement, place, 0.1);
  place.command_counter = 2;
  place.designated_position = Point{nan, 100.0};
  send(placement, place, 0.1);
  place.command_counter = 3;
  place.designated_position.reset();
  send(placement, place, 0.1);
  write(dir / "ball-placement", placement.bytes());

  // Team names: new ones that hold for 1.2 s take over, five times within a minute (the last
  // two refused by the rate limit); a flicker of names that never holds; then a minute later.
  TimedInput names;
  RefereeSpec spec = named(Referee::NORMAL_START, 1);
  send(names, spec, 0.0);
  for (int i = 0; i < 5; ++i) {
    spec.yellow = "Team Y" + std::to_string(i);
    spec.blue = "Team B" + std::to_string(i);
    for (int k = 0; k < 4; ++k) send(names, spec, 0.4);
  }
  for (int i = 0; i < 6; ++i) {
    spec.yellow = i % 2 == 0 ? "Flicker" : "Team Y4";
    send(names, spec, 0.3);
  }
  spec.yellow = "RoboTeam Twente";
  spec.blue = "";
  send(names, spec, 30.0);
  send(names, spec, 30.0);
  send(names, spec, 1.5);
  spec.yellow = spec.blue = "";
  send(names, spec, 0.5);
  send(names, spec, 1.0);
  write(dir / "name-switches", names.bytes());

  // Two game controllers on the group: the second is ignored while the first speaks, takes
  // over once the first is silent for 3 s, and the first is then the second.
  TimedInput two;
  RefereeSpec first = named(Referee::STOP, 5);
  first.source = "gc-main";
  RefereeSpec second = named(Referee::HALT, 1);
  second.source = "gc-test";
  second.yellow = "Test Yellow";
  for (int i = 0; i < 4; ++i) {
    send(two, first, 0.1);
    send(two, second, 0.05);
  }
  send(two, second, 3.0);
  send(two, first, 0.1);
  send(two, second, 0.1);
  write(dir / "two-game-controllers", two.bytes());

  // The game controller followed falls silent for 2.5 s; another, naming other teams, takes
  // over at once and its names after they hold.
  TimedInput silence;
  RefereeSpec before_silence = named(Referee::STOP, 3);
  before_silence.source = "gc-a";
  send(silence, before_silence, 0.1);
  send(silence, before_silence, 0.1);
  RefereeSpec after_silence = named(Referee::HALT, 0);
  after_silence.source = "gc-b";
  after_silence.yellow = "Tigers";
  after_silence.blue = "Delft Mercurians";
  send(silence, after_silence, 2.5);
  for (int i = 0; i < 4; ++i) send(silence, after_silence, 0.4);
  write(dir / "source-silence", silence.bytes());

  // Stale and forged messages of the followed game controller: its counter back, its timestamp
  // 2 s back or 20 s ahead; then a restart (counter from 0) after a silence, and one at once in
  // a new stage.
  TimedInput stale;
  send(stale, named(Referee::STOP, 40), 0.1);
  send(stale, named(Referee::HALT, 39), 0.1);
  stale.add(referee_payload(named(Referee::NORMAL_START, 41), 1000.0 + stale.now_s() - 2.0), 0.1);
  stale.add(referee_payload(named(Referee::NORMAL_START, 41), 1000.0 + stale.now_s() + 20.0), 0.1);
  send(stale, named(Referee::HALT, 0), 3.0);
  send(stale, named(Referee::STOP, 12), 0.1);
  RefereeSpec next_stage = named(Referee::HALT, 1);
  next_stage.stage = Referee::NORMAL_HALF_TIME;
  send(stale, next_stage, 0.1);
  write(dir / "stale-and-restarted", stale.bytes());

  // Text from the wire that must come out short and printable.
  TimedInput hostile;
  RefereeSpec loud = named(Referee::HALT, 1);
  loud.yellow = std::string(2000, 'Y');
  loud.blue = "Blue\x1b[2J\r\n\x7f\xc2\x9b\xe2\x80\xae\xef\xbb\xbf\xff\xfe\xc0\xaf";
  loud.source = "gc\n-a\\x41\\u{202E}";
  send(hostile, loud, 0.1);
  loud.command_counter = 2;
  loud.yellow = std::string(70, '\x01');
  loud.blue = std::string(70, '\xe2') + "\xe2\x80\xa6(5 bytes)";
  send(hostile, loud, 1.5);
  send(hostile, loud, 1.5);
  write(dir / "hostile-text", hostile.bytes());

  // What is not a message to use: bytes that do not parse, a cut message, a command number the
  // wire format does not define, a message of no more than a command (required fields missing).
  TimedInput junk;
  const std::string good = referee_payload(named(Referee::STOP, 1), 1000.0);
  junk.add("\x0a\x05garbage", 0.1);
  junk.add(good.substr(0, good.size() / 2), 0.1);
  Referee unknown;
  unknown.set_command_counter(2);
  junk.add(unknown.SerializePartialAsString() + std::string("\x20\x63", 2), 0.1);  // command 99
  Referee bare;
  bare.set_command(Referee::FORCE_START);
  junk.add(bare.SerializePartialAsString(), 0.1);
  junk.add("", 0.1);
  send(junk, named(Referee::STOP, 3), 0.1);
  write(dir / "undecodable-and-unknown", junk.bytes());

  // The receive clock going back, then a new stream (another log file) whose game controller
  // starts again.
  TimedInput streams;
  send(streams, named(Referee::NORMAL_START, 7), 5.0);
  send(streams, named(Referee::STOP, 8), -3.0);
  send(streams, named(Referee::HALT, 9), 0.1);
  streams.new_stream();
  RefereeSpec other = named(Referee::HALT, 0);
  other.yellow = "KIKS";
  other.blue = "RoboDragons";
  other.blue_on_positive_half = false;
  send(streams, other, 0.1);
  other.command = Referee::STOP;
  other.command_counter = 1;
  send(streams, other, 0.1);
  write(dir / "clock-back-and-new-stream", streams.bytes());
}

// ---- Tracker feeds

using testing::tracked_frame_of_six;

// A tracker's packet whose frame the test builds, with robots and balls in metres.
TrackerWrapperPacket tracker_packet(const std::string& uuid, std::uint32_t frame_number,
                                    double timestamp) {
  TrackerWrapperPacket packet;
  packet.set_uuid(uuid);
  packet.set_source_name("hostile " + uuid);
  TrackedFrame& frame = *packet.mutable_tracked_frame();
  frame.set_frame_number(frame_number);
  frame.set_timestamp(timestamp);
  return packet;
}

void add_robot(TrackedFrame& frame, std::optional<Team> team, std::optional<std::uint32_t> id,
               float x, float y, std::optional<float> visibility = {}) {
  TrackedRobot& robot = *frame.add_robots();
  if (id) robot.mutable_robot_id()->set_id(*id);
  if (team) robot.mutable_robot_id()->set_team(*team);
  robot.mutable_pos()->set_x(x);
  robot.mutable_pos()->set_y(y);
  robot.set_orientation(0.0F);
  if (visibility) robot.set_visibility(*visibility);
}

void add_ball(TrackedFrame& frame, float x, float y, std::optional<float> visibility,
              std::optional<std::pair<float, float>> velocity = {}) {
  TrackedBall& ball = *frame.add_balls();
  ball.mutable_pos()->set_x(x);
  ball.mutable_pos()->set_y(y);
  ball.mutable_pos()->set_z(0.0F);
  if (visibility) ball.set_visibility(*visibility);
  if (velocity) {
    ball.mutable_vel()->set_x(velocity->first);
    ball.mutable_vel()->set_y(velocity->second);
    ball.mutable_vel()->set_z(0.0F);
  }
}

void write_tracker_corpus(const fs::path& dir) {
  // One tracker at 60 Hz for half a second (steps of 17 ms), six yellow robots moving.
  TimedInput one;
  for (int f = 0; f < 30; ++f) one.add(tracked_frame_of_six(f, 100.0, "tracker-a", 1), 0.017);
  write(dir / "one-tracker-60hz", one.bytes());

  // Single packets, the smallest seeds to mutate: a frame, and the followed tracker without one.
  TimedInput single;
  single.add(tracked_frame_of_six(0, 100.0, "tracker-a", 1), 0.0);
  write(dir / "one-frame", single.bytes());
  TimedInput frameless;
  TrackerWrapperPacket uuid_only;
  uuid_only.set_uuid("tracker-a");
  uuid_only.set_source_name("TIGERs AutoRef");
  frameless.add(uuid_only.SerializeAsString(), 0.0);
  write(dir / "no-frame", frameless.bytes());

  // Both teams, six robots each, for 1.5 s at 10 Hz of tracker time: the sampler behind
  // (0.1 s step) samples formations and transitions.
  TimedInput teams;
  for (int f = 0; f < 15; ++f) {
    TrackerWrapperPacket packet =
        tracker_packet("tracker-a", static_cast<std::uint32_t>(f), 100.0 + f * 0.1);
    TrackedFrame& frame = *packet.mutable_tracked_frame();
    for (std::uint32_t i = 0; i < 6; ++i) {
      const float x = -4.0F + 1.2F * static_cast<float>(i) + 0.3F * static_cast<float>(f);
      add_robot(frame, YELLOW, i, x, -2.5F + static_cast<float>(i), 1.0F);
      add_robot(frame, BLUE, i, -x, 2.5F - static_cast<float>(i), 0.9F);
    }
    add_ball(frame, 0.05F * static_cast<float>(f), 0.0F, 1.0F, std::pair{0.5F, 0.0F});
    teams.add(packet.SerializeAsString(), 0.1);
  }
  write(dir / "both-teams-10hz", teams.bytes());

  // With a robot of no team in every frame.
  TimedInput stray;
  for (int f = 0; f < 12; ++f)
    stray.add(tracked_frame_of_six(f, 100.0, "tracker-a", 2, true), 0.017);
  write(dir / "stray-robot", stray.bytes());

  // Two trackers on the group: the second is ignored while the first speaks, takes over after
  // the first is silent for 1.5 s; a packet of the followed one without a frame keeps it alive.
  TimedInput two;
  for (int f = 0; f < 6; ++f) {
    two.add(tracked_frame_of_six(f, 100.0, "tracker-a", 1), 0.017);
    two.add(tracked_frame_of_six(f, 200.0, "tracker-b", 3), 0.002);
  }
  TrackerWrapperPacket no_frame;
  no_frame.set_uuid("tracker-a");
  two.add(no_frame.SerializeAsString(), 0.8);
  two.add(tracked_frame_of_six(7, 200.0, "tracker-b", 3), 0.8);
  two.add(tracked_frame_of_six(8, 200.0, "tracker-b", 3), 1.5);
  two.add(tracked_frame_of_six(9, 100.0, "tracker-a", 1), 0.017);
  write(dir / "two-trackers", two.bytes());

  // The tracker followed falls silent for 1.2 s: another takes over, and the first, back, is
  // ignored.
  TimedInput silence;
  silence.add(tracked_frame_of_six(0, 100.0, "tracker-a", 1), 0.017);
  silence.add(tracked_frame_of_six(1, 100.0, "tracker-a", 1), 0.017);
  silence.add(tracked_frame_of_six(0, 300.0, "tracker-b", 5), 1.2);
  silence.add(tracked_frame_of_six(2, 100.0, "tracker-a", 1), 0.017);
  silence.add(tracked_frame_of_six(1, 300.0, "tracker-b", 5), 0.017);
  write(dir / "source-silence", silence.bytes());

  // Balls: several of different visibility, with and without velocity, one not finite; a
  // frame with none; a kicked ball.
  TimedInput balls;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (int f = 0; f < 4; ++f) {
    TrackerWrapperPacket packet =
        tracker_packet("tracker-a", static_cast<std::uint32_t>(f), 100.0 + f / 60.0);
    TrackedFrame& frame = *packet.mutable_tracked_frame();
    add_robot(frame, YELLOW, 1, 0.5F * static_cast<float>(f), 1.0F);
    add_robot(frame, BLUE, 1, -1.0F, 0.5F, 0.8F);
    if (f == 1) {
      add_ball(frame, nan, 0.0F, 1.0F);
      add_ball(frame, 1.0F, 2.0F, 0.3F, std::pair{2.0F, -1.0F});
      add_ball(frame, -1.0F, 0.5F, 0.9F, std::pair{inf, 0.0F});
      add_ball(frame, -2.0F, 0.5F, 0.9F);
    } else if (f == 2) {
      KickedBall& kicked = *frame.mutable_kicked_ball();
      kicked.mutable_pos()->set_x(0.0F);
      kicked.mutable_pos()->set_y(0.0F);
      kicked.mutable_vel()->set_x(4.0F);
      kicked.mutable_vel()->set_y(0.0F);
      kicked.mutable_vel()->set_z(1.0F);
      kicked.set_start_timestamp(100.0);
      add_ball(frame, 0.1F, 0.0F, std::nullopt, std::pair{4.0F, 0.0F});
    } else if (f == 3) {
      add_ball(frame, 0.2F, 0.0F, std::nullopt);
    }
    balls.add(packet.SerializeAsString(), 0.017);
  }
  write(dir / "balls", balls.bytes());

  // Coordinates the sampler behind must refuse: not finite, past float range in millimetres,
  // far off the field; robots without an id or a team; a timestamp that is not finite.
  TimedInput hostile;
  TrackerWrapperPacket packet = tracker_packet("tracker-a", 1, 100.0);
  TrackedFrame& frame = *packet.mutable_tracked_frame();
  add_robot(frame, YELLOW, 0, nan, 0.0F);
  add_robot(frame, YELLOW, 1, 0.0F, inf);
  add_robot(frame, YELLOW, 2, 1e36F, 0.0F);
  add_robot(frame, YELLOW, 3, 300.0F, 0.0F);
  add_robot(frame, YELLOW, 4, 1.0F, 1.0F, -1.0F);
  add_robot(frame, BLUE, std::nullopt, 1.0F, 1.0F);
  add_robot(frame, std::nullopt, 5, 1.0F, 1.0F);
  add_robot(frame, UNKNOWN, 6, 1.0F, 1.0F);
  add_robot(frame, YELLOW, 4'000'000'000U, 1.0F, 1.0F);
  add_ball(frame, 1e36F, 0.0F, 1.0F, std::pair{nan, nan});
  hostile.add(packet.SerializeAsString(), 0.017);
  frame.set_frame_number(2);
  frame.set_timestamp(std::numeric_limits<double>::quiet_NaN());
  hostile.add(packet.SerializeAsString(), 0.017);
  frame.set_frame_number(3);
  frame.set_timestamp(-1e300);
  hostile.add(packet.SerializeAsString(), 0.017);
  write(dir / "hostile-coordinates", hostile.bytes());

  // Text from the wire that must come out short and printable, an empty uuid, packets that do
  // not parse (no uuid; cut) and no frame at all.
  TimedInput text;
  text.add(tracked_frame_of_six(0, 100.0, std::string(300, 'u'), 1), 0.017);
  TrackerWrapperPacket loud = tracker_packet("id\x1b[31m\xe2\x80\xae\xff", 0, 105.0);
  loud.set_source_name(std::string(100, '\n') + "\\u{0041}");
  text.add(loud.SerializeAsString(), 2.0);
  text.add(tracked_frame_of_six(1, 110.0, "", 1), 2.0);
  text.add(tracked_frame_of_six(2, 110.0, "tracker-b", 1), 0.017);
  TrackerWrapperPacket no_uuid;
  no_uuid.mutable_tracked_frame()->set_frame_number(1);
  no_uuid.mutable_tracked_frame()->set_timestamp(1.0);
  text.add(no_uuid.SerializePartialAsString(), 0.017);
  const std::string whole = tracked_frame_of_six(3, 110.0, "tracker-b", 1);
  text.add(whole.substr(0, whole.size() - 7), 0.017);
  text.add("", 0.017);
  write(dir / "hostile-text-and-undecodable", text.bytes());

  // The receive clock going back (the tracker followed stays), then a new stream whose tracker
  // is followed anew.
  TimedInput streams;
  streams.add(tracked_frame_of_six(0, 100.0, "tracker-a", 1), 2.0);
  streams.add(tracked_frame_of_six(1, 100.0, "tracker-b", 1), -1.0);
  streams.add(tracked_frame_of_six(2, 100.0, "tracker-a", 1), 0.017);
  streams.new_stream();
  streams.add(tracked_frame_of_six(0, 5.0, "tracker-c", 4), 0.017);
  streams.add(tracked_frame_of_six(1, 5.0, "tracker-c", 4), 0.017);
  write(dir / "clock-back-and-new-stream", streams.bytes());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s GRSIM_LOG OUTPUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const auto read = read_vision_log(argv[1]);
    if (!read) {
      std::fprintf(stderr, "cannot read %s: %s\n", argv[1], read.error().message.c_str());
      return 1;
    }
    const LogVisionPackets& log = *read;
    if (log.stopped_early || log.packets.size() < 8) {
      std::fprintf(stderr, "cannot read %s: %s\n", argv[1],
                   log.stopped_early ? log.stopped_early->message.c_str() : "too few packets");
      return 1;
    }
    const fs::path out = argv[2];
    for (const char* target : {"sampler", "log", "table", "referee", "tracker"})
      fs::create_directories(out / target);
    write_sampler_corpus(out / "sampler", log.packets);
    write_log_corpus(out / "log", log.packets);
    write_table_corpus(out / "table", log.packets);
    write_referee_corpus(out / "referee");
    write_tracker_corpus(out / "tracker");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_corpus: %s\n", e.what());
    return 1;
  }
  return 0;
}
