#!/usr/bin/env bash
# End-to-end benchmark (issue 3): builds the project (Release), then runs the real daemons on
# loopback multicast and prints one table:
#   - latency from just before the producer's send to the prediction received by a listener, at
#     60 and 1,000 packets/s, next to the floor measured in the same run: a bare multicast round
#     trip through an echo process that has the predictor's receive+send path and no work. The
#     two paths are interleaved packet by packet, half a period apart (which goes first swaps
#     every 100 packets), so both see the same machine conditions;
#   - what the predictor adds over the floor (targets: median <= 20 us, p99 <= 1.5 x floor p99);
#   - ssl-trainer and ssl-predictor under 20,000 packets/s (6+6 robots, 4 cameras): every packet
#     received and zero kernel drops, from the daemons' own final status lines.
# Everything sends and joins on 127.0.0.1 with TTL 1, on groups 224.5.23.210-213 (ports
# 10210-10213), away from the defaults and from the tests. Every run stops by itself.
#
# Environment: SSLF_BUILD_DIR (default build/), SSLF_BENCH_SLOW_SECONDS (60 packets/s run,
# default 60), SSLF_BENCH_FAST_SECONDS (1,000 packets/s run, default 10), SSLF_BENCH_LOAD_RATE
# (default 20000), SSLF_BENCH_LOAD_SECONDS (default 5), SSLF_BENCH_PREDICTOR_OPTIONS (more
# ssl-predictor options for the latency runs, e.g. "--warm-up-lead 0"). The whole script takes
# about 2.5 minutes after the build. Exit status 1 if a target is missed.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
slow_seconds="${SSLF_BENCH_SLOW_SECONDS:-60}"
fast_seconds="${SSLF_BENCH_FAST_SECONDS:-10}"
load_rate="${SSLF_BENCH_LOAD_RATE:-20000}"
load_seconds="${SSLF_BENCH_LOAD_SECONDS:-5}"

vision=224.5.23.210:10210
predictions=224.5.23.211:10211
echo_in=224.5.23.212:10212
echo_out=224.5.23.213:10213

sslf_install_packages
mkdir -p "$(dirname "$build_dir")"
sslf_build "$build_dir" -DCMAKE_BUILD_TYPE=Release
bench="$build_dir/benchmarks/e2e_bench"
predictor="$build_dir/predictor/ssl-predictor"
trainer="$build_dir/trainer/ssl-trainer"
for program in "$bench" "$predictor" "$trainer"; do
  [ -x "$program" ] || { echo "error: $program was not built" >&2; exit 1; }
done

work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-bench-e2e.XXXXXX")"
children=()
cleanup() {
  local pid
  for pid in "${children[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

# start LOG PROGRAM ARGS...: runs a daemon in the background, stderr to LOG; sets $started.
start() {
  local log="$1"
  shift
  "$@" >"$work/$(basename "$log" .log).out" 2>"$log" &
  started=$!
  children+=("$started")
}

# wait_for LOG TEXT PID: until LOG holds TEXT (5 s at most, and only while PID lives).
wait_for() {
  local i
  for i in $(seq 100); do
    grep -q "$2" "$1" 2>/dev/null && return 0
    kill -0 "$3" 2>/dev/null || { echo "error: $(basename "$1" .log) exited:" >&2; cat "$1" >&2; return 1; }
    sleep 0.05
  done
  echo "error: no '$2' from $(basename "$1" .log) within 5 s:" >&2
  cat "$1" >&2
  return 1
}

# stop PID: SIGTERM, then wait (SIGKILL after 5 s).
stop() {
  local i
  kill -TERM "$1" 2>/dev/null || true
  for i in $(seq 100); do
    kill -0 "$1" 2>/dev/null || break
    sleep 0.05
  done
  kill -KILL "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
}

# value TEXT KEY: the number after KEY= in TEXT.
value() { sed -n "s/.*[ :]$2=\([0-9.na-]*\).*/\1/p" <<<"$1" | head -1; }
# The last status line of a daemon's LOG, with the lines of what it had no room for as it stopped
# ("status, more: ..."); counter TEXT KEY: KEY's number there, 0 when left out (as every counter
# at zero is).
last_status() {
  awk '/ status: / { s = $0; next } / status, more: / { s = s " " $0 } END { print s }' "$1"
}
counter() { local v; v="$(value "$1" "$2")"; echo "${v:-0}"; }

failures=0
rows=()
# row MEASURE RATE N LOST P50 P90 P99 MAX TARGET RESULT
row() { rows+=("$(printf '%-40s %7s %6s %5s %8s %8s %8s %8s  %-22s %s' "$@")"); }
# judge OK: sets $result to PASS (OK = 1) or FAIL, and counts failures.
judge() { if [ "$1" = 1 ]; then result=PASS; else result=FAIL; failures=$((failures + 1)); fi; }

# The predictor runs its default model, the motion model: a version-3 table at its default
# step, and vision packets one 60 Hz frame apart on the data clock (frame sampling: a prediction
# at every packet, every robot with a velocity).
frame_s=0.0166667
"$bench" make-table --table "$work/table.bin" --formations 3000 >"$work/make-table.out"

latency_run() {
  local rate="$1" seconds="$2"
  local plog="$work/predictor-$rate.log" elog="$work/echo-$rate.log"
  # shellcheck disable=SC2086
  start "$plog" "$predictor" --quiet --referee-address none --table "$work/table.bin" --vision-address "$vision" \
    --prediction-address "$predictions" --interface 127.0.0.1 --ttl 1 ${SSLF_BENCH_PREDICTOR_OPTIONS:-}
  local ppid=$started
  start "$elog" "$bench" echo --echo-in "$echo_in" --echo-out "$echo_out" --interface 127.0.0.1 \
    --seconds $((seconds + 60))
  local epid=$started
  wait_for "$plog" "loaded table" "$ppid"
  wait_for "$elog" "listening on" "$epid"
  "$bench" latency --rate "$rate" --seconds "$seconds" --step "$frame_s" --vision-address "$vision" \
    --prediction-address "$predictions" --echo-in "$echo_in" --echo-out "$echo_out" \
    --interface 127.0.0.1 >"$work/latency-$rate.out"
  stop "$ppid"
  stop "$epid"

  local floor pred status
  floor="$(grep 'path=floor' "$work/latency-$rate.out")"
  pred="$(grep 'path=predictor' "$work/latency-$rate.out")"
  status="$(last_status "$plog")"
  local path line
  for path in floor predictor; do
    line="$floor"
    [ "$path" = predictor ] && line="$pred"
    local name="floor: bare multicast echo round trip"
    [ "$path" = predictor ] && name="predictor: send -> prediction received"
    local ok
    ok=$(awk -v l="$(value "$line" lost)" -v d="$(value "$line" duplicates)" \
      -v u="$(value "$line" unmatched)" 'BEGIN { print (l == 0 && d == 0 && u == 0) ? 1 : 0 }')
    judge "$ok"
    row "$name" "$rate/s" "$(value "$line" n)" "$(value "$line" lost)" "$(value "$line" p50_us)" \
      "$(value "$line" p90_us)" "$(value "$line" p99_us)" "$(value "$line" max_us)" \
      "none lost (report)" "$result"
  done
  local fp50 fp99 pp50 pp99 added ratio
  fp50="$(value "$floor" p50_us)"; fp99="$(value "$floor" p99_us)"
  pp50="$(value "$pred" p50_us)"; pp99="$(value "$pred" p99_us)"
  added=$(awk -v a="$pp50" -v b="$fp50" 'BEGIN { printf "%.1f", a - b }')
  ratio=$(awk -v a="$pp99" -v b="$fp99" 'BEGIN { printf "%.2f", a / b }')
  judge "$(awk -v a="$added" 'BEGIN { print (a <= 20) ? 1 : 0 }')"
  row "predictor adds: median - floor median" "$rate/s" "" "" "$added" "" "" "" "<= 20 us" "$result"
  judge "$(awk -v r="$ratio" 'BEGIN { print (r <= 1.5) ? 1 : 0 }')"
  row "predictor p99 / floor p99" "$rate/s" "" "" "" "" "${ratio}x" "" "<= 1.5x" "$result"
  row "  predictor status at exit" "$rate/s" "$(counter "$status" packets)" "" "" "" "" "" \
    "drops=$(counter "$status" kernel_drops) preds=$(counter "$status" predictions)" ""
}

latency_run 60 "$slow_seconds"
latency_run 1000 "$fast_seconds"

# The predictor's own work per packet, in-process: back to back, and after idling a 60/s period.
"$bench" pipeline --table "$work/table.bin" --step "$frame_s" >"$work/pipeline.out"
pipeline="$(grep '^pipeline packets' "$work/pipeline.out")"
row "predictor work in-process, back to back" "" "$(value "$pipeline" packets)" "" \
  "$(value "$pipeline" warm_p50_us)" "" "$(value "$pipeline" warm_p99_us)" "" "(for diagnosis)" ""
row "predictor work in-process, after 16.7 ms" "" "$(value "$pipeline" packets)" "" \
  "$(value "$pipeline" idle_p50_us)" "" "$(value "$pipeline" idle_p99_us)" "" "(for diagnosis)" ""

# Load: the trainer (fresh table) and the predictor on the same vision group.
tlog="$work/trainer-load.log"
plog="$work/predictor-load.log"
start "$tlog" "$trainer" --referee-address none --table "$work/trained.bin" --reset --vision-address "$vision" \
  --interface 127.0.0.1
tpid=$started
start "$plog" "$predictor" --quiet --referee-address none --table "$work/table.bin" --vision-address "$vision" \
  --prediction-address "$predictions" --interface 127.0.0.1 --ttl 1
ppid=$started
wait_for "$tlog" "listening on" "$tpid"
wait_for "$plog" "loaded table" "$ppid"
"$bench" load --rate "$load_rate" --seconds "$load_seconds" --cameras 4 --frame-dt "$frame_s" \
  --vision-address "$vision" \
  --interface 127.0.0.1 >"$work/load.out"
sleep 1  # let both finish what is queued
stop "$tpid"
stop "$ppid"
load="$(grep '^load ' "$work/load.out")"
sent="$(value "$load" sent)"
frames="$(value "$load" complete_frames)"
row "load: packets sent (6+6 robots, 4 cams)" "$(value "$load" achieved_pps)/s" "$sent" "" "" "" "" "" \
  "$load_rate/s for $load_seconds s" ""
for daemon in trainer predictor; do
  status="$(last_status "$work/$daemon-load.log")"
  got="$(counter "$status" packets)"
  drops="$(counter "$status" kernel_drops)"
  errors="$(counter "$status" parse_errors)"
  formations="$(counter "$status" formations)"
  ok=$([ "$got" = "$sent" ] && [ "$drops" = 0 ] && [ "$errors" = 0 ] && echo 1 || echo 0)
  judge "$ok"
  row "load: $daemon received, kernel drops" "" "$got" "$drops" "" "" "" "" "= sent, 0 drops" "$result"
  extra="formations=$formations/$frames"
  [ "$daemon" = predictor ] &&
    extra="$extra sent=$(( $(counter "$status" predictions) - $(counter "$status" send_errors) ))"
  judge "$([ "$formations" = "$frames" ] && echo 1 || echo 0)"
  row "  $daemon formations (= complete frames)" "" "$formations" "" "" "" "" "" "$extra" "$result"
done

echo
echo "ssl-formation end-to-end benchmark: loopback multicast (127.0.0.1, TTL 1), $(nproc) CPUs,"
echo "$(date -u '+%Y-%m-%d %H:%M UTC'), load average $(cut -d' ' -f1-3 /proc/loadavg)."
echo "Latency in microseconds from just before the producer's send to reception by the listener;"
echo "floor and predictor interleaved packet by packet in the same run, half a period apart (which"
echo "goes first swaps every 100 packets); first 10 of each left out."
printf '%-40s %7s %6s %5s %8s %8s %8s %8s  %-22s %s\n' measure rate n lost p50 p90 p99 max target result
printf '%s\n' "$(printf '%.0s-' $(seq 128))"
printf '%s\n' "${rows[@]}"
echo
echo "In-process $(sed -n 's/^pipeline stage medians after idling (us):/stage medians after idling 16.7 ms (us):/p' "$work/pipeline.out")"
[ "$failures" -eq 0 ] && echo "all targets met" || echo "$failures target(s) missed"
[ "$failures" -eq 0 ]
