#!/usr/bin/env bash
# Runs every benchmark of the project and prints one table of figures:
#   prediction latency and sampler cost            (Google Benchmark: core_benchmarks)
#   offline training against the bare-parse floor  (Google Benchmark: log_benchmarks)
#   table memory and prediction time per grid      (ssl-evaluate grid-sweep)
#   end-to-end latency against the loopback floor  (scripts/bench-e2e.sh: real daemons)
# Everything stays on 127.0.0.1. Takes about 3 minutes after the build.
#   SSLF_BUILD_DIR   build folder (default: build)
#   SSLF_RECORDING   a recorded match (.log or .log.gz, e.g. grSim's or a real match's) for the
#                    recorded-match rows; default: a simulated match ssl-producer writes (600 s,
#                    4 cameras, seed 1)
#   SSLF_BENCH_SKIP_E2E=1  skip the end-to-end part
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
sslf_install_packages
sslf_build_quietly "$build_dir" || exit 1
work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-bench.XXXXXX")"
trap 'rm -rf "$work"' EXIT

echo "ssl-formation benchmarks, $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo

# Google Benchmark medians over 5 repetitions, CPU time (less disturbed by other processes).
"$build_dir/benchmarks/core_benchmarks" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_format=csv 2>/dev/null >"$work/core.csv"
# Offline training is also measured on a recorded match, uncompressed into $work: $SSLF_RECORDING,
# or a simulated match of 4 cameras written there by ssl-producer.
sslf_recording "$build_dir" "${SSLF_RECORDING:-}" 1 "$work/recording-A.log" || exit 1
export SSLF_BENCH_RECORDING="$work/recording-A.log"
# The recorded-match benchmarks report a counter the others lack, and Google Benchmark's CSV
# output aborts on a counter its first row did not have: they run on their own, after the rest.
recorded='^BM_OfflineTrainingRecorded'
"$build_dir/benchmarks/log_benchmarks" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
  --benchmark_filter="-$recorded" --benchmark_format=csv 2>/dev/null >"$work/log.csv"
if [ -n "${SSLF_BENCH_RECORDING:-}" ]; then
  "$build_dir/benchmarks/log_benchmarks" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
    --benchmark_filter="$recorded" --benchmark_format=csv 2>/dev/null | tail -n +2 >>"$work/log.csv"
fi

# csv columns: name,iterations,real_time,cpu_time,time_unit,bytes_per_second,items_per_second,label,...
median() { grep "^\"$1_median\"" "$2" | head -1; }
cpu_ns() { median "$1" "$2" | awk -F, '{ t = $4; u = $5; if (u == "us") t *= 1000; if (u == "ms") t *= 1e6; printf "%.0f", t }'; }
items() { median "$1" "$2" | awk -F, '{ printf "%.0f", $7 }'; }

printf '%-58s %14s %s\n' "measure (median)" "figure" "target"
printf '%s\n' "--------------------------------------------------------------------------------------------"
row() { printf '%-58s %14s %s\n' "$1" "$2" "${3:-}"; }
row "2-step prediction, 6 robots, 3x2 (dense)" "$(cpu_ns 'BM_Predict/grid12x9:0/robots:6/horizon:2' "$work/core.csv") ns" "<= 1000 ns"
row "2-step prediction, 11 robots, 3x2 (dense)" "$(cpu_ns 'BM_Predict/grid12x9:0/robots:11/horizon:2' "$work/core.csv") ns"
row "2-step prediction, 6 robots, 12x9 (sparse)" "$(cpu_ns 'BM_Predict/grid12x9:1/robots:6/horizon:2' "$work/core.csv") ns"
row "2-step prediction, 11 robots, 12x9 (sparse)" "$(cpu_ns 'BM_Predict/grid12x9:1/robots:11/horizon:2' "$work/core.csv") ns" "<= 20000 ns"
row "1-step prediction, 11 robots, 12x9 (sparse)" "$(cpu_ns 'BM_Predict/grid12x9:1/robots:11/horizon:1' "$work/core.csv") ns"
row "table increment, 3x2 dense" "$(cpu_ns 'BM_TableIncrement/grid12x9:0' "$work/core.csv") ns"
row "table increment, 12x9 sparse" "$(cpu_ns 'BM_TableIncrement/grid12x9:1' "$work/core.csv") ns"
per_robot() { awk -v i="$(items "$1" "$work/core.csv")" 'BEGIN { printf "%.1f", 1e9 / i }'; }
row "sampling + state encoding per robot, 1 camera" "$(per_robot 'BM_SamplerPerPacket/cameras:1') ns" "<= 1000 ns"
row "sampling + state encoding per robot, 4 cameras" "$(per_robot 'BM_SamplerPerPacket/cameras:4') ns" "<= 1000 ns"
row "rolling prediction per frame, 11 robots, 3x2, 3 steps, paper" "$(cpu_ns 'BM_RollingPrediction/grid12x9:0/horizon:3/motion:0' "$work/core.csv") ns"
row "rolling prediction per frame, 11 robots, 12x9, 3 steps, paper" "$(cpu_ns 'BM_RollingPrediction/grid12x9:1/horizon:3/motion:0' "$work/core.csv") ns"
row "rolling prediction per frame, 11 robots, 12x9, 3 steps, motion" "$(cpu_ns 'BM_RollingPrediction/grid12x9:1/horizon:3/motion:1' "$work/core.csv") ns" "<= 5000 ns"
# A .log.gz is inflated by ISA-L where the build has it, as the programs do (isal:1), else by
# zlib (isal:0); zlib's floor is shown next to ISA-L's.
gz_isal=0
[ -n "$(median "BM_ReadAndParse/gzip:1/isal:1" "$work/log.csv")" ] && gz_isal=1
for variant in 0 1; do
  name=$([ $variant = 0 ] && echo ".log" || echo ".log.gz")
  isal=$([ $variant = 1 ] && echo $gz_isal || echo 0)
  if [ $variant = 1 ] && [ $isal = 1 ]; then
    row "read + decode only, $name inflated by zlib, frames/s" "$(items "BM_ReadAndParse/gzip:1/isal:0" "$work/log.csv")"
    name="$name (ISA-L)"
  fi
  floor=$(items "BM_ReadAndParse/gzip:$variant/isal:$isal" "$work/log.csv")
  row "read + decode only (the floor), $name, frames/s" "$floor"
  row "read + protobuf parse only, $name, frames/s" "$(items "BM_ReadAndParseProtobuf/gzip:$variant/isal:$isal" "$work/log.csv")"
  for sampling in 0 1 2; do
    kind=$(case $sampling in 0) echo "step" ;; 1) echo "frame" ;; *) echo "frame + motion" ;; esac)
    training=$(items "BM_OfflineTraining/gzip:$variant/frame:$sampling" "$work/log.csv")
    row "offline training, $name, $kind sampling, 6+6-robot frames/s" "$training" "$([ $variant = 0 ] && [ $sampling = 2 ] && echo '>= 1000000')"
    row "offline training / floor, $name, $kind sampling" "$(awk -v a="$training" -v b="$floor" 'BEGIN { printf "%.2f", a / b }')" "$([ $sampling != 2 ] && echo '>= 0.80')"
  done
done

if [ -n "${SSLF_BENCH_RECORDING:-}" ]; then
  row "offline training, recording A, frame + motion, frames/s" \
    "$(items BM_OfflineTrainingRecorded "$work/log.csv")" ">= 1000000"
  row "offline training, recording A as real logs come (camera 0, half fields), frames/s" \
    "$(items BM_OfflineTrainingRecordedAsOneCameraHalves "$work/log.csv")" ">= 1000000"
fi

# The match simulation written as fast as it goes: 600 simulated seconds of Division A (22
# robots, 4 cameras, 60 Hz), simulated seconds per wall second, median of three seeds.
match_rates=()
for seed in 1 2 3; do
  started=$(date +%s.%N)
  "$build_dir/producer/ssl-producer" --simulation match -o "$work/match.log" \
    --duration 600 --cameras 4 --seed "$seed" 2>/dev/null
  match_rates+=("$(awk -v s="$started" -v e="$(date +%s.%N)" 'BEGIN { printf "%.0f", 600 / (e - s) }')")
done
row "match simulation written, simulated s per wall s" \
  "$(printf '%s\n' "${match_rates[@]}" | sort -n | sed -n 2p)" ">= 50"

# The paper table's memory per grid, on the paper's simulated opponent.
"$build_dir/predictor/ssl-evaluate" grid-sweep --model paper -o "$work" --overwrite 2>/dev/null >/dev/null
while IFS=, read -r grid states transitions memory prediction _; do
  [ "$grid" = grid ] && continue
  row "table memory, $grid ($states states, $transitions transitions)" "$(awk -v m="$memory" 'BEGIN { printf "%.1f KiB", m / 1024 }')"
  row "  2-step prediction over the held-out formations, $grid" "$(awk -v p="$prediction" 'BEGIN { printf "%.2f us", p }')"
done <"$work/grid-sweep.csv"

if [ "${SSLF_BENCH_SKIP_E2E:-0}" != 1 ]; then
  echo
  SSLF_BUILD_DIR="$build_dir" "$SSLF_ROOT/scripts/bench-e2e.sh" | sed -n '/^ssl-formation end-to-end/,$p'
fi
