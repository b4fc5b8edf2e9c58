#include "ssl_formation/files/real_log_shape.hpp"

#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
inline namespace files {

std::optional<RealLogMess> parse_real_log_mess(std::string_view text) {
  RealLogMess mess;
  if (text == "none") return mess;
  if (text == "all") {
    mess.ghosts = mess.substitutions = mess.stoppages = mess.cuts = mess.change_of_ends = true;
    mess.noise_mm = RealLogMess::real_noise_mm;
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
      mess.noise_mm = RealLogMess::real_noise_mm;
    } else if (part.rfind("noise=", 0) == 0) {
      // Another level of noise, in mm: to see what a noisier vision than the logs' does.
      const std::string value = part.substr(6);
      std::size_t used = 0;
      double mm = -1.0;
      try {
        mm = std::stod(value, &used);
      } catch (const std::exception&) {
        return std::nullopt;
      }
      if (used != value.size() || !std::isfinite(mm) || mm < 0.0 || mm > 1000.0)
        return std::nullopt;
      mess.noise_mm = mm;
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
// The recording's ball as last seen (the most confident candidate of its latest packet), none
// before the first: real logs have a ball, and the motion model reads whether it is in flight.
using RecordedBall = std::optional<Point>;

// The reshaped log's referee sends a message this often (a game controller sends about ten a
// second), and one at each new command.
constexpr double referee_interval_s = 0.1;
constexpr std::string_view referee_source = "ssl-evaluate as-real-log";

// What the recording's referee says of the teams (its first message naming one).
struct RecordedTeams {
  std::string yellow = "Yellow";
  std::string blue = "Blue";
  std::uint32_t yellow_goalkeeper = 0;
  std::uint32_t blue_goalkeeper = 0;
  std::optional<bool> blue_on_positive_half;
  bool named = false;
};

void take_teams(std::string_view payload, RecordedTeams& teams) {
  if (teams.named) return;
  Referee referee;
  if (!referee.ParsePartialFromArray(payload.data(), static_cast<int>(payload.size()))) return;
  if (referee.yellow().name().empty() && referee.blue().name().empty()) return;
  teams.named = true;
  if (!referee.yellow().name().empty()) teams.yellow = referee.yellow().name();
  if (!referee.blue().name().empty()) teams.blue = referee.blue().name();
  teams.yellow_goalkeeper = referee.yellow().goalkeeper();
  teams.blue_goalkeeper = referee.blue().goalkeeper();
  if (referee.has_blue_team_on_positive_half()) {
    teams.blue_on_positive_half = referee.blue_team_on_positive_half();
  }
}

std::uint64_t microseconds(double t_s) {
  return t_s <= 0.0 ? 0 : static_cast<std::uint64_t>(std::llround(t_s * 1e6));
}

// The reshaped log's game controller: the command and stage it is told at each moment, sent as
// a game controller sends them.
class RefereeScript {
 public:
  explicit RefereeScript(const RecordedTeams& teams)
      : blue_on_positive_half_(teams.blue_on_positive_half) {
    for (auto [team, name, goalkeeper] :
         {std::tuple{message_.mutable_yellow(), &teams.yellow, teams.yellow_goalkeeper},
          std::tuple{message_.mutable_blue(), &teams.blue, teams.blue_goalkeeper}}) {
      team->set_name(*name);
      team->set_score(0);
      team->set_red_cards(0);
      team->set_yellow_cards(0);
      team->set_timeouts(4);
      team->set_timeout_time(300'000'000);
      team->set_goalkeeper(goalkeeper);
    }
    message_.set_source_identifier(std::string(referee_source));
  }

  // `command` in `stage` holds from data time `t` on (the teams on the other ends once they
  // have changed them): a message when either is new, else when the last is 0.1 s old.
  void at(double t, Referee::Command command, Referee::Stage stage, bool ends_changed,
          LogWriter& out, RealLogCounts& counts) {
    const bool new_command = !started_ || command != message_.command();
    const bool new_stage = !started_ || stage != message_.stage();
    if (!new_command && !new_stage && t < last_sent_s_ + referee_interval_s - 1e-9) return;
    if (new_command) {
      message_.set_command(command);
      message_.set_command_counter(message_.command_counter() + 1);
      message_.set_command_timestamp(microseconds(t));
    }
    message_.set_stage(stage);
    if (blue_on_positive_half_) {
      message_.set_blue_team_on_positive_half(*blue_on_positive_half_ != ends_changed);
    }
    message_.set_packet_timestamp(microseconds(t));
    message_.SerializeToString(&scratch_);
    // Stamped as the vision packets are (write_halves), so a message and the pair it comes
    // with are received at the same nanosecond.
    out.write(static_cast<std::int32_t>(LogMessageType::referee),
              static_cast<std::int64_t>(t * 1e9), scratch_);
    started_ = true;
    last_sent_s_ = t;
    ++counts.referee_messages;
  }

 private:
  Referee message_;
  std::optional<bool> blue_on_positive_half_;
  std::string scratch_;
  double last_sent_s_ = 0.0;
  bool started_ = false;
};

struct Ghost {
  int packets_left = 0;
  bool yellow = true;
  RobotDetection detection;
};

class Messer {
 public:
  Messer(const RealLogMess& mess, double start_s, double length_s, const RecordedTeams& teams)
      : mess_(mess),
        start_s_(start_s),
        length_s_(length_s),
        ghosts_(mess.seed),
        noise_(mess.seed + 1) {
    // The stoppages come with the referee that says so.
    if (mess_.stoppages) referee_.emplace(teams);
  }

  // The packets of one pair at recording time `t` (none inside a cut), with the time every
  // packet is stamped with (stoppages and the half-time break push later times back).
  void write_pair(double t, const Team& yellow, const Team& blue, const RecordedBall& ball,
                  LogWriter& out, RealLogCounts& counts) {
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
        // Everyone stands where they are for the stoppage's length, in HALT; the recording then
        // goes on, the referee restarting the play at once.
        stopped_[i] = true;
        // Counted, not summed: a sum of 1/45 s steps can fall a hair short of the length and
        // put one pair more, on the time of the pair that follows.
        const auto pairs =
            static_cast<int>(std::ceil(stoppages[i].length_s / pair_interval_s - 1e-9));
        for (int k = 0; k < pairs; ++k) {
          const double s = k * pair_interval_s;
          referee_at(t + shift_s_ + s, Referee::HALT, out, counts);
          write_halves(t + shift_s_ + s, yellow, blue, ball, fraction, out, counts);
        }
        shift_s_ += stoppages[i].length_s;
        running_command_ = Referee::FORCE_START;
      }
    }
    if (mess_.change_of_ends && !ends_changed_ && fraction >= change_of_ends_at) {
      // The half-time break: no vision, the referee halting the game, and the teams back on the
      // other ends.
      stage_ = Referee::NORMAL_HALF_TIME;
      const auto messages =
          static_cast<int>(std::ceil(half_time_break_s / referee_interval_s - 1e-9));
      for (int k = 0; k < messages; ++k) {
        referee_at(t + shift_s_ + k * referee_interval_s, Referee::HALT, out, counts);
      }
      ends_changed_ = true;
      stage_ = Referee::NORMAL_SECOND_HALF;
      running_command_ = Referee::FORCE_START;
      shift_s_ += half_time_break_s;
    }
    referee_at(t + shift_s_, running_command_, out, counts);
    write_halves(t + shift_s_, yellow, blue, ball, fraction, out, counts);
  }

 private:
  void referee_at(double t, Referee::Command command, LogWriter& out, RealLogCounts& counts) {
    if (referee_) referee_->at(t, command, stage_, ends_changed_, out, counts);
  }

  void write_halves(double t, const Team& yellow, const Team& blue, const RecordedBall& ball,
                    double fraction, LogWriter& out, RealLogCounts& counts) {
    start_ghost_maybe();
    for (const bool left : {true, false}) {
      DetectionFrameSpec spec;
      spec.frame_number = frame_number_++;
      spec.t_capture = left ? t : t + second_half_after_s;
      add_team(yellow, fraction, left, spec.yellow);
      add_team(blue, fraction, left, spec.blue);
      add_ball(ball, left, spec.balls);
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

  // A recorded position as the messed-up vision reports it: mirrored after the change of ends,
  // with the noise.
  Point as_seen(Point recorded) {
    const double mirror = mess_.change_of_ends && ends_changed_ ? -1.0 : 1.0;
    Point p{mirror * recorded.x, mirror * recorded.y};
    if (mess_.noise_mm > 0.0) {
      std::normal_distribution<double> noise(0.0, mess_.noise_mm);
      p.x += noise(noise_);
      p.y += noise(noise_);
    }
    return p;
  }

  void add_team(const Team& team, double fraction, bool left,
                std::vector<RobotDetection>& detections) {
    for (const auto& [recorded_id, recorded] : team) {
      std::uint32_t id = recorded_id;
      if (mess_.substitutions) {
        for (const Substitution& s : substitutions) {
          if (fraction >= s.from && id == s.leaves) id = s.comes;
        }
      }
      const Point p = as_seen(recorded);
      if ((p.x < 0.0) == left) detections.push_back({id, p});
    }
  }

  // The ball in the packet of its half, where the robots' positions go (mirrored, noisy).
  void add_ball(const RecordedBall& ball, bool left, std::vector<Point>& balls) {
    if (!ball) return;
    const Point p = as_seen(*ball);
    if ((p.x < 0.0) == left) balls.push_back(p);
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
  std::optional<RefereeScript> referee_;
  Referee::Command running_command_ = Referee::NORMAL_START;
  Referee::Stage stage_ = Referee::NORMAL_FIRST_HALF;
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
  // First pass: the recording's length, which places the mess, and its referee's team names.
  double first_s = 0.0;
  double last_s = 0.0;
  RecordedTeams teams;
  {
    auto reader = LogReader::open(recording);
    if (!reader) return fail(reader.error().message);
    LogReader::MatchInput kind = LogReader::MatchInput::vision;
    std::string_view payload;
    while (reader->next_match_input(kind, packet, payload)) {
      if (kind == LogReader::MatchInput::referee) take_teams(payload, teams);
      if (kind != LogReader::MatchInput::vision || !packet.has_detection()) continue;
      const double t = packet.detection().t_capture();
      if (counts.packets_read++ == 0) first_s = t;
      last_s = std::max(last_s, t);
    }
  }
  if (counts.packets_read == 0) {
    return fail(recording.string() + ": no vision detection to reshape");
  }
  counts.recording_s = last_s - first_s;
  counts.sides_given = teams.blue_on_positive_half.has_value();
  auto reader = LogReader::open(recording);
  if (!reader) return fail(reader.error().message);
  auto writer = LogWriter::create(out);
  if (!writer) return fail(writer.error().message);
  Messer messer(mess, first_s, std::max(counts.recording_s, 1e-9), teams);
  Team yellow;
  Team blue;
  RecordedBall ball;
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
    const SSL_DetectionBall* seen = nullptr;
    for (const auto& candidate : detection.balls()) {
      if (!seen || candidate.confidence() > seen->confidence()) seen = &candidate;
    }
    if (seen) ball = Point{seen->x(), seen->y()};
    const double t = detection.t_capture();
    if (t < next_pair_s) continue;
    // A pause in the recording starts the beat again.
    next_pair_s = (t - next_pair_s > 1.0 ? t : next_pair_s) + pair_interval_s;
    messer.write_pair(t, yellow, blue, ball, *writer, counts);
  }
  if (!writer->close()) return fail(out.string() + ": " + writer->error());
  return counts;
}

}  // namespace files
}  // namespace ssl_formation
