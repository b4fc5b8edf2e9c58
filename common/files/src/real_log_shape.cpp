#include "ssl_formation/files/real_log_shape.hpp"

#include <array>
#include <map>
#include <random>
#include <sstream>
#include <utility>
#include <vector>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {

std::optional<RealLogMess> parse_real_log_mess(std::string_view text) {
  RealLogMess mess;
  if (text == "none") return mess;
  if (text == "all") {
    mess.ghosts = mess.substitutions = mess.stoppages = mess.cuts = mess.change_of_ends = true;
    mess.noise_mm = 3.0;
    return mess;
  }
  std::istringstream parts{std::string(text)};
  std::string part;
  bool any = false;
  while (std::getline(parts, part, ',')) {
    any = true;
    if (part == "ghosts") {
      mess.ghosts = true;
    } else if (part == "substitutions") {
      mess.substitutions = true;
    } else if (part == "stoppages") {
      mess.stoppages = true;
    } else if (part == "cuts") {
      mess.cuts = true;
    } else if (part == "ends") {
      mess.change_of_ends = true;
    } else if (part == "noise") {
      mess.noise_mm = 3.0;
    } else {
      return std::nullopt;
    }
  }
  if (!any) return std::nullopt;
  return mess;
}

namespace {

// A stretch of the recording, as fractions of its length.
struct Stretch {
  double from = 0.0;
  double length_s = 0.0;
};
constexpr std::array<Stretch, 3> stoppages{{{0.10, 25.0}, {0.40, 25.0}, {0.83, 25.0}}};
constexpr std::array<Stretch, 2> cuts{{{0.25, 15.0}, {0.70, 20.0}}};
constexpr double change_of_ends_at = 0.5;
constexpr double half_time_break_s = 60.0;
struct Substitution {
  double from = 0.0;
  std::uint32_t leaves = 0;
  std::uint32_t comes = 0;
};
constexpr std::array<Substitution, 2> substitutions{{{1.0 / 3.0, 4, 12}, {0.63, 7, 14}}};
// 45 pairs of half-field packets a second (90 packets), the second half 11 ms after the first.
constexpr double pair_interval_s = 1.0 / 45.0;
constexpr double second_half_after_s = 0.011;

using Team = std::map<std::uint32_t, Point>;  // the last position seen of each robot id

struct Ghost {
  int packets_left = 0;
  bool yellow = true;
  RobotDetection detection;
};

class Messer {
 public:
  Messer(const RealLogMess& mess, double start_s, double length_s)
      : mess_(mess),
        start_s_(start_s),
        length_s_(length_s),
        ghosts_(mess.seed),
        noise_(mess.seed + 1) {}

  // The packets of one pair at recording time `t` (none inside a cut), with the time every
  // packet is stamped with (stoppages and the half-time break push later times back).
  void write_pair(double t, const Team& yellow, const Team& blue, LogWriter& out,
                  RealLogCounts& counts) {
    const double fraction = (t - start_s_) / length_s_;
    if (mess_.cuts) {
      for (const Stretch& cut : cuts) {
        const double from_s = start_s_ + cut.from * length_s_;
        if (t >= from_s && t < from_s + cut.length_s) return;
      }
    }
    if (mess_.stoppages) {
      for (std::size_t i = 0; i < stoppages.size(); ++i) {
        if (stopped_[i] || fraction < stoppages[i].from) continue;
        // Everyone stands where they are for the stoppage's length; the recording then goes on.
        stopped_[i] = true;
        for (double s = 0.0; s < stoppages[i].length_s; s += pair_interval_s) {
          write_halves(t + shift_s_ + s, yellow, blue, fraction, out, counts);
        }
        shift_s_ += stoppages[i].length_s;
      }
    }
    if (mess_.change_of_ends && !ends_changed_ && fraction >= change_of_ends_at) {
      ends_changed_ = true;
      shift_s_ += half_time_break_s;
    }
    write_halves(t + shift_s_, yellow, blue, fraction, out, counts);
  }

 private:
  void write_halves(double t, const Team& yellow, const Team& blue, double fraction, LogWriter& out,
                    RealLogCounts& counts) {
    start_ghost_maybe();
    for (const bool left : {true, false}) {
      DetectionFrameSpec spec;
      spec.frame_number = frame_number_++;
      spec.t_capture = left ? t : t + second_half_after_s;
      add_team(yellow, fraction, left, spec.yellow);
      add_team(blue, fraction, left, spec.blue);
      if (ghost_.packets_left > 0 && (ghost_.detection.position.x < 0.0) == left) {
        (ghost_.yellow ? spec.yellow : spec.blue).push_back(ghost_.detection);
        --ghost_.packets_left;
        ++counts.ghost_detections;
      }
      out.write_vision(make_detection_packet(spec),
                       static_cast<std::int64_t>(spec.t_capture * 1e9));
      ++counts.packets_written;
    }
  }

  void add_team(const Team& team, double fraction, bool left,
                std::vector<RobotDetection>& detections) {
    const double mirror = mess_.change_of_ends && ends_changed_ ? -1.0 : 1.0;
    for (const auto& [recorded_id, recorded] : team) {
      std::uint32_t id = recorded_id;
      if (mess_.substitutions) {
        for (const Substitution& s : substitutions) {
          if (fraction >= s.from && id == s.leaves) id = s.comes;
        }
      }
      Point p{mirror * recorded.x, mirror * recorded.y};
      if (mess_.noise_mm > 0.0) {
        std::normal_distribution<double> noise(0.0, mess_.noise_mm);
        p.x += noise(noise_);
        p.y += noise(noise_);
      }
      if ((p.x < 0.0) == left) detections.push_back({id, p});
    }
  }

  void start_ghost_maybe() {
    if (!mess_.ghosts || ghost_.packets_left > 0) return;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    if (unit(ghosts_) >= pair_interval_s / 4.0) return;  // one every 4 s
    ghost_.packets_left = 3 + static_cast<int>(unit(ghosts_) * 6.0);
    ghost_.yellow = unit(ghosts_) < 0.5;
    const bool own_id = unit(ghosts_) < 0.5;
    ghost_.detection.robot_id = own_id ? static_cast<std::uint32_t>(unit(ghosts_) * 11.0)
                                       : 11 + static_cast<std::uint32_t>(unit(ghosts_) * 5.0);
    ghost_.detection.position = {unit(ghosts_) * 12000.0 - 6000.0, unit(ghosts_) * 9000.0 - 4500.0};
    // A robot's own id more confident than the robot (0.9): the ghost wins the frame.
    ghost_.detection.confidence = own_id ? 0.95F : 0.5F;
  }

  RealLogMess mess_;
  double start_s_;
  double length_s_;
  std::mt19937_64 ghosts_;
  std::mt19937_64 noise_;
  std::array<bool, stoppages.size()> stopped_{};
  bool ends_changed_ = false;
  double shift_s_ = 0.0;
  std::uint32_t frame_number_ = 0;
  Ghost ghost_;
};

}  // namespace

Result<RealLogCounts> write_as_real_log(const std::filesystem::path& recording,
                                        const std::filesystem::path& out, const RealLogMess& mess) {
  RealLogCounts counts;
  std::error_code same_error;
  if (std::filesystem::equivalent(recording, out, same_error)) {
    return fail(out.string() + ": is the recording itself; writing it would destroy it");
  }
  SSL_WrapperPacket packet;
  // First pass: the recording's length, which places the mess.
  double first_s = 0.0;
  double last_s = 0.0;
  {
    auto reader = LogReader::open(recording);
    if (!reader) return fail(reader.error().message);
    while (reader->next_vision(packet)) {
      if (!packet.has_detection()) continue;
      const double t = packet.detection().t_capture();
      if (counts.packets_read++ == 0) first_s = t;
      last_s = std::max(last_s, t);
    }
  }
  if (counts.packets_read == 0) {
    return fail(recording.string() + ": no vision detection to reshape");
  }
  counts.recording_s = last_s - first_s;
  auto reader = LogReader::open(recording);
  if (!reader) return fail(reader.error().message);
  auto writer = LogWriter::create(out);
  if (!writer) return fail(writer.error().message);
  Messer messer(mess, first_s, std::max(counts.recording_s, 1e-9));
  Team yellow;
  Team blue;
  double next_pair_s = 0.0;
  while (reader->next_vision(packet)) {
    if (!packet.has_detection()) continue;
    const auto& detection = packet.detection();
    for (const auto& robot : detection.robots_yellow()) {
      yellow[robot.robot_id()] = {robot.x(), robot.y()};
    }
    for (const auto& robot : detection.robots_blue()) {
      blue[robot.robot_id()] = {robot.x(), robot.y()};
    }
    const double t = detection.t_capture();
    if (t < next_pair_s) continue;
    // A pause in the recording starts the beat again.
    next_pair_s = (t - next_pair_s > 1.0 ? t : next_pair_s) + pair_interval_s;
    messer.write_pair(t, yellow, blue, *writer, counts);
  }
  if (!writer->close()) return fail(out.string() + ": " + writer->error());
  return counts;
}

}  // namespace ssl_formation
