#pragma once
// A clean recording rewritten the way recorded Division A matches come (docs/simulation.md), to
// measure training and prediction on what users will feed rather than on grSim's tidy frames:
// every packet with camera id 0 holding the robots of one half of the field (as last seen in the
// recording), 90 packets a second, no geometry packets; and, each on request, the mess of real
// logs. The benchmarks time training on it, `ssl-evaluate as-real-log` writes it for held-out
// evaluations.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "ssl_formation/base/result.hpp"

namespace ssl_formation {
inline namespace files {

// Each part of real logs' mess, placed at fixed fractions of the recording so that a held-out
// split (the first two thirds to train) has some of each on both sides.
struct RealLogMess {
  // About one every 4 s for 3-8 packets: half of them a new id (11-15) somewhere on the field,
  // half a robot's own id elsewhere and more confident than the robot (it wins the frame).
  bool ghosts = false;
  // Robot 4 of each team plays on as id 12 from a third of the recording, robot 7 as id 14 from
  // 63% (a substitution: one id leaves, another appears where it was).
  bool substitutions = false;
  // Three stoppages of 25 s (from 10%, 40% and 83%) in which every robot stands where it was,
  // with a game controller's referee messages (type 3): HALT through each stoppage, running play
  // elsewhere (NORMAL_START, FORCE_START after each stoppage), the teams named as the
  // recording's referee names them ("Yellow" and "Blue" without one). See write_as_real_log.
  bool stoppages = false;
  // Two stretches missing (15 s from 25%, 20 s from 70%): recordings cut into pieces.
  bool cuts = false;
  // From half of the recording on, every position mirrored: the teams changed ends.
  bool change_of_ends = false;
  // Gaussian noise on every reported position (each axis' standard deviation), mm.
  double noise_mm = 0.0;
  // The noise of the real logs: in their halts a robot's 1 s displacement has a median of 0 mm
  // and a 90th percentile of 1 mm (docs/simulation.md). The displacement between two sightings
  // with noise s per axis has its 90th percentile at 3.03 s and its median at 1.67 s: s = 0.3 mm
  // gives 0.9 and 0.5 mm. (3 mm, a guess before those figures, made halts ten times as restless
  // as the logs' and every velocity noisier than a real tracker's.)
  static constexpr double real_noise_mm = 0.3;
  std::uint64_t seed = 11;
  friend bool operator==(const RealLogMess&, const RealLogMess&) = default;
};

// Every part of the mess by name, for messages: what parse_real_log_mess takes in a list.
inline constexpr std::string_view real_log_mess_names =
    "ghosts, substitutions, stoppages, cuts, ends, noise";
// "none", "all" (every part; noise RealLogMess::real_noise_mm) or a comma-separated list (no
// spaces) of real_log_mess_names, where noise=MM sets another noise (0 to 1000 mm); nothing for
// anything else.
std::optional<RealLogMess> parse_real_log_mess(std::string_view text);

struct RealLogCounts {
  std::uint64_t packets_read = 0;     // vision packets with a detection in the recording
  std::uint64_t packets_written = 0;  // half-field packets written
  std::uint64_t ghost_detections = 0;
  std::uint64_t referee_messages = 0;  // written (with stoppages)
  // Whether they say which half blue defends: only if the recording's referee did. Without it
  // nothing in the log tells the side after a change of ends but where the goalkeepers stand.
  bool sides_given = false;
  double recording_s = 0.0;  // the recording's first to last capture time
};

// Writes `recording`'s vision reshaped (and messed up) to `out` (gzip if its name ends in .gz).
// The recording's own referee messages are not copied; with stoppages the log gets a referee of
// its own, as a game controller sends it: a message about every 0.1 s and one at each new
// command (its counter counting up), stage NORMAL_FIRST_HALF (with the change of ends,
// NORMAL_HALF_TIME through the break and NORMAL_SECOND_HALF after it), the recording's team
// names and goalkeepers and, where the recording's referee gives it, which half blue defends
// (turned at the change of ends). Nothing is sent inside a cut.
// Errors: the recording cannot be read or holds no detection, `out` is the recording itself or
// cannot be written.
Result<RealLogCounts> write_as_real_log(const std::filesystem::path& recording,
                                        const std::filesystem::path& out, const RealLogMess& mess);

}  // namespace files
}  // namespace ssl_formation
