#!/usr/bin/env bash
# Offline training's cost in instructions per frame, counted by valgrind's callgrind inside the
# training benchmarks alone (reading, sampling, the paper's counts, the motion model's history and
# learning). Time on these shared machines moves by a third from one minute to the next; the
# instruction count of a build is the same in every run, so two builds compare exactly. It is a
# proxy: it does not see cache misses or branch mispredictions, so a speed claim still needs
# log_benchmarks' times (scripts/bench.sh).
#
# Logs: recording A and the same recording reshaped as real Division A logs come (camera id 0,
# half the field a packet; see benchmarks/log_benchmarks.cpp). Recording A is $SSLF_RECORDING
# when set, else a simulated match that ssl-producer writes (600 s, 4 cameras, seed 1).
#   SSLF_BUILD_DIR       build folder (default: build)
#   SSLF_RECORDING       a recorded match of your own (.log or .log.gz, e.g. grSim's or a real
#                        match's) to count on instead of the simulated one
#   SSLF_BENCH_BASELINE  another build folder (for example of an older commit, built in a git
#                        worktree) to count too, and the change against it
# Takes about a minute per build after the build.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
baseline_dir="${SSLF_BENCH_BASELINE:-}"
if [ -n "${SSLF_RECORDING:-}" ] && [ ! -f "$SSLF_RECORDING" ]; then
  echo "error: SSLF_RECORDING=$SSLF_RECORDING not found" >&2
  exit 1
fi
if [ -n "$baseline_dir" ] && [ ! -x "$baseline_dir/benchmarks/log_benchmarks" ]; then
  echo "error: $baseline_dir/benchmarks/log_benchmarks not found (build the baseline first)" >&2
  exit 1
fi
SSLF_PACKAGES+=(valgrind)
sslf_install_packages
sslf_build_quietly "$build_dir" || exit 1
work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-instructions.XXXXXX")"
trap 'rm -rf "$work"' EXIT
sslf_recording "$build_dir" "${SSLF_RECORDING:-}" 1 "$work/recording-A.log" || exit 1

# count BUILD_DIR BENCHMARK_REGEX: "INSTRUCTIONS ITERATIONS FRAMES_PER_PASS", callgrind's count
# inside the benchmark function over the iterations it ran (FRAMES_PER_PASS is empty for builds
# older than the benchmark's counter).
count() {
  local dir="$1" filter="$2"
  SSLF_BENCH_RECORDING="$work/recording-A.log" valgrind --tool=callgrind \
    --callgrind-out-file="$work/callgrind.out" --toggle-collect='*BM_OfflineTrainingRecorded(*' \
    "$dir/benchmarks/log_benchmarks" --benchmark_filter="$filter" --benchmark_min_time=0 \
    --benchmark_format=csv >"$work/run.csv" 2>"$work/valgrind.log"
  local instructions
  instructions=$(grep -o 'refs: *[0-9,]*' "$work/valgrind.log" | tr -d ', ' | cut -d: -f2)
  # csv: name,iterations,...,label,...; the counter, when there, is the last column (the label
  # holds a comma, so columns are counted from the end).
  awk -F, -v total="$instructions" '
    /^name,/ { counted = ($NF == "\"frames_per_pass\""); next }
    /^"BM_/ { print total, $2, (counted ? $NF : "") }' "$work/run.csv"
}
per_frame() { awk -v n="$1" -v iterations="$2" -v frames="$3" 'BEGIN { printf "%.0f", n / (iterations * frames) }'; }

echo "offline training, instructions per frame (callgrind), $(date -u '+%Y-%m-%d %H:%M UTC')"
echo
printf '%-58s %12s %12s %8s\n' "log (frames)" "this build" "baseline" "change"
for case in "recording A, as recorded|BM_OfflineTrainingRecorded\$" \
  "recording A as real logs come, half fields|BM_OfflineTrainingRecordedAsOneCameraHalves"; do
  name="${case%%|*}"
  filter="${case#*|}"
  read -r instructions iterations frames <<<"$(count "$build_dir" "$filter")"
  now=$(per_frame "$instructions" "$iterations" "$frames")
  before="-"
  change="-"
  if [ -n "$baseline_dir" ]; then
    # The same recording reshaped the same way: an older build without the counter read as
    # many frames.
    read -r instructions iterations baseline_frames <<<"$(count "$baseline_dir" "$filter")"
    before=$(per_frame "$instructions" "$iterations" "${baseline_frames:-$frames}")
    change=$(awk -v a="$now" -v b="$before" 'BEGIN { printf "%+.1f%%", 100 * (a - b) / b }')
  fi
  printf '%-58s %12s %12s %8s\n' "$name ($frames)" "$now" "$before" "$change"
done
