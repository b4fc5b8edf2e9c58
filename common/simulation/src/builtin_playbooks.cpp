// The playbooks ssl-producer has built in, in the same format a team writes its own in (see
// playbook.hpp). Roles by robot id, the first six making Division B's team:
//   0 goalkeeper, 1 and 2 centre backs, 3 midfielder, 4 left wing, 5 striker,
//   6 right wing, 7 right back, 8 left back, 9 second striker, 10 holding midfielder.
// In Division B a pass to robots 6 to 10 goes to the robot whose target is nearest to theirs.

#include <array>
#include <utility>

#include "ssl_formation/simulation/playbook.hpp"

namespace ssl_formation::simulation {

namespace {

constexpr std::string_view kWings =
    R"(# Attacks down either wing, corners from both sides, and a retreat.
playbook "wings"

play "kick-off" weight 1
  restart kickoff
  step 1.5 ball 5
    1 -0.60  0.20
    2 -0.60 -0.20
    3 -0.25  0.00
    4 -0.05  0.65
    5  0.00  0.04
    6 -0.05 -0.65
    7 -0.50 -0.50
    8 -0.50  0.50
    9 -0.04 -0.20
    10 -0.40  0.00
  step 2.0 ball 3
    4  0.25  0.75
    5  0.30  0.10
    6  0.25 -0.75
    9  0.25 -0.20
  step 2.5 ball 4
    3  0.05  0.20
    4  0.45  0.80
    5  0.55  0.05
    8 -0.25  0.60

play "attack down the left" weight 3
  step 2.0 ball 3
    1 -0.55  0.25
    2 -0.55 -0.25
    3 -0.10  0.15
    4  0.10  0.70
    5  0.30  0.00
    6  0.15 -0.65
    7 -0.40 -0.55
    8 -0.30  0.55
    9  0.20 -0.25
    10 -0.35  0.00
  step 2.5 ball 4
    3  0.15  0.30
    4  0.55  0.85
    5  0.60  0.10
    8 -0.05  0.70
    9  0.50 -0.20
  step 2.0 ball 5
    4  0.80  0.75
    5  0.80  0.05
    6  0.60 -0.40
    9  0.70 -0.20
    3  0.45  0.25
  step 1.5 ball goal
    5  0.88  0.00
    9  0.80 -0.15

play "attack down the right" weight 3
  step 2.0 ball 3
    1 -0.55 -0.25
    2 -0.55  0.25
    3 -0.10 -0.15
    4  0.15  0.65
    5  0.30  0.00
    6  0.10 -0.70
    7 -0.30 -0.55
    8 -0.40  0.55
    9  0.20  0.25
    10 -0.35  0.00
  step 2.5 ball 6
    3  0.15 -0.30
    6  0.55 -0.85
    5  0.60 -0.10
    7 -0.05 -0.70
    9  0.50  0.20
  step 2.0 ball 9
    6  0.80 -0.75
    5  0.80 -0.05
    4  0.60  0.40
    9  0.75  0.15
    3  0.45 -0.25
  step 1.5 ball goal
    9  0.86  0.05
    5  0.82 -0.10

play "corner from the left" weight 1
  restart free_kick
  step 3.0 ball 4
    1 -0.30  0.20
    2 -0.30 -0.20
    3  0.55  0.35
    4  0.97  0.96
    5  0.80  0.10
    6  0.70 -0.35
    7 -0.10 -0.45
    8  0.20  0.55
    9  0.78 -0.15
    10  0.35  0.00
  step 1.5 ball 5
    5  0.86  0.05
    9  0.84 -0.10
    3  0.70  0.30
  step 1.0 ball goal
    5  0.88  0.02

play "corner from the right" weight 1
  restart free_kick
  step 3.0 ball 6
    1 -0.30 -0.20
    2 -0.30  0.20
    3  0.55 -0.35
    6  0.97 -0.96
    5  0.80 -0.10
    4  0.70  0.35
    8 -0.10  0.45
    7  0.20 -0.55
    9  0.78  0.15
    10  0.35  0.00
  step 1.5 ball 9
    9  0.86 -0.05
    5  0.84  0.10
    3  0.70 -0.30
  step 1.0 ball goal
    9  0.88 -0.02

play "retreat" weight 2
  step 3.0 ball 1
    1 -0.75  0.20
    2 -0.75 -0.20
    3 -0.45  0.00
    4 -0.20  0.60
    5 -0.05  0.00
    6 -0.20 -0.60
    7 -0.65 -0.50
    8 -0.65  0.50
    9 -0.15 -0.25
    10 -0.55  0.00
  step 2.5 ball 10
    3 -0.30  0.25
    4 -0.05  0.70
    6 -0.05 -0.70
)";

constexpr std::string_view kCentre =
    R"(# Kick-off moves, through balls and free kicks in the middle, a one-two, and a retreat.
playbook "centre"

play "kick-off" weight 1
  restart kickoff
  step 1.5 ball 5
    1 -0.60  0.15
    2 -0.60 -0.15
    3 -0.20  0.10
    4 -0.10  0.50
    5  0.00  0.04
    6 -0.10 -0.50
    7 -0.50 -0.45
    8 -0.50  0.45
    9 -0.04 -0.15
    10 -0.35  0.00
  step 2.0 ball 10
    5  0.25  0.00
    9  0.30 -0.15
    4  0.20  0.45
    6  0.20 -0.45
  step 2.5 ball 5
    10 -0.10  0.00
    3  0.20  0.15
    5  0.55  0.00
    9  0.50 -0.20

play "through ball" weight 3
  step 2.0 ball 10
    1 -0.55  0.15
    2 -0.55 -0.15
    3  0.05  0.20
    4  0.20  0.50
    5  0.35  0.00
    6  0.20 -0.50
    7 -0.40 -0.45
    8 -0.40  0.45
    9  0.30 -0.20
    10 -0.15  0.00
  step 1.5 ball 3
    3  0.25  0.10
    5  0.50 -0.05
    9  0.45  0.20
  step 2.0 ball 5
    5  0.78  0.00
    9  0.70  0.15
    4  0.55  0.40
    6  0.55 -0.40
  step 1.0 ball goal
    5  0.86  0.00

play "one-two" weight 2
  step 2.0 ball 3
    3  0.00  0.00
    5  0.35  0.10
    9  0.30 -0.25
    10 -0.25  0.00
  step 1.0 ball 5
    3  0.30  0.05
    5  0.40  0.15
  step 1.5 ball 3
    3  0.65  0.00
    5  0.60  0.25
  step 1.0 ball goal
    3  0.80  0.00

play "free kick in the middle" weight 1
  restart free_kick
  step 3.0 ball 3
    1 -0.45  0.15
    2 -0.45 -0.15
    3  0.35  0.00
    4  0.55  0.40
    5  0.70  0.10
    6  0.55 -0.40
    7 -0.20 -0.45
    8 -0.20  0.45
    9  0.68 -0.12
    10  0.15  0.00
  step 1.5 ball 9
    9  0.80 -0.10
    5  0.82  0.10
  step 1.0 ball goal
    9  0.86 -0.05

play "retreat" weight 2
  step 3.0 ball 2
    1 -0.75  0.15
    2 -0.75 -0.15
    3 -0.40  0.10
    4 -0.25  0.45
    5 -0.05  0.00
    6 -0.25 -0.45
    7 -0.65 -0.45
    8 -0.65  0.45
    9 -0.10 -0.20
    10 -0.55  0.00
  step 2.0 ball 10
    3 -0.25  0.10
    10 -0.40  0.05
)";

constexpr std::array<std::pair<std::string_view, std::string_view>, 2> kBuiltin{{
    {"wings", kWings},
    {"centre", kCentre},
}};

}  // namespace

std::vector<std::string> builtin_playbook_names() {
  std::vector<std::string> names;
  for (const auto& [name, text] : kBuiltin) names.emplace_back(name);
  return names;
}

std::optional<std::string_view> builtin_playbook_text(std::string_view name) {
  for (const auto& [known, text] : kBuiltin) {
    if (known == name) return text;
  }
  return std::nullopt;
}

}  // namespace ssl_formation::simulation
