#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (build folder build-fuzz, -DSSLF_FUZZ=ON) and runs each
# for SECONDS, one at a time on one worker, starting from the committed seed corpus
# (tests/fuzz/corpus), then prints per target executions, exec/s, corpus size, coverage and
# findings. Installs clang and libFuzzer (libclang-rt-14-dev) from Debian if missing.
# Exit status is non-zero if a target crashed, leaked, timed out or broke an invariant.
#
#   scripts/fuzz.sh SECONDS [TARGET...]    TARGET: sampler_fuzzer log_reader_fuzzer table_file_fuzzer
#                                                  referee_fuzzer tracker_fuzzer
#
# The seeds are copied into build-fuzz/fuzz-work/TARGET/corpus, where the corpus grows (kept
# between runs); crashing inputs land in build-fuzz/fuzz-work/TARGET/artifacts. A finding is
# fixed by copying its input to tests/fuzz/regressions/{sampler,log,table,referee,tracker}/ and
# adding a case to tests/common/files/fuzz_regressions_test.cpp.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

seconds="${1:-}"
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "usage: $0 SECONDS [TARGET...]" >&2
  exit 2
fi
shift
targets=("$@")
[ ${#targets[@]} -gt 0 ] ||
  targets=(sampler_fuzzer log_reader_fuzzer table_file_fuzzer referee_fuzzer tracker_fuzzer)
declare -A corpus_of=([sampler_fuzzer]=sampler [log_reader_fuzzer]=log [table_file_fuzzer]=table
  [referee_fuzzer]=referee [tracker_fuzzer]=tracker)
for target in "${targets[@]}"; do
  [ -n "${corpus_of[$target]:-}" ] || { echo "error: unknown fuzz target '$target'" >&2; exit 2; }
done

SSLF_PACKAGES+=(clang libclang-rt-14-dev)
sslf_install_packages

build_dir="$SSLF_ROOT/build-fuzz"
echo "== Configuring $build_dir with clang (SSLF_FUZZ=ON)"
CC=clang CXX=clang++ cmake -S "$SSLF_ROOT" -B "$build_dir" -G Ninja -DSSLF_FUZZ=ON \
  -DSSLF_BUILD_BENCHMARKS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >"$build_dir.configure.log" 2>&1 ||
  { cat "$build_dir.configure.log" >&2; exit 1; }
cmake --build "$build_dir" -j "$(nproc)" --target "${targets[@]}"

work="$build_dir/fuzz-work"
summary="$work/summary.txt"
mkdir -p "$work"
: >"$summary"
failed=0
for target in "${targets[@]}"; do
  dir="$work/$target"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  cp -n "$SSLF_ROOT/tests/fuzz/corpus/${corpus_of[$target]}/"* "$dir/corpus/" || true
  before=$(find "$dir/artifacts" -type f | wc -l)
  echo "== $target for ${seconds}s (log: $dir/fuzz-0.log)"
  status=0
  # -jobs=1 -workers=1: one fuzzing process (the machine is shared); its output goes to
  # fuzz-0.log in the current folder.
  (cd "$dir" && "$build_dir/tests/fuzz/$target" -jobs=1 -workers=1 \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$dir/artifacts/" corpus) >"$dir/run.log" 2>&1 || status=$?
  log="$dir/fuzz-0.log"
  [ -f "$log" ] || log="$dir/run.log"
  last=$(grep -E '^#[0-9]+' "$log" | tail -n 1 || true)
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  corp=$(sed -n 's/.* corp: \([^ ]*\).*/\1/p' <<<"$last")
  files=$(find "$dir/corpus" -type f | wc -l)
  after=$(find "$dir/artifacts" -type f | wc -l)
  findings=$((after - before))
  line="$target: executions=${execs:-?} exec/s=${rate:-?} cov=${cov:-?} ft=${ft:-?} corpus=${corp:-?} (${files} files) findings=$findings exit=$status"
  echo "$line" | tee -a "$summary"
  if [ "$status" -ne 0 ] || [ "$findings" -gt 0 ]; then
    failed=1
    grep -E 'ERROR: |INVARIANT BROKEN|SUMMARY: ' "$log" | head -n 5 || true
    ls -t "$dir/artifacts" | head -n 5 | sed "s|^|  $dir/artifacts/|"
  fi
done
echo "== Summary ($summary)"
cat "$summary"
exit "$failed"
