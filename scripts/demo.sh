#!/usr/bin/env bash
# Runs the whole system on this machine's loopback: ssl-producer simulates a match (an
# opponent running a playbook at 60 frames a second, our team marking it, a game controller's
# referee messages), ssl-trainer learns the tables, ssl-predictor predicts (a prediction at every
# frame). Stops all three on Ctrl-C or after --duration seconds.
#
#   scripts/demo.sh [--duration SECONDS] [--simulation match|paper] [--replay LOG] [--model M]
#                   [--grid LxW] [--horizons SECONDS] [--cameras N] [--period SECONDS]
#                   [--keep-table] [--http-port PORT]
#
# The terminal shows the newest prediction once a second, short (the robots' lists left out) and
# cut to the terminal's width, and the trainer's and predictor's status lines and every warning
# or error of the three programs as they come. The full prediction stream, one line per
# prediction with every robot, goes to build/demo/predictions.txt (rewritten at each start); the
# programs' logs to build/demo/producer.log, trainer.log and predictor.log; the live field view
# is at http://127.0.0.1:8080/ (another free port if 8080 is taken; the demo prints the one in
# use; --http-port picks one). (build/ is $SSLF_BUILD_DIR when that is set.)
#
# The daemons are told only our team's name, as at a tournament: the referee gives the
# opponent's colour and side (the teams change ends at half time, every 5 minutes) and learning
# happens in every game state, each filed under its state. The demo runs the motion model, the
# daemons' default.
# --simulation paper sends the paper's simulated opponent instead, jumping from formation to
# formation every 2 s of data time (one every --period s of wall time), with the paper's model.
# --replay LOG (an official log of a real or simulated match, e.g. one you make with
# `build/producer/ssl-producer -o match.log.gz --duration 120`; without a referee in
# the log the opponent is yellow attacking +x) loops the recording instead.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

duration=0
period=0.1
grid=3x2
horizons=1
cameras=4
keep_table=0
http_port=""
# The simulated match of this seed opens with half a minute of running play (a kick-off, then
# play until a goal): what a newcomer should see first, where most seeds, like real matches,
# soon stop for a placement or a HALT.
seed=8
replay=""
model=""
simulation=match
usage() { sed -n '2,/^[^#]/s/^# \{0,1\}//p' "$0"; }  # the comment at the top
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration="$2"; shift 2 ;;
    --period) period="$2"; shift 2 ;;
    --grid) grid="$2"; shift 2 ;;
    --horizons) horizons="$2"; shift 2 ;;
    --cameras) cameras="$2"; shift 2 ;;
    --keep-table) keep_table=1; shift ;;
    --http-port) http_port="$2"; shift 2 ;;
    --replay) replay="$2"; shift 2 ;;
    --model) model="$2"; shift 2 ;;
    --simulation) simulation="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "demo.sh: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done

if [ -n "$replay" ]; then
  [ -f "$replay" ] || { echo "demo.sh: no such log: $replay" >&2; exit 2; }
  replay="$(cd "$(dirname "$replay")" && pwd)/$(basename "$replay")"
  model="${model:-motion}"
elif [ "$simulation" = paper ]; then
  model="${model:-paper}"
elif [ "$simulation" = match ]; then
  model="${model:-motion}"
else
  echo "demo.sh: --simulation must be match or paper, not '$simulation'" >&2; exit 2
fi

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
sslf_install_packages
echo "Building in $build_dir ..."
sslf_build_quietly "$build_dir" || exit 1

run_dir="$build_dir/demo"
mkdir -p "$run_dir"
table="$run_dir/formation-table.bin"
[ "$keep_table" = 1 ] || rm -f "$table"

# Everything on loopback: the programs' default interface is 127.0.0.1.
vision=224.5.23.2:10006
predictions=224.5.23.4:10040
predictions_file="$run_dir/predictions.txt"
pids=()      # the three programs
watchers=()  # what shows their output on the terminal
interrupted=0
stop=0
timer=""  # the --duration sleep
cleanup() {
  trap - EXIT INT TERM
  [ -z "$timer" ] || kill -TERM "$timer" 2>/dev/null || true
  # The prediction ticker first, then the programs; the log watcher last, so that the programs'
  # last status lines (they log one as they stop) still show.
  kill -TERM "${watchers[0]:-}" 2>/dev/null || true
  if [ "$interrupted" = 1 ]; then
    # Ctrl-C reached the programs too (the terminal signals its whole foreground group), and a
    # second signal would stop the trainer before it saves: give them a few seconds first.
    for _ in $(seq 50); do
      alive=0
      for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
      [ "$alive" = 1 ] || break
      sleep 0.1
    done
  fi
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  [ "${#watchers[@]}" -lt 2 ] || sleep 0.5
  for pid in "${watchers[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${watchers[@]}"; do wait "$pid" 2>/dev/null || true; done
  echo
  echo "Stopped. The predictions are in $predictions_file; the logs and the learned table in $run_dir"
}
trap cleanup EXIT
trap 'interrupted=1; exit 0' INT
trap 'exit 0' TERM

# The last complete line of file $1 (the predictor may be halfway through writing the next).
newest_line() {
  local chunk=""
  IFS= read -r -d '' chunk < <(tail -n 2 "$1" 2>/dev/null) || true
  if [[ $chunk == *$'\n' ]]; then
    chunk=${chunk%$'\n'}
  elif [[ $chunk == *$'\n'* ]]; then
    chunk=${chunk%$'\n'*}
  else
    return 0
  fi
  printf '%s\n' "${chunk##*$'\n'}"
}

# Once a second, the newest prediction without the robots' lists ("[...]"), cut to the
# terminal's width; nothing when no new one came. Runs in the background until killed, or until
# this script is gone.
show_predictions() {
  set +e
  ticker_sleep=""
  trap 'kill "$ticker_sleep" 2>/dev/null; exit 0' TERM
  exec 3>&1  # the terminal, for stty inside $(...)
  local shown="" line width
  while kill -0 "$$" 2>/dev/null; do
    sleep 1 &
    ticker_sleep=$!
    wait "$ticker_sleep"
    line=$(newest_line "$predictions_file")
    if [ -z "$line" ] || [ "$line" = "$shown" ]; then continue; fi
    shown=$line
    width=${COLUMNS:-}
    if [ -z "$width" ] && [ -t 3 ]; then width=$(stty size <&3 2>/dev/null); fi
    width=${width##* }  # stty says "ROWS COLUMNS"
    [[ $width =~ ^[1-9][0-9]*$ ]] || width=100
    line=$(sed 's/ \[[^]]*\]//g' <<<"$line")
    printf '%s\n' "${line:0:width}"
  done
}

rm -f "$run_dir"/*.ready
# Emptied now, so that the log watcher shows nothing of an earlier run.
: >"$predictions_file"
for log in producer trainer predictor; do : >"$run_dir/$log.log"; done
# The simulation's game controller names our team; a recorded match may carry no referee at all,
# and then the opponent is the default one (yellow attacking +x, as ssl-producer's matches start).
match_options=()
[ -n "$replay" ] || match_options=(--our-team ssl-formation)
"$build_dir/trainer/ssl-trainer" --vision-address "$vision" --table "$table" --grid "$grid" \
  --model "$model" --sampling frame --flush-interval 1 --status-interval 5 --ready-file "$run_dir/trainer.ready" \
  "${match_options[@]}" 2>"$run_dir/trainer.log" &
pids+=($!)
"$build_dir/predictor/ssl-predictor" --vision-address "$vision" --prediction-address "$predictions" \
  --table "$table" --grid "$grid" --model "$model" --horizons "$horizons" --sampling frame \
  --reload-interval 0.5 --print-predictions \
  ${http_port:+--http-port "$http_port"} --http-address 127.0.0.1 --ready-file "$run_dir/predictor.ready" \
  "${match_options[@]}" >"$predictions_file" 2>"$run_dir/predictor.log" &
pids+=($!)
# The producer starts once both daemons have joined the group (they write their ready files).
for _ in $(seq 100); do
  [ -f "$run_dir/trainer.ready" ] && [ -f "$run_dir/predictor.ready" ] && break
  for pid in "${pids[@]}"; do
    kill -0 "$pid" 2>/dev/null || { echo "a daemon failed to start; see $run_dir/*.log" >&2; tail -5 "$run_dir"/*.log >&2; exit 1; }
  done
  sleep 0.1
done
if [ -n "$replay" ]; then
  "$build_dir/producer/ssl-producer" --vision-address "$vision" --replay "$replay" --loop \
    2>"$run_dir/producer.log" &
elif [ "$simulation" = paper ]; then
  "$build_dir/producer/ssl-producer" --vision-address "$vision" --period "$period" \
    --cameras "$cameras" --our-team ssl-formation 2>"$run_dir/producer.log" &
else
  "$build_dir/producer/ssl-producer" --simulation match --vision-address "$vision" \
    --cameras "$cameras" --seed "$seed" --our-team ssl-formation 2>"$run_dir/producer.log" &
fi
pids+=($!)

field_view=$(sed -n 's/^http=//p' "$run_dir/predictor.ready")
[ -z "$field_view" ] || echo "Live field view: open $field_view"
if [ -n "$replay" ]; then
  source_line="Replaying $replay in a loop; the $model model, grid $grid."
elif [ "$simulation" = paper ]; then
  source_line="The paper's simulated opponent: one formation every $period s (2 s of data time each), grid $grid, $cameras cameras; the $model model.
The referee (224.5.23.1:10003) names our team 'ssl-formation' and the opponent; the teams change ends at half time."
else
  source_line="A simulated match (Division A, the 'wings' playbook), 60 frames a second on $cameras cameras; the $model model, grid $grid.
The referee (224.5.23.1:10003) names our team 'ssl-formation' and the opponent; the teams change ends at half time."
fi
cat <<EOT
ssl-producer -> $vision -> ssl-trainer + ssl-predictor -> predictions on $predictions
$source_line
Once a second, the newest prediction: the sample time and frame, the opponent's centroid cell now,
then for each predicted step (+ its horizon) the centroid, its probability and the confidence.
The full lines, with every robot's prediction (the paper's model: cells, '?' = a state never
seen; the motion model: position in mm, 90% radius), one per prediction, go to
$predictions_file.
The trainer's and predictor's status lines, and every warning or error, come as they are logged
(all of it in $run_dir/*.log). Ctrl-C stops everything.
EOT
sleep 0.2
for pid in "${pids[@]}"; do
  kill -0 "$pid" 2>/dev/null || { echo "a daemon failed to start; see $run_dir/*.log" >&2; tail -5 "$run_dir"/*.log >&2; exit 1; }
done

show_predictions &
watchers+=($!)
# From the logs' first lines, so what was logged before this started shows too. $! is tail's
# pid: grep ends when tail does. --pid: tail ends by itself once this script is gone, however it
# ended. Both ignore Ctrl-C, so the programs' last status lines show as they stop.
tail -q -n +1 -F --pid=$$ "$run_dir/trainer.log" "$run_dir/predictor.log" \
  "$run_dir/producer.log" 2>/dev/null \
  > >(trap '' INT; exec grep --line-buffered -E \
    'ssl-(trainer|predictor): [a-z]+: status: | (warning|error|critical): ') &
watchers+=($!)

# Until --duration has passed or, without one, until the trainer stops. From here on Ctrl-C and
# TERM only raise a flag, and the stop (cleanup) runs once this loop ends: run from a trap that
# interrupted the `wait` builtin, bash's own waits for the programs could hang.
trap 'interrupted=1; stop=1' INT
trap 'stop=1' TERM
if [ "$duration" != 0 ]; then
  sleep "$duration" &
  timer=$!
fi
while [ "$stop" = 0 ]; do
  sleep 0.2 || true
  kill -0 "${timer:-${pids[0]}}" 2>/dev/null || break
done
