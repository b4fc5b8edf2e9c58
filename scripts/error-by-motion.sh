#!/usr/bin/env bash
# Where the error is: every method's mean error at one horizon, by game state and by how each
# robot moved over the horizon, from the robots `ssl-evaluate holdout --write-samples FILE`
# scored one by one (each horizon's own model; the file's first grid unless GRID is given).
#
#   scripts/error-by-motion.sh SAMPLES.csv [HORIZON_S [GRID]]      (default: 1 s)
#
# A robot is "standing" below 250 mm/s (its displacement over the last 0.1 s, from the samples'
# own positions), and then either stays (within 100 mm of where it stood a horizon later) or
# sets off. A moving one stops (within 100 mm), goes straight on (its path over the horizon,
# seen at fifths of it, at most 5% longer than the straight line, and that line within 30
# degrees of its heading) or turns. Robots without the positions to tell are left out, and
# counted. The last column is each group's share of the model's summed error: what a better
# model of that group could win at most.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

if [[ $# -lt 1 || $# -gt 3 || "$1" == "-h" || "$1" == "--help" ]]; then
  sed -n '2,14p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  [[ $# -ge 1 && ( "$1" == "-h" || "$1" == "--help" ) ]] && exit 0
  exit 2
fi
samples="$1"
horizon="${2:-1}"
grid="${3:-}"
[[ -r "$samples" ]] || { echo "error-by-motion: cannot read $samples" >&2; exit 2; }
[[ "$horizon" =~ ^[0-9]+([.][0-9]+)?$ ]] || {
  echo "error-by-motion: the horizon is in seconds (such as 0.5 or 1), not '$horizon'" >&2
  exit 2
}
SSLF_PACKAGES+=(python3)
sslf_install_packages

/usr/bin/python3 - "$samples" "$horizon" "$grid" <<'PY'
import bisect, collections, csv, math, signal, sys

signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # quietly cut short by `| head`

path, horizon, grid = sys.argv[1], float(sys.argv[2]), sys.argv[3]
STANDING_MM_S, MOVED_MM, STRAIGHT, HEADING_COS = 250.0, 100.0, 1.05, math.cos(math.radians(30))

with open(path, newline="") as f:
    reader = csv.reader(f)
    header = next(reader)
    col = {name: i for i, name in enumerate(header)}
    methods = [name[:-5] for name in header if name.endswith("_x_mm") and name != "truth_x_mm"]
    positions = collections.defaultdict(dict)  # (stream, robot) -> time (ms) -> (x, y)
    scored = []
    grids = []
    for row in reader:
        if row[col["grid"]] not in grids:
            grids.append(row[col["grid"]])
        if row[col["chain"]] != "0" or row[col["grid"]] != (grid or grids[0]):
            continue
        robot = (row[col["stream"]], int(row[col["robot_id"]]))
        t_ms = round(float(row[col["time_s"]]) * 1000)
        positions[robot][t_ms] = (float(row[col["x_mm"]]), float(row[col["y_mm"]]))
        if row[col["horizon_steps"]] == "1" and abs(float(row[col["horizon_s"]]) - horizon) < 1e-6:
            truth = (float(row[col["truth_x_mm"]]), float(row[col["truth_y_mm"]]))
            errors = [math.dist((float(row[col[m + "_x_mm"]]), float(row[col[m + "_y_mm"]])), truth)
                      for m in methods]
            scored.append((robot, t_ms, row[col["game_state"]], truth, errors))
grid = grid or (grids[0] if grids else "")
if not scored:
    sys.exit(f"error-by-motion: no robot scored at {horizon:g} s on grid {grid} in {path} "
             f"(its grids: {', '.join(grids) or 'none'}; ssl-evaluate holdout --horizons lists "
             "the horizons scored)")

series = {robot: (sorted(by_time), by_time) for robot, by_time in positions.items()}
def sighting(robot, t_ms, tolerance_ms=25):
    """The robot's (time, position) nearest t_ms, within the tolerance; None if there is none."""
    times, by_time = series[robot]
    i = bisect.bisect_left(times, t_ms - tolerance_ms)
    best = None
    while i < len(times) and times[i] <= t_ms + tolerance_ms:
        if best is None or abs(times[i] - t_ms) < abs(best - t_ms):
            best = times[i]
        i += 1
    return (best, by_time[best]) if best is not None else None

def motion(robot, t_ms, truth):
    """How the robot moved over the horizon, or None where its positions cannot tell."""
    now, before = sighting(robot, t_ms, 0), sighting(robot, t_ms - 100)
    if now is None or before is None or now[0] == before[0]:
        return None
    (t_now, at_now), (t_before, at_before) = now, before
    speed = math.dist(at_now, at_before) / ((t_now - t_before) / 1000)
    moved = math.dist(at_now, truth)
    if speed < STANDING_MM_S:
        return "standing, stays" if moved < MOVED_MM else "standing, sets off"
    if moved < MOVED_MM:
        return "moving, stops"
    path, last = 0.0, at_now
    for j in range(1, 6):
        seen = (0, truth) if j == 5 else sighting(robot, t_ms + round(horizon * 1000 * j / 5))
        if seen is None:
            return None
        path += math.dist(last, seen[1])
        last = seen[1]
    heading = (at_now[0] - at_before[0], at_now[1] - at_before[1])
    chord = (truth[0] - at_now[0], truth[1] - at_now[1])
    cos = (heading[0] * chord[0] + heading[1] * chord[1]) / (math.hypot(*heading) * moved)
    return "moving, straight on" if path <= STRAIGHT * moved and cos >= HEADING_COS else "moving, turns"

sums = collections.defaultdict(lambda: [0, [0.0] * len(methods)])
unknown = 0
for robot, t_ms, state, truth, errors in scored:
    kind = motion(robot, t_ms, truth)
    if kind is None:
        unknown += 1
        continue
    for key in ((state, "*"), (state, kind), ("all", "*"), ("all", kind)):
        entry = sums[key]
        entry[0] += 1
        entry[1] = [a + b for a, b in zip(entry[1], errors)]

if ("all", "*") not in sums:
    sys.exit(f"error-by-motion: no robot at {horizon:g} s has the positions to tell how it moved "
             "(its position 0.1 s before and at fifths of the horizon: every frame sampled?)")
total_n, total_errors = sums[("all", "*")]
short = {"model": "model", "persistence": "P", "constant-velocity": "CV",
         "damped-constant-velocity": "dCV", "constant-acceleration": "CA",
         "damped-constant-acceleration": "dCA"}
print(f"Mean error (mm) at {horizon:g} s, grid {grid}, by game state and by how the robot moved; "
      f"{total_n} robots" + (f" ({unknown} left out: their positions cannot tell)" if unknown else ""))
print(f"{'game state':24} {'how it moved':20} {'robots':>8} {'share':>6} "
      + " ".join(f"{short.get(m, m):>7}" for m in methods) + f" {'of model error':>15}")
states = ["all"] + sorted({state for state, _ in sums} - {"all"})
kinds = ["*", "standing, stays", "standing, sets off", "moving, straight on", "moving, turns",
         "moving, stops"]
for state in states:
    for kind in kinds:
        if (state, kind) not in sums:
            continue
        n, errors = sums[(state, kind)]
        print(f"{state if kind == '*' else '':24} {'every robot' if kind == '*' else kind:20} "
              f"{n:8d} {100 * n / total_n:5.1f}% "
              + " ".join(f"{e / n:7.1f}" for e in errors)
              + f" {100 * errors[0] / total_errors[0]:14.1f}%")
PY
