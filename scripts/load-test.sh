#!/usr/bin/env bash
# Load test (issue 6): ssl-trainer and ssl-predictor under 50,000 packets/s for 10 s (4 cameras,
# 6+6 robots, every frame completing a formation), sent by benchmarks/e2e_bench's load mode.
# Prints what each daemon received, the kernel drops it counted (SO_RXQ_OVFL), the receive
# buffer the kernel granted (SO_RCVBUF, --receive-buffer) and its resident memory (VmRSS) at the
# start and at the end. Exit status 1 if a daemon died, grew by 10 MiB or more, or lost a
# datagram it did not count (received + drops != sent).
# Everything sends and joins on 127.0.0.1 with TTL 1, on 224.5.23.220:10220 (away from the
# defaults, the tests and bench-e2e.sh); every run stops by itself.
#
# Environment: SSLF_BUILD_DIR (default build/), SSLF_LOAD_RATE (50000), SSLF_LOAD_SECONDS (10),
# SSLF_LOAD_RECEIVE_BUFFER (bytes to request, default 4194304).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
rate="${SSLF_LOAD_RATE:-50000}"
seconds="${SSLF_LOAD_SECONDS:-10}"
receive_buffer="${SSLF_LOAD_RECEIVE_BUFFER:-4194304}"
vision=224.5.23.220:10220
predictions=224.5.23.221:10221

if [ ! -x "$build_dir/benchmarks/e2e_bench" ]; then
  sslf_install_packages
  mkdir -p "$build_dir"
  sslf_build "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSSLF_BUILD_BENCHMARKS=ON
fi
bench="$build_dir/benchmarks/e2e_bench"
trainer="$build_dir/trainer/ssl-trainer"
predictor="$build_dir/predictor/ssl-predictor"
for program in "$bench" "$trainer" "$predictor"; do
  [ -x "$program" ] || { echo "error: $program was not built" >&2; exit 1; }
done

work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-load.XXXXXX")"
pids=()
cleanup() {
  local pid
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

rss_kib() { awk '/^VmRSS:/ {print $2}' "/proc/$1/status" 2>/dev/null || echo 0; }
wait_for() {  # LOG TEXT PID
  local i
  for i in $(seq 100); do
    grep -q "$2" "$1" 2>/dev/null && return 0
    kill -0 "$3" 2>/dev/null || { echo "error: $(basename "$1") ended:" >&2; cat "$1" >&2; return 1; }
    sleep 0.05
  done
  echo "error: no '$2' in $1 within 5 s" >&2
  cat "$1" >&2
  return 1
}
# field LOG KEY: KEY's value on the last status line of LOG; 0 when the line leaves it out, as
# status lines do with every counter at zero.
field() {
  local value
  value=$(grep 'status:' "$1" | tail -1 | grep -o "[ :]$2=[0-9]*" | head -1 | cut -d= -f2)
  echo "${value:-0}"
}

"$bench" make-table --table "$work/fixed.bin" --formations 2000 >/dev/null
"$trainer" --referee-address none --vision-address "$vision" --table "$work/trainer.bin" --flush-interval 1 \
  --status-interval 1 --receive-buffer "$receive_buffer" 2>"$work/trainer.log" &
pids+=($!)
trainer_pid=$!
"$predictor" --referee-address none --vision-address "$vision" --prediction-address "$predictions" --table "$work/fixed.bin" \
  --quiet --status-interval 1 --receive-buffer "$receive_buffer" >/dev/null 2>"$work/predictor.log" &
pids+=($!)
predictor_pid=$!
wait_for "$work/trainer.log" "listening on" "$trainer_pid"
wait_for "$work/predictor.log" "loaded table" "$predictor_pid"
sleep 0.2
trainer_rss_start=$(rss_kib "$trainer_pid")
predictor_rss_start=$(rss_kib "$predictor_pid")

"$bench" load --vision-address "$vision" --rate "$rate" --seconds "$seconds" | tee "$work/load.txt"
sleep 0.3
# A few slow packets after the load: the kernel reports drops with the next datagram delivered.
"$bench" load --vision-address "$vision" --rate 200 --seconds 0.2 >"$work/trailing.txt"
sleep 0.3
sent=$(( $(grep -o 'sent=[0-9]*' "$work/load.txt" | cut -d= -f2) + $(grep -o 'sent=[0-9]*' "$work/trailing.txt" | cut -d= -f2) ))

failed=0
alive() { kill -0 "$1" 2>/dev/null; }
alive "$trainer_pid" || { echo "FAIL: ssl-trainer died" >&2; failed=1; }
alive "$predictor_pid" || { echo "FAIL: ssl-predictor died" >&2; failed=1; }
trainer_rss_end=$(rss_kib "$trainer_pid")
predictor_rss_end=$(rss_kib "$predictor_pid")
kill -TERM "$trainer_pid" "$predictor_pid" 2>/dev/null || true
wait "$trainer_pid" "$predictor_pid" 2>/dev/null || true
pids=()

echo
printf '%-14s %10s %10s %12s %12s %14s %14s\n' daemon sent received kernel_drops so_rcvbuf rss_start_kib rss_end_kib
for daemon in trainer predictor; do
  log="$work/$daemon.log"
  received=$(field "$log" packets)
  drops=$(field "$log" kernel_drops)
  granted=$(grep -o 'receive buffer [0-9]* bytes' "$log" | head -1 | grep -o '[0-9]*')
  start_var="${daemon}_rss_start"
  end_var="${daemon}_rss_end"
  printf '%-14s %10s %10s %12s %12s %14s %14s\n' "ssl-$daemon" "$sent" "$received" "$drops" "$granted" \
    "${!start_var}" "${!end_var}"
  if [ "$((received + drops))" -ne "$sent" ]; then
    echo "FAIL: ssl-$daemon: received + kernel drops = $((received + drops)), sent $sent" >&2
    failed=1
  fi
  if [ "${!end_var:-0}" -ge "$(( ${!start_var:-0} + 10240 ))" ]; then
    echo "FAIL: ssl-$daemon grew from ${!start_var} to ${!end_var} KiB" >&2
    failed=1
  fi
done
exit "$failed"
