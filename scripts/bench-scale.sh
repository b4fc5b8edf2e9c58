#!/usr/bin/env bash
# A season of use (issue 44): what the table, the trainer, the predictor and the evaluation cost
# after 10 minutes, 1 hour and 5 hours of simulated match of one opponent, and for a generic
# table of three playbooks merged. Prints one table:
#   table size and stored rows (of the rows learned), trainer time and resident memory, the
#   table's load time and the predictor's resident memory (ssl-predictor --from-log over one
#   second of match, which is mostly the load), then ssl-evaluate holdout's time and peak memory
#   against the length of its test log and of its training log, and the longest gap between
#   predictions at 60 frames/s while the hour's table is replaced every 2 s
#   (scripts/bench-reload.sh, on loopback test groups).
# The logs are made by ssl-producer -o with one camera, as the figures in docs/benchmarks.md
# were (the 5-hour one gzipped, about 240 MB), in a
# temporary folder that is removed at the end. Takes about 8 minutes on 2 cores.
#   SSLF_BUILD_DIR        build folder (default: build)
#   SSLF_SCALE_SECONDS    the match lengths (default "600 3600 18000")
#   SSLF_SCALE_GENERIC_SECONDS  seconds of each of the three playbooks (default 6000: 5 h in all)
#   SSLF_SCALE_NO_RELOAD  set to 1 to skip the reload gap
# Exit status 1 if a program fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
lengths="${SSLF_SCALE_SECONDS:-600 3600 18000}"
generic_seconds="${SSLF_SCALE_GENERIC_SECONDS:-6000}"
producer="$build_dir/producer/ssl-producer"
trainer="$build_dir/trainer/ssl-trainer"
predictor="$build_dir/predictor/ssl-predictor"
evaluate="$build_dir/predictor/ssl-evaluate"
for program in "$producer" "$trainer" "$predictor" "$evaluate"; do
  [ -x "$program" ] || { echo "error: $program was not built" >&2; exit 1; }
done
command -v /usr/bin/time >/dev/null || { echo "error: needs /usr/bin/time (apt-get install time)" >&2; exit 1; }

work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-bench-scale.XXXXXX")"
trap 'rm -rf "$work"' EXIT

# measure NAME COMMAND...: runs COMMAND, keeps its stderr in $work/NAME.err and its wall time (s)
# and peak resident memory (MB) in $work/NAME.time.
measure() {
  local name=$1
  shift
  /usr/bin/time -f "%e %M" -o "$work/$name.time" "$@" >"$work/$name.out" 2>"$work/$name.err" || {
    echo "error: $name failed:" >&2
    tail -5 "$work/$name.err" >&2
    exit 1
  }
}
wall() { cut -d' ' -f1 "$work/$1.time"; }
peak_mb() { awk '{printf "%.0f", $2 / 1024}' "$work/$1.time"; }
size_mb() { awk -v b="$(stat -c %s "$1")" 'BEGIN {printf "%.2f", b / 1e6}'; }
# The rows stored and learned, from the trainer's last report.
rows_of() { sed -n 's/.*motion_rows=\([0-9]*\) (of \([0-9]*\) learned.*/\1 of \2/p' "$work/$1.err" | tail -1; }

echo "scale benchmark, $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) CPUs, load average" \
  "$(cut -d' ' -f1-3 /proc/loadavg), $(git -C "$SSLF_ROOT" rev-parse --short HEAD 2>/dev/null || echo '?')"

# One second of match: what ssl-predictor --from-log predicts while the table's load is timed.
"$producer" --cameras 1 -o "$work/second.log" --duration 1 --seed 9 2>/dev/null

echo
echo "| match | log | table | rows stored of learned | training | trainer memory | load + 1 s of prediction | predictor memory |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for seconds in $lengths; do
  log="$work/m$seconds.log"
  [ "$seconds" -gt 3600 ] && log="$log.gz"
  "$producer" --cameras 1 -o "$log" --duration "$seconds" 2>/dev/null
  measure "train$seconds" "$trainer" --from-log "$log" --table "$work/t$seconds.bin" \
    --our-team ssl-formation
  measure "load$seconds" "$predictor" --from-log "$work/second.log" --table "$work/t$seconds.bin" \
    --our-team ssl-formation -o "$work/second.csv" --overwrite
  printf '| %s s | %s MB | %s MB | %s | %s s | %s MB | %s s | %s MB |\n' "$seconds" \
    "$(size_mb "$log")" "$(size_mb "$work/t$seconds.bin")" "$(rows_of "train$seconds")" \
    "$(wall "train$seconds")" "$(peak_mb "train$seconds")" "$(wall "load$seconds")" \
    "$(peak_mb "load$seconds")"
done

# A generic table: three playbooks (the two built in and one written here), each its own
# opponent, trained apart and merged as a prior of every team would be.
cat >"$work/flanks.txt" <<'PLAYS'
playbook "flanks"
play "down the right" weight 2
  step 2.0 ball 2
    2 -0.30 -0.70
    3  0.00 -0.20
  step 2.0 ball 5
    5  0.50 -0.80
    2  0.20 -0.60
  step 1.5 ball goal
play "switch to the left"
  step 2.5 ball 4
    4  0.10  0.75
    5  0.30 -0.50
  step 2.0 ball goal
play "corner from the right"
  restart free_kick
  step 3.0 ball 5
    5  0.95 -0.95
PLAYS
generic=()
for playbook in wings centre "$work/flanks.txt"; do
  name="$(basename "$playbook" .txt)"
  "$producer" --cameras 1 -o "$work/g-$name.log.gz" --duration "$generic_seconds" \
    --playbook "$playbook" --seed 5 2>/dev/null
  measure "generic-$name" "$trainer" --from-log "$work/g-$name.log.gz" \
    --table "$work/g-$name.bin" --our-team ssl-formation
  rm -f "$work/g-$name.log.gz"
  generic+=("$work/g-$name.bin")
done
measure merge "$trainer" merge "${generic[@]}" -o "$work/generic.bin"
measure generic-load "$predictor" --from-log "$work/second.log" --table "$work/generic.bin" \
  --our-team ssl-formation -o "$work/second.csv" --overwrite
printf '| generic: 3 x %s s merged | | %s MB | %s | | %s MB (merge) | %s s | %s MB |\n' \
  "$generic_seconds" "$(size_mb "$work/generic.bin")" \
  "$(sed -n 's/.*motion_rows=\([0-9]*\).*/\1/p' "$work/merge.err" | tail -1)" \
  "$(peak_mb merge)" "$(wall generic-load)" "$(peak_mb generic-load)"

# A log of the run by its name (m600, b600, m18000: the long ones are gzipped).
log_of() { if [ -f "$work/$1.log" ]; then echo "$work/$1.log"; else echo "$work/$1.log.gz"; fi; }
if [ -f "$work/m600.log" ] && [ -f "$work/m3600.log" ]; then
  "$producer" --cameras 1 -o "$work/b600.log" --duration 600 --seed 2 2>/dev/null
  echo
  echo "ssl-evaluate holdout (the four horizons and the chains, defaults):"
  echo
  echo "| training log | test log | time | peak memory |"
  echo "| --- | --- | --- | --- |"
  pairs=("m600 b600" "m600 m3600" "m3600 b600")
  [ -f "$work/m18000.log.gz" ] && pairs+=("m18000 b600")
  for pair in "${pairs[@]}"; do
    set -- $pair
    measure "holdout-$1-$2" "$evaluate" holdout --train-log "$(log_of "$1")" \
      --test-log "$(log_of "$2")" --our-team ssl-formation
    printf '| %s | %s | %s s | %s MB |\n' "$1" "$2" "$(wall "holdout-$1-$2")" "$(peak_mb "holdout-$1-$2")"
  done
fi

if [ "${SSLF_SCALE_NO_RELOAD:-0}" != 1 ] && [ -f "$work/t3600.bin" ]; then
  echo
  echo "Reloading the hour's table every 2 s at 60 frames/s (scripts/bench-reload.sh):"
  SSLF_BUILD_DIR="$build_dir" SSLF_RELOAD_TABLE="$work/t3600.bin" \
    "$SSLF_ROOT/scripts/bench-reload.sh" | grep -i "gap\|target" || true
fi
