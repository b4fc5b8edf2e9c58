#pragma once
// The code paths the fuzz targets drive, with the invariants each one checks, shared by the
// libFuzzer targets (clang, SSLF_FUZZ=ON) and tests/common/files/fuzz_regressions_test.cpp (the
// normal gcc build), so a crashing input and its regression test run exactly the same code.
//
// Every function returns what happened and the first broken invariant (`violation`, empty if
// none) instead of aborting: a fuzz target aborts on it, a test reports it.
//
//  - sampler: bytes -> SSL_WrapperPacket (as the daemons decode datagrams) -> FormationSampler ->
//    TransitionTable and predict() from every formation, the whole live path.
//    Input: one config byte, then records of a little-endian u16 length and that many packet
//    bytes; the length 0xFFFF is a record without bytes that starts a new stream.
//  - log: bytes as a log file -> LogReader::open/next, and again with next_vision (whose
//    packets go through the sampler path), and again gzip-compressed.
//  - table: bytes as a table file -> load_table, then again with its two checksums fixed so the
//    fuzzer reaches the counts, then save/load round trips of what loaded.
//  - referee: timed datagrams (below) -> one RefereeFollower, as the referee group feeds it.
//  - tracker: timed datagrams -> one TrackedVision, and the frames it hands on through the
//    sampler, as with --vision-source tracked.
//    Timed datagrams: records of a little-endian u16 length, a little-endian u16 receive step
//    and that many bytes (the last may be cut short). The step is the milliseconds since the
//    previous datagram; with its top bit set the receive clock went back by the other 15 bits
//    instead. The length 0xFFFF is a record without step or bytes that starts a new stream
//    (reset(), as for a new log file).

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "ssl_formation/base/wire_text.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_formation/match/team_name_gate.hpp"
#include "ssl_formation/match/tracked_vision.hpp"
#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/paper_model/predictor.hpp"
#include "ssl_formation/vision/sampler.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::fuzz {

// ---- Helpers

// Records the first broken invariant only: later ones are usually its consequences.
struct Violations {
  std::string first;
  void fail(const std::string& what) {
    if (first.empty()) first = what;
  }
};

// Each write makes a new file: rewriting one in place (O_TRUNC) or renaming over one makes ext4
// flush it to disk at close (auto_da_alloc), which would slow the fuzzing down tenfold.
inline void remove_file(const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::remove(path, ec);
}

inline bool write_bytes(const std::filesystem::path& path, const std::uint8_t* data,
                        std::size_t size) {
  remove_file(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return static_cast<bool>(out);
}

inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline bool write_gzip(const std::filesystem::path& path, const std::uint8_t* data,
                       std::size_t size) {
  remove_file(path);
  gzFile file = gzopen(path.c_str(), "wb1");
  if (file == nullptr) return false;
  const bool ok =
      size == 0 || gzwrite(file, data, static_cast<unsigned>(size)) == static_cast<int>(size);
  return gzclose(file) == Z_OK && ok;
}

inline std::uint32_t le32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= std::uint32_t{p[i]} << (8 * i);
  return v;
}
inline std::uint64_t le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= std::uint64_t{p[i]} << (8 * i);
  return v;
}
inline void put_le32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

inline bool starts_with(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

inline std::uint16_t le16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

// The number of characters of `text`, which must be UTF-8 without an unprintable one; none if not.
// An escape printable_wire_text writes ("\x9B", "\u{202E}") counts as the one character it
// stands for (a backslash that came as such and happens to be followed by the same makes the
// count smaller, never larger).
inline std::optional<std::size_t> printable_chars(std::string_view text) {
  // Printable UTF-8 is what printable_wire_text gives back unchanged, however long.
  if (printable_wire_text(text, std::numeric_limits<std::size_t>::max()) != text) {
    return std::nullopt;
  }
  const auto hex = [](char c) { return (c >= '0' && c <= '9') || (c >= 'A' && c <= 'F'); };
  std::size_t chars = 0;
  for (std::size_t at = 0; at < text.size(); ++at) {
    if ((static_cast<unsigned char>(text[at]) & 0xC0) == 0x80) continue;  // inside a character
    ++chars;
    if (text[at] != '\\') continue;
    const std::string_view rest = text.substr(at + 1);
    if (rest.size() >= 3 && rest[0] == 'x' && hex(rest[1]) && hex(rest[2])) {
      at += 3;
    } else if (rest.size() >= 3 && rest[0] == 'u' && rest[1] == '{') {
      std::size_t end = 2;
      while (end < rest.size() && hex(rest[end])) ++end;
      if (end > 2 && end < rest.size() && rest[end] == '}') at += end + 1;
    }
  }
  return chars;
}

// What printable_wire_text (base/wire_text.hpp) promises of every text that came from the wire:
// printable UTF-8 of at most wire_text_max_chars characters, then "…(N bytes)" if it was cut.
inline void check_wire_text(std::string_view text, Violations& v, const std::string& where) {
  std::string_view kept = text;
  constexpr std::string_view cut_end = " bytes)";
  constexpr std::string_view cut_start = "\xE2\x80\xA6(";  // "…("
  if (kept.ends_with(cut_end)) {
    std::size_t digits = kept.size() - cut_end.size();
    const std::size_t digits_end = digits;
    while (digits > 0 && kept[digits - 1] >= '0' && kept[digits - 1] <= '9') --digits;
    if (digits < digits_end && kept.substr(0, digits).ends_with(cut_start))
      kept = kept.substr(0, digits - cut_start.size());
  }
  const std::optional<std::size_t> chars = printable_chars(kept);
  if (!chars) {
    v.fail(where + ": not printable UTF-8");
  } else if (*chars > wire_text_max_chars) {
    v.fail(where + ": " + std::to_string(*chars) + " characters, over wire_text_max_chars");
  }
}

// The table's counts as (from, to, count) triples, in increasing order.
struct Entry {
  StateIndex from;
  StateIndex to;
  TransitionTable::Count count;
  friend bool operator==(const Entry&, const Entry&) = default;
};
inline std::vector<Entry> entries_of(const TransitionTable& table) {
  std::vector<Entry> out;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count c) {
    out.push_back({from, to, c});
  });
  return out;
}

// What every table must satisfy whatever filled it: totals equal the sums of the counts.
inline void check_table(const TransitionTable& table, Violations& v, const std::string& where) {
  const StateCodec& codec = table.codec();
  const std::uint64_t states = codec.state_count();
  const std::uint64_t cells = codec.cell_count();
  std::uint64_t sum = 0;
  std::uint64_t row_sum = 0;
  std::optional<StateIndex> row;
  std::size_t nonzero = 0;
  std::size_t rows = 0;
  std::vector<std::uint64_t> centroid_sums(cells, 0);
  const auto close_row = [&] {
    if (row && table.row_total(*row) != row_sum) v.fail(where + ": row total != sum of its row");
  };
  bool in_order = true;
  std::optional<std::pair<StateIndex, StateIndex>> last;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count c) {
    if (from >= states || to >= states) v.fail(where + ": state index >= S");
    if (c == 0) v.fail(where + ": for_each_nonzero visited a zero count");
    if (last && !(*last < std::pair{from, to})) in_order = false;
    last = std::pair{from, to};
    if (row != from) {
      close_row();
      row = from;
      row_sum = 0;
      ++rows;
    }
    row_sum += c;
    sum += c;
    ++nonzero;
    if (from < states) centroid_sums[codec.centroid_id(from)] += c;
    if (table.count(from, to) != c) v.fail(where + ": count() differs from for_each_nonzero");
  });
  close_row();
  if (!in_order) v.fail(where + ": for_each_nonzero out of order");
  if (sum != table.transitions()) v.fail(where + ": transitions() != sum of counts");
  if (nonzero != table.nonzero_entries()) v.fail(where + ": nonzero_entries() != nonzero counts");
  if (rows != table.rows_seen()) v.fail(where + ": rows_seen() != rows with counts");
  for (StateIndex c = 0; c < cells; ++c) {
    if (table.centroid_total(c) != centroid_sums[c]) v.fail(where + ": centroid total != sum");
  }
}

// ---- Path 1: packets -> sampler -> table -> predict

struct SamplerOutcome {
  std::uint64_t packets = 0;      // records that decoded
  std::uint64_t undecodable = 0;  // records that did not (dropped, as the daemons do)
  std::uint64_t samples = 0;
  std::uint64_t transitions = 0;
  std::string violation;
};

// The sampler, its table and the invariants of everything they produce; packets come from a
// fuzz record stream or from a log.
class SamplerHarness {
 public:
  explicit SamplerHarness(const SamplerConfig& config)
      : table_(config.grid),
        sampler_(config, [this](const FormationSample& sample) { on_sample(sample); }) {}

  void add(const SSL_WrapperPacket& packet) { sampler_.add(packet); }
  void add(const VisionFrame& frame) { sampler_.add(frame); }
  void fail(const std::string& what) { v_.fail(what); }
  void start_new_stream() {
    sampler_.start_new_stream();
    ++epoch_;
  }

  SamplerOutcome finish(SamplerOutcome out) {
    check_table(table_, v_, "sampler table");
    if (table_.transitions() != added_) v_.fail("table holds other than the transitions added");
    const SamplerCounters& c = sampler_.counters();
    if (c.samples != samples_) v_.fail("counters().samples != samples handed on");
    if (c.transitions != transitions_) v_.fail("counters().transitions != transitions handed on");
    out.samples = samples_;
    out.transitions = transitions_;
    out.violation = v_.first;
    return out;
  }

 private:
  void on_sample(const FormationSample& sample) {
    const Formation& f = sample.formation;
    const SamplerConfig& config = sampler_.config();
    const Grid& grid = config.grid;
    const StateCodec& codec = sampler_.codec();
    const StateIndex states = codec.state_count();
    ++samples_;
    transitions_ += sample.transitions.size();

    if (f.robots.empty()) v_.fail("sampler emitted an empty formation");
    if (!grid.contains(f.centroid_cell)) v_.fail("centroid cell outside the grid");
    if (!std::isfinite(f.centroid.x) || !std::isfinite(f.centroid.y))
      v_.fail("centroid not finite");
    if (f.centroid_cell != grid.cell_of(f.centroid, sampler_.field()))
      v_.fail("centroid cell wrong");
    const std::uint64_t epoch = epoch_ + sampler_.counters().clock_resets;
    if (last_ && last_epoch_ == epoch && f.time_s < last_->time_s) v_.fail("sample time went back");
    if (f.continues_previous && (!last_ || last_epoch_ != epoch)) {
      v_.fail("formation continues a previous one that was not handed on");
    }
    std::size_t expected_transitions = 0;
    for (std::size_t i = 0; i < f.robots.size(); ++i) {
      const FormationRobot& r = f.robots[i];
      if (i > 0 && f.robots[i - 1].robot_id >= r.robot_id)
        v_.fail("robot ids not strictly increasing");
      if (r.robot_id > config.max_robot_id) v_.fail("robot id over max_robot_id");
      if (!grid.contains(r.cell) || !grid.contains(r.previous_cell))
        v_.fail("robot cell outside the grid");
      if (!std::isfinite(r.feed_position.x) || !std::isfinite(r.feed_position.y) ||
          std::abs(r.feed_position.x) > config.max_abs_coordinate_mm ||
          std::abs(r.feed_position.y) > config.max_abs_coordinate_mm) {
        v_.fail("robot position not finite or out of range");
      }
      if (r.position != normalise(r.feed_position, config.opponent_attacks))
        v_.fail("position not normalised");
      if (r.cell != grid.cell_of(r.position, sampler_.field())) v_.fail("robot cell wrong");
      if (r.state >= states) v_.fail("state index >= S");
      if (r.state != codec.encode(RobotState{f.centroid_cell, r.cell, r.previous_cell})) {
        v_.fail("state index does not encode the robot's cells");
      }
      const FormationRobot* before =
          f.continues_previous && last_ ? last_->find(r.robot_id) : nullptr;
      if (before != nullptr) {
        ++expected_transitions;
        if (r.previous_cell != before->cell)
          v_.fail("previous cell is not the cell of the last sample");
      } else if (r.previous_cell != r.cell) {
        v_.fail("robot starting a chain has a velocity");
      }
    }
    if (sample.transitions.size() != expected_transitions) v_.fail("wrong number of transitions");
    for (const Transition& t : sample.transitions) {
      if (t.from >= states || t.to >= states) v_.fail("transition state index >= S");
      const FormationRobot* now = f.find(t.robot_id);
      const FormationRobot* before = last_ ? last_->find(t.robot_id) : nullptr;
      if (now == nullptr || before == nullptr || t.to != now->state || t.from != before->state) {
        v_.fail("transition does not join the robot's last and current states");
      }
      added_ += table_.add(t.from, t.to);
    }
    last_ = f;
    last_epoch_ = epoch;

    // predict() from every formation, as ssl-predictor does.
    predict(table_, robot_states(f), 3, prediction_);
    if (prediction_.steps.size() != 3) v_.fail("prediction has the wrong number of steps");
    double confidence = 1.0;
    for (const PredictedStep& step : prediction_.steps) {
      if (!grid.contains(step.centroid)) v_.fail("predicted centroid outside the grid");
      if (!(step.centroid_probability > 0.0 && step.centroid_probability <= 1.0)) {
        v_.fail("centroid probability outside (0, 1]");
      }
      if (step.robots.size() != f.robots.size()) v_.fail("prediction lost or added robots");
      for (std::size_t i = 0; i < step.robots.size() && i < f.robots.size(); ++i) {
        const RobotPrediction& r = step.robots[i];
        if (r.robot_id != f.robots[i].robot_id) v_.fail("predicted robot ids differ");
        if (r.state >= states) v_.fail("predicted state index >= S");
        if (!grid.contains(r.position) || !grid.contains(r.previous))
          v_.fail("predicted cell outside the grid");
        if (codec.centroid_id(r.state) != static_cast<StateIndex>(grid.cell_id(step.centroid))) {
          v_.fail("predicted robot state not in the predicted centroid block");
        }
        if (!(r.probability > 0.0 && r.probability <= 1.0))
          v_.fail("robot probability outside (0, 1]");
      }
      confidence *= step.formation_probability;
      if (!(step.confidence >= 0.0 && step.confidence <= 1.0) || step.confidence != confidence) {
        v_.fail("confidence is not the product of the formation probabilities");
      }
    }
  }

  TransitionTable table_;
  FormationSampler sampler_;
  Prediction prediction_;
  Violations v_;
  std::optional<Formation> last_;
  std::uint64_t last_epoch_ = 0;
  std::uint64_t epoch_ = 0;
  std::uint64_t samples_ = 0;
  std::uint64_t transitions_ = 0;
  std::uint64_t added_ = 0;
};

// The sampler configuration a fuzz input's first byte selects.
inline SamplerConfig sampler_config(std::uint8_t selector) {
  static const Grid grids[] = {Grid(3, 2), Grid(1, 1), Grid(12, 9), Grid(16, 16)};
  static const double steps[] = {2.0, 0.1, 1.0 / 60.0, 1e-6};
  SamplerConfig config;
  config.grid = grids[selector & 3];
  config.opponent_color = (selector & 4) != 0 ? TeamColor::blue : TeamColor::yellow;
  config.opponent_attacks =
      (selector & 8) != 0 ? AttackDirection::negative_x : AttackDirection::positive_x;
  config.use_geometry = (selector & 16) == 0;
  config.step_s = steps[(selector >> 5) & 3];
  return config;
}

inline constexpr std::uint16_t new_stream_record = 0xFFFF;

// Bit for bit, so that NaN coordinates compare equal.
inline bool same_frame(const VisionFrame& a, const VisionFrame& b) {
  const auto same_robots = [](const std::vector<VisionRobot>& x,
                              const std::vector<VisionRobot>& y) {
    return std::equal(
        x.begin(), x.end(), y.begin(), y.end(), [](const VisionRobot& r, const VisionRobot& q) {
          return r.robot_id == q.robot_id && r.has_robot_id == q.has_robot_id &&
                 std::bit_cast<std::uint32_t>(r.x) == std::bit_cast<std::uint32_t>(q.x) &&
                 std::bit_cast<std::uint32_t>(r.y) == std::bit_cast<std::uint32_t>(q.y) &&
                 std::bit_cast<std::uint32_t>(r.confidence) ==
                     std::bit_cast<std::uint32_t>(q.confidence);
        });
  };
  return a.has_detection == b.has_detection && a.has_geometry == b.has_geometry &&
         a.detection.frame_number == b.detection.frame_number &&
         std::bit_cast<std::uint64_t>(a.detection.t_capture) ==
             std::bit_cast<std::uint64_t>(b.detection.t_capture) &&
         a.detection.camera_id == b.detection.camera_id &&
         same_robots(a.detection.robots_yellow, b.detection.robots_yellow) &&
         same_robots(a.detection.robots_blue, b.detection.robots_blue);
}

inline SamplerOutcome run_sampler_path(const std::uint8_t* data, std::size_t size) {
  SamplerOutcome out;
  if (size == 0) return out;
  SamplerHarness harness(sampler_config(data[0]));
  SSL_WrapperPacket packet;
  VisionFrame direct;
  VisionFrame reference;
  std::size_t at = 1;
  while (at + 2 <= size) {
    const std::uint16_t length = static_cast<std::uint16_t>(data[at] | (data[at + 1] << 8));
    at += 2;
    if (length == new_stream_record) {
      harness.start_new_stream();
      continue;
    }
    const std::size_t n = std::min<std::size_t>(length, size - at);
    // As the daemons decode a datagram (net/vision_receiver.hpp): straight from the bytes if
    // decode_detection_datagram takes it, which must then agree with protobuf; otherwise a
    // partial parse, then required fields, so that a packet missing one is dropped.
    const auto bytes = std::as_bytes(std::span(data + at, n));
    const bool parsed =
        packet.ParsePartialFromArray(data + at, static_cast<int>(n)) && packet.IsInitialized();
    if (decode_detection_datagram(bytes, direct)) {
      if (!parsed) {
        harness.fail("decode_detection_datagram took a datagram protobuf refuses");
      } else {
        to_vision_frame(packet, reference);
        if (!same_frame(direct, reference)) {
          harness.fail("decode_detection_datagram and protobuf read a datagram differently");
        }
      }
      ++out.packets;
      harness.add(direct);
    } else if (parsed) {
      ++out.packets;
      harness.add(packet);
    } else {
      ++out.undecodable;
    }
    at += n;
  }
  return harness.finish(out);
}

// ---- Path 2: log files

struct LogOutcome {
  bool opened = false;
  std::string error;                 // open's error, or the reader's at the end
  std::uint64_t messages = 0;        // from next()
  std::uint64_t vision_packets = 0;  // from next_vision()
  LogReadCounters counters;          // next_vision's reader
  std::string violation;
};

struct RawRead {
  bool opened = false;
  std::string error;
  std::vector<LogMessage> messages;
  LogReadCounters counters;
};

inline RawRead read_raw_log(const std::filesystem::path& path, Violations& v) {
  RawRead out;
  Result<LogReader> reader = LogReader::open(path);
  if (!reader) {
    out.error = reader.error().message;
    if (out.error.empty() || !starts_with(out.error, path.string() + ": ")) {
      v.fail("open failed without an error naming the path");
    }
    return out;
  }
  out.opened = true;
  std::uint64_t expected_offset = kLogFileHeaderSize;
  LogMessage message;
  while (reader->next(message)) {
    if (message.offset != expected_offset) v.fail("message offset does not follow the previous");
    if (message.type == static_cast<std::int32_t>(LogMessageType::index))
      v.fail("next() returned an index");
    if (message.payload.size() > static_cast<std::size_t>(kLogMaxMessageSize))
      v.fail("payload over the limit");
    expected_offset += kLogMessageHeaderSize + message.payload.size();
    out.messages.push_back(message);
  }
  if (reader->next(message)) v.fail("next() returned a message after the end");
  const LogReadCounters& c = reader->counters();
  if (c.messages != out.messages.size() + c.index) v.fail("counters().messages != messages read");
  if (c.blank + c.unknown + c.legacy_vision + c.referee + c.vision + c.tracker + c.index !=
      c.messages) {
    v.fail("counters by type do not add up to counters().messages");
  }
  if (c.index > 1) v.fail("read past an index message");
  if (c.bytes != expected_offset) v.fail("counters().bytes != bytes of the messages read");
  out.error = reader->error();
  if (!out.error.empty() && !starts_with(out.error, path.string() + ": "))
    v.fail("error does not name the path");
  out.counters = c;
  return out;
}

inline LogOutcome run_log_path(const std::uint8_t* data, std::size_t size,
                               const std::filesystem::path& dir) {
  LogOutcome out;
  Violations v;
  const std::filesystem::path path = dir / "input.log";
  if (!write_bytes(path, data, size)) {
    out.violation = "cannot write " + path.string();
    return out;
  }

  const RawRead raw = read_raw_log(path, v);
  out.opened = raw.opened;
  out.error = raw.error;
  out.messages = raw.messages.size();

  if (raw.opened) {
    // The replay path: next_vision into the sampler, as ssl-trainer --replay and ssl-evaluate do.
    Result<LogReader> reader = LogReader::open(path);
    if (!reader) {
      v.fail("the second open of the same file failed: " + reader.error().message);
    } else {
      SamplerConfig config;
      config.step_s = 0.1;
      SamplerHarness harness(config);
      SSL_WrapperPacket packet;
      std::int64_t receive_time_ns = 0;
      while (reader->next_vision(packet, &receive_time_ns)) {
        ++out.vision_packets;
        if (!packet.IsInitialized())
          v.fail("next_vision returned a packet lacking required fields");
        harness.add(packet);
        packet.Clear();
      }
      const LogReadCounters& c = reader->counters();
      out.counters = c;
      if (reader->error() != raw.error) v.fail("next_vision stopped with another error than next");
      if (c.messages != raw.counters.messages || c.vision != raw.counters.vision ||
          c.legacy_vision != raw.counters.legacy_vision || c.bytes != raw.counters.bytes) {
        v.fail("next_vision counted other messages than next");
      }
      if (out.vision_packets + c.parse_errors + c.legacy_unusable != c.vision + c.legacy_vision) {
        v.fail("vision packets returned + refused != vision messages");
      }
      const SamplerOutcome sampled = harness.finish({});
      if (!sampled.violation.empty()) v.fail("replay: " + sampled.violation);
    }
  }

  // The same stream gzip-compressed must read the same (the reader takes either, whatever the
  // name). Not for inputs that are gzip already: zlib would unwrap one layer only.
  if (size < 2 || data[0] != 0x1f || data[1] != 0x8b) {
    if (!write_gzip(path, data, size)) {
      v.fail("cannot write " + path.string());
    } else {
      Violations ignored;  // reported by the first pass
      const RawRead gz = read_raw_log(path, ignored);
      if (gz.opened != raw.opened || gz.error != raw.error) {
        v.fail("gzip-compressed stream read differently: '" + gz.error + "' vs '" + raw.error +
               "'");
      } else if (gz.messages.size() != raw.messages.size()) {
        v.fail("gzip-compressed stream gave another number of messages");
      } else {
        for (std::size_t i = 0; i < gz.messages.size(); ++i) {
          const LogMessage& a = gz.messages[i];
          const LogMessage& b = raw.messages[i];
          if (a.offset != b.offset || a.type != b.type || a.receive_time_ns != b.receive_time_ns ||
              a.payload != b.payload) {
            v.fail("gzip-compressed stream gave another message " + std::to_string(i));
          }
        }
      }
    }
  }
  out.violation = v.first;
  return out;
}

// ---- Path 3: table files

struct TableOutcome {
  std::optional<TableFileError> error;        // the bytes as given; nullopt if they loaded
  std::optional<TableFileError> fixed_error;  // with both checksums fixed
  bool fixed_tried = false;
  std::string violation;
};

inline constexpr std::size_t table_header_size = 84;

// A load's result against the file it read: failures name the path, successes match the header.
inline void check_load(const Result<StoredTable, TableLoadError>& r,
                       const std::filesystem::path& path, const std::string& bytes, Violations& v,
                       const std::string& where) {
  if (!r) {
    if (!starts_with(r.error().message, path.string()))
      v.fail(where + ": error message does not name the path");
    return;
  }
  if (bytes.size() < table_header_size + 4) {
    v.fail(where + ": loaded a file shorter than header and checksum");
    return;
  }
  const auto* h = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const TransitionTable& table = r->table;
  const TableMetadata& m = r->metadata;
  if (table.grid().length() != static_cast<int>(le32(h + 12)) ||
      table.grid().width() != static_cast<int>(le32(h + 16))) {
    v.fail(where + ": grid differs from the header");
  }
  if (std::bit_cast<std::uint64_t>(m.field.length_mm) != le64(h + 24) ||
      std::bit_cast<std::uint64_t>(m.field.width_mm) != le64(h + 32) ||
      std::bit_cast<std::uint64_t>(m.step_s) != le64(h + 40) || m.samples != le64(h + 48)) {
    v.fail(where + ": metadata differs from the header");
  }
  if (!m.field.valid() || !(m.step_s > 0.0) || !std::isfinite(m.step_s))
    v.fail(where + ": invalid metadata loaded");
  if (table.transitions() != le64(h + 56)) v.fail(where + ": transitions != the header's total");
  const std::uint32_t encoding = le32(h + 20);
  if (encoding == 1 &&
      (table.nonzero_entries() != le64(h + 72) || table.rows_seen() != le64(h + 64))) {
    v.fail(where + ": sparse entries or rows differ from the header");
  }
  check_table(table, v, where);
}

inline TableOutcome run_table_path(const std::uint8_t* data, std::size_t size,
                                   const std::filesystem::path& dir) {
  TableOutcome out;
  Violations v;
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::filesystem::path path = dir / "input.sslft";

  // Loads `bytes` and checks the result; the table if it loaded.
  const auto load = [&](const std::string& bytes, const std::string& where,
                        std::optional<TableFileError>& error) -> std::optional<StoredTable> {
    if (!write_bytes(path, reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size())) {
      v.fail("cannot write " + path.string());
      return std::nullopt;
    }
    Result<StoredTable, TableLoadError> r = load_table(path);
    error = r ? std::nullopt : std::optional(r.error().kind);
    check_load(r, path, bytes, v, where);
    if (read_bytes(path) != bytes) v.fail(where + ": loading changed the file");
    if (!r) return std::nullopt;
    // Other storage and an expected grid: same counts, or wrong_grid for another grid.
    const TransitionTable& table = r->table;
    const auto sparse = load_table(path, table.grid(), TableStorage::sparse);
    if (!sparse) {
      v.fail(where +
             ": loads automatically but not sparse with its own grid: " + sparse.error().message);
    } else if (entries_of(sparse->table) != entries_of(table)) {
      v.fail(where + ": sparse storage loaded other counts");
    }
    const Grid other = table.grid() == Grid(3, 2) ? Grid(2, 3) : Grid(3, 2);
    const auto wrong = load_table(path, other);
    if (wrong || wrong.error().kind != TableFileError::wrong_grid)
      v.fail(where + ": another grid was accepted");
    return std::move(*r);
  };

  std::optional<StoredTable> loaded = load(input, "as given", out.error);

  // The checksums stop nearly every mutation before the counts; fixed, the fuzzer reaches them.
  if (size >= table_header_size) {
    std::string fixed = input;
    auto* b = reinterpret_cast<std::uint8_t*>(fixed.data());
    put_le32(b + 80, static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0), b, 80)));
    if (size >= table_header_size + 4) {
      put_le32(b + size - 4, static_cast<std::uint32_t>(
                                 crc32(crc32(0L, Z_NULL, 0), b, static_cast<uInt>(size - 4))));
    }
    if (fixed != input) {
      out.fixed_tried = true;
      std::optional<StoredTable> fixed_loaded = load(fixed, "checksums fixed", out.fixed_error);
      if (!loaded) loaded = std::move(fixed_loaded);
    }
  }

  // Whatever loaded saves and loads back unchanged.
  if (loaded) {
    const std::filesystem::path copy = dir / "roundtrip.sslft";
    remove_file(copy);
    const auto saved = save_table(copy, loaded->table, loaded->metadata);
    if (!saved) {
      v.fail("a loaded table does not save: " + saved.error().message);
    } else {
      const auto again = load_table(copy, loaded->table.grid());
      if (!again) {
        v.fail("a saved table does not load: " + again.error().message);
      } else if (!(again->metadata == loaded->metadata) ||
                 entries_of(again->table) != entries_of(loaded->table)) {
        v.fail("a saved table loads back different");
      }
    }
  }
  out.violation = v.first;
  return out;
}

// ---- Timed datagrams, for paths 4 and 5

inline constexpr std::uint16_t clock_back_bit = 0x8000;

// One record of a timed datagram input (see the top of this file).
struct TimedDatagram {
  bool new_stream = false;  // a new-stream record: no bytes, no time
  bool clock_back = false;  // the receive clock went back before this datagram
  std::string_view bytes;
  double receive_s = 0.0;
};

class TimedDatagrams {
 public:
  TimedDatagrams(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  // The next record; false at the end of the input (a record cut before its bytes included).
  bool next(TimedDatagram& out) {
    out = TimedDatagram{};
    if (at_ + 2 > size_) return false;
    const std::uint16_t length = le16(data_ + at_);
    at_ += 2;
    if (length == new_stream_record) {
      out.new_stream = true;
      return true;
    }
    if (at_ + 2 > size_) return false;
    const std::uint16_t step = le16(data_ + at_);
    at_ += 2;
    const std::int64_t step_ms = step & ~clock_back_bit;
    out.clock_back = (step & clock_back_bit) != 0;
    clock_ms_ += out.clock_back ? -step_ms : step_ms;
    // Whole milliseconds: the same instants the followers' own subtractions see, exactly.
    out.receive_s = static_cast<double>(clock_ms_) / 1000.0;
    const std::size_t n = std::min<std::size_t>(length, size_ - at_);
    out.bytes = std::string_view(reinterpret_cast<const char*>(data_ + at_), n);
    at_ += n;
    return true;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
  std::int64_t clock_ms_ = 0;
};

// ---- Path 4: referee datagrams -> RefereeFollower

struct RefereeOutcome {
  std::uint64_t datagrams = 0;
  std::uint64_t name_changes = 0;  // RefereeChange::teams, the first naming included
  RefereeCounters counters;
  std::string violation;
};

inline bool same_view(const RefereeView& a, const RefereeView& b) {
  return a.state == b.state && a.command == b.command && a.command_counter == b.command_counter &&
         a.stage == b.stage && a.yellow_name == b.yellow_name && a.blue_name == b.blue_name &&
         a.blue_on_positive_half == b.blue_on_positive_half &&
         a.designated_position == b.designated_position && a.source == b.source;
}

// describe() holds the names as they are, between fixed words well under this many bytes.
inline constexpr std::size_t describe_max_bytes_besides_names = 150;

// The promises of referee.hpp, message by message. Team names are checked against what the
// message said (read here once more, as add() reads it) and against the product's own rule
// (TeamNameGate, fed the same names and times): they take over exactly when it says, and then
// as the message said them.
inline RefereeOutcome run_referee_path(const std::uint8_t* data, std::size_t size) {
  RefereeOutcome out;
  Violations v;
  RefereeFollower referee;
  Referee message;
  TeamNameGate names_rule;
  TimedDatagrams records(data, size);
  TimedDatagram d;
  while (records.next(d)) {
    if (d.new_stream) {
      referee.reset();
      if (referee.heard() || !same_view(referee.view(), RefereeView{}))
        v.fail("reset() kept something of the view");
      names_rule.reset();
      continue;
    }
    ++out.datagrams;
    const RefereeCounters before = referee.counters();
    const RefereeView view_before = referee.view();
    RefereeChange change;
    try {
      change = referee.add(d.bytes, d.receive_s);
    } catch (const std::exception& e) {
      v.fail(std::string("add() threw: ") + e.what());
      break;
    } catch (...) {
      v.fail("add() threw");
      break;
    }
    const RefereeCounters& c = referee.counters();
    const RefereeView& view = referee.view();
    const bool used = c.used != before.used;

    if (c.messages != before.messages + 1) v.fail("counters().messages did not count a message");
    if (c.used + c.undecodable + c.unknown_command + c.other_source + c.stale != c.messages)
      v.fail("used + undecodable + unknown_command + other_source + stale != messages");
    if (change.stale != (c.stale != before.stale))
      v.fail("change.stale and counters().stale differ");
    if (change.source != (c.source_switches != before.source_switches))
      v.fail("change.source and counters().source_switches differ");
    if (change.command != (c.commands != before.commands))
      v.fail("change.command and counters().commands differ");
    if (change.conflict && c.other_source == before.other_source)
      v.fail("a conflict not counted in other_source");
    if (!used && (change.any() || !same_view(view, view_before)))
      v.fail("a message not used changed the view");
    if (used && !referee.heard()) v.fail("a message used, but heard() is false");
    const bool names_changed =
        view.yellow_name != view_before.yellow_name || view.blue_name != view_before.blue_name;
    if (change.teams != names_changed) v.fail("change.teams differs from a change of the names");
    if (change.sides != (view.blue_on_positive_half != view_before.blue_on_positive_half))
      v.fail("change.sides differs from a change of blue_on_positive_half");
    if (referee.heard() && game_state_of_command(view.command) != view.state)
      v.fail("the game state is not the last command's");
    if (view.designated_position && (!std::isfinite(view.designated_position->x) ||
                                     !std::isfinite(view.designated_position->y)))
      v.fail("designated_position not finite");
    check_wire_text(view.yellow_name, v, "yellow_name");
    check_wire_text(view.blue_name, v, "blue_name");
    check_wire_text(view.source, v, "source");
    const std::string described = describe(referee);
    if (!printable_chars(described)) v.fail("describe() not printable UTF-8");
    if (described.size() >
        describe_max_bytes_besides_names + view.yellow_name.size() + view.blue_name.size())
      v.fail("describe() holds more than the names and its own words");

    if (!used) continue;
    if (!message.ParsePartialFromArray(d.bytes.data(), static_cast<int>(d.bytes.size()))) {
      v.fail("a message used that protobuf does not parse");
      continue;
    }
    if (view.source != printable_wire_text(message.source_identifier()) ||
        view.command != message.command() || view.command_counter != message.command_counter())
      v.fail("the view is not what the message used said");
    std::pair<std::string, std::string> names{printable_wire_text(message.yellow().name()),
                                              printable_wire_text(message.blue().name())};
    const bool take_over = names_rule.take_over(view_before.yellow_name, view_before.blue_name,
                                                names.first, names.second, d.receive_s);
    if (change.teams != take_over) v.fail("team names took over other than TeamNameGate says");
    if (!change.teams) continue;
    ++out.name_changes;
    if (view.yellow_name != names.first || view.blue_name != names.second)
      v.fail("names taken over other than the message's");
  }
  out.counters = referee.counters();
  out.violation = v.first;
  return out;
}

// ---- Path 5: tracker datagrams -> TrackedVision -> sampler

struct TrackerOutcome {
  std::uint64_t datagrams = 0;
  TrackerCounters counters;
  SamplerOutcome sampled;  // the frames handed on, through the sampler
  std::string violation;
};

inline bool same_ball(const std::optional<BallState>& a, const std::optional<BallState>& b) {
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  if (!a || !b) return !a && !b;
  return bits(a->time_s) == bits(b->time_s) && bits(a->position.x) == bits(b->position.x) &&
         bits(a->position.y) == bits(b->position.y) && bits(a->velocity.x) == bits(b->velocity.x) &&
         bits(a->velocity.y) == bits(b->velocity.y);
}

// The promises of tracked_vision.hpp, datagram by datagram. Robot positions come as the tracker
// sent them, finite or not (the header promises nothing there): the sampler behind, as with
// --vision-source tracked, is what must refuse what is not finite or out of range, and its own
// invariants (SamplerHarness) say whether it did.
inline TrackerOutcome run_tracker_path(const std::uint8_t* data, std::size_t size) {
  TrackerOutcome out;
  Violations v;
  TrackedVision tracked;
  // One cell: the sampler path fuzzes the grids; here a table of a single state keeps each run
  // fast (a 3 x 2 grid's dense table alone took 2 ms to set up and check).
  SamplerConfig config;
  config.grid = Grid(1, 1);
  config.step_s = 0.1;
  SamplerHarness harness(config);
  VisionFrame frame;
  // When the tracker followed last sent anything (a frame or not), for its source timeout.
  double followed_heard_s = 0.0;
  TimedDatagrams records(data, size);
  TimedDatagram d;
  while (records.next(d)) {
    if (d.new_stream) {
      tracked.reset();
      harness.start_new_stream();
      if (!tracked.source_uuid().empty() || !tracked.source_name().empty() || tracked.ball())
        v.fail("reset() kept the tracker followed or its ball");
      continue;
    }
    ++out.datagrams;
    const TrackerCounters before = tracked.counters();
    const std::string uuid_before = tracked.source_uuid();
    const std::optional<BallState> ball_before = tracked.ball();
    bool handed_on = false;
    try {
      handed_on = tracked.add(d.bytes, d.receive_s, frame);
    } catch (const std::exception& e) {
      v.fail(std::string("add() threw: ") + e.what());
      break;
    } catch (...) {
      v.fail("add() threw");
      break;
    }
    const TrackerCounters& c = tracked.counters();
    if (c.packets != before.packets + 1) v.fail("counters().packets did not count a datagram");
    if (c.undecodable + c.without_frame + c.other_source + c.frames != c.packets)
      v.fail("undecodable + without_frame + other_source + frames != packets");
    if (handed_on != (c.frames != before.frames))
      v.fail("add() returned other than counters().frames says");
    check_wire_text(tracked.source_uuid(), v, "source_uuid");
    check_wire_text(tracked.source_name(), v, "source_name");

    const bool switched = tracked.source_uuid() != uuid_before;
    if (switched && !uuid_before.empty() &&
        !(d.receive_s - followed_heard_s > TrackedVision::source_timeout_s ||
          d.receive_s < followed_heard_s)) {
      v.fail("another tracker took over while the one followed still spoke");
    }
    if (c.undecodable == before.undecodable && c.other_source == before.other_source)
      followed_heard_s = d.receive_s;

    if (!handed_on) {
      if (!same_ball(tracked.ball(), ball_before)) v.fail("ball() changed with no frame handed on");
      continue;
    }
    if (!frame.has_detection || frame.has_geometry || frame.detection.camera_id != 0)
      v.fail("a frame handed on other than as camera 0's detection");
    for (const auto* team : {&frame.detection.robots_yellow, &frame.detection.robots_blue}) {
      for (const VisionRobot& robot : *team) {
        if (!robot.has_robot_id) v.fail("a robot without an id handed on");
      }
    }
    if (const std::optional<BallState>& ball = tracked.ball()) {
      if (!std::isfinite(ball->position.x) || !std::isfinite(ball->position.y))
        v.fail("ball() position not finite");
      if (!std::isfinite(ball->velocity.x) || !std::isfinite(ball->velocity.y))
        v.fail("ball() velocity not finite");
      if (std::bit_cast<std::uint64_t>(ball->time_s) !=
          std::bit_cast<std::uint64_t>(frame.detection.t_capture))
        v.fail("ball() not at the frame's timestamp");
    }
    harness.add(frame);
  }
  out.counters = tracked.counters();
  out.sampled = harness.finish({});
  if (!out.sampled.violation.empty()) v.fail("sampler: " + out.sampled.violation);
  out.violation = v.first;
  return out;
}

}  // namespace ssl_formation::fuzz
