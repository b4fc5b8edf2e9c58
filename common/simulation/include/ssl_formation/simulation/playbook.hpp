#pragma once
// A playbook: the set plays a simulated opponent runs (issue 15's match simulation), read from a
// text file a team can write for the opponent it expects. Each play is a sequence of steps; each
// step gives some robots a target to drive to and says who has the ball, and is held for a
// while. Robot 0 keeps goal and is never listed: the simulation keeps it on its line.
//
// The format, line by line ('#' starts a comment; blank lines are skipped):
//
//   playbook "Wing play"                      the playbook's name (once, first)
//   play "attack down the left" weight 2      a play, and how often it is picked against the
//                                             others (weight 1 if not given)
//     restart kickoff                         optional: the play starts after this restart only
//                                             (kickoff, free_kick, any; default any)
//     step 2.5 ball 3                         a step held 2.5 s, robot 3 has the ball (a pass
//                                             from whoever had it); "ball goal" is a shot
//       1 -0.5 -0.3                           robot 1's target: x, y
//       3  0.1  0.6
//
// Coordinates are fractions of the field, so one playbook serves both divisions: x from -1 (the
// opponent's own goal line) to 1 (the goal line it attacks), y from -1 (its right touch line as
// it attacks) to 1 (its left). Robots a step does not list keep their targets. Robots beyond a
// division's team size (ids 6 to 10 in Division B) are left out, and a pass to one of them goes
// to the robot whose target is nearest to where it would have been.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/result.hpp"

namespace ssl_formation::simulation {

inline constexpr std::uint32_t playbook_max_robot_id = 10;  // Division A's 11 robots

struct PlayTarget {
  std::uint32_t robot_id = 0;
  Point position;  // fractions of the half field: x, y in [-1, 1]
};

struct PlayStep {
  double hold_s = 0.0;
  // Who has the ball at this step; none: nobody new (the ball stays where it is).
  std::optional<std::uint32_t> ball_robot;
  bool shot = false;  // "ball goal": the holder shoots at the goal it attacks
  std::vector<PlayTarget> targets;
  int line = 0;  // where the step starts in the file, for messages
};

enum class PlayRestart { any, kickoff, free_kick };

struct Play {
  std::string name;
  double weight = 1.0;
  PlayRestart restart = PlayRestart::any;
  std::vector<PlayStep> steps;
  int line = 0;
};

struct Playbook {
  std::string name;
  std::vector<Play> plays;
};

// Reads a playbook from its text. The error names `source` (the file), the line and what is
// wrong there: "plays.txt:12: robot 11: ids go from 1 to 10 (0 keeps goal)".
Result<Playbook> parse_playbook(std::string_view text, std::string_view source);
Result<Playbook> load_playbook(const std::string& path);

// The playbooks ssl-producer knows by name: "wings" (attacks down either wing, corners, a
// retreat) and "centre" (kick-off moves, through balls and free kicks in the middle).
std::vector<std::string> builtin_playbook_names();
// The text of a built-in playbook; none for another name.
std::optional<std::string_view> builtin_playbook_text(std::string_view name);
// A built-in playbook by name, else the playbook file of that path.
Result<Playbook> builtin_or_file_playbook(const std::string& name_or_path);

}  // namespace ssl_formation::simulation
