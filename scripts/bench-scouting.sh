#!/usr/bin/env bash
# Scouting throughput: ssl-trainer --from-log over 8 .log.gz files on one core (--jobs 1) and on
# every core (--jobs 0), wall time, alternating three times in one run so both see the same
# machine. Prints frames per second of each and their ratio (target on 2 cores: >= 1.6).
# The logs are two recorded matches A and B, four copies of each: $SSLF_RECORDING and
# $SSLF_RECORDING_B when set (.log.gz or .log of your own, e.g. grSim's or a real match's; a .log
# is compressed), else simulated matches that ssl-producer writes (600 s, 4 cameras, seeds 1 and 2).
#   SSLF_BUILD_DIR   build folder (default: build)
#   SSLF_RECORDING, SSLF_RECORDING_B   the recordings A and B (default: simulated, as above)
# Takes about a minute after the build. Exit status 1 if the target is missed on 2+ cores.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
for recording in "${SSLF_RECORDING:-}" "${SSLF_RECORDING_B:-}"; do
  if [ -n "$recording" ] && [ ! -f "$recording" ]; then
    echo "bench-scouting: $recording not found" >&2
    exit 1
  fi
done
sslf_install_packages
sslf_build_quietly "$build_dir" || exit 1
trainer="$build_dir/trainer/ssl-trainer"
work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-scouting.XXXXXX")"
trap 'rm -rf "$work"' EXIT

sslf_recording "$build_dir" "${SSLF_RECORDING:-}" 1 "$work/A.log.gz" || exit 1
sslf_recording "$build_dir" "${SSLF_RECORDING_B:-}" 2 "$work/B.log.gz" || exit 1
logs=()
for copy in 1 2 3 4; do
  for recording in A B; do
    cp "$work/$recording.log.gz" "$work/$recording-$copy.log.gz"
    logs+=("$work/$recording-$copy.log.gz")
  done
done
cat "${logs[@]}" >/dev/null  # in the page cache before the first timed run

echo "scouting throughput, $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg)"
run() {  # run JOBS -> "wall user sys" seconds
  local jobs=$1 TIMEFORMAT='%R %U %S'
  rm -f "$work/t.bin"
  { time "$trainer" --from-log "${logs[@]}" --table "$work/t.bin" --jobs "$jobs" \
      2>"$work/err-$jobs.txt"; } 2>&1
}
one=()
all=()
one_cpu=()
all_cpu=()
for round in 1 2 3; do
  read -r wall user sys <<<"$(run 1)"
  one+=("$wall")
  one_cpu+=("$(awk -v u="$user" -v s="$sys" 'BEGIN { printf "%.2f/%.2f", u, s }')")
  read -r wall user sys <<<"$(run 0)"
  all+=("$wall")
  all_cpu+=("$(awk -v u="$user" -v s="$sys" 'BEGIN { printf "%.2f/%.2f", u, s }')")
done
# Frames in the set, from a run's own log lines.
frames=$(grep -o '[0-9]* vision packets' "$work/err-1.txt" | awk '{ s += $1 } END { print s }')
median() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
one_s=$(median "${one[@]}")
all_s=$(median "${all[@]}")
ratio=$(awk -v a="$one_s" -v b="$all_s" 'BEGIN { printf "%.2f", a / b }')
rate() { awk -v f="$frames" -v s="$1" 'BEGIN { printf "%.0f", f / s }'; }
printf '%-44s %12s %14s   %s\n' "run (median of 3, wall time)" "seconds" "frames/s" \
  "user/sys CPU seconds of the 3 runs"
printf '%-44s %12.2f %14.0f   %s\n' "8 .log.gz, one core (--jobs 1)" "$one_s" "$(rate "$one_s")" \
  "${one_cpu[*]}"
printf '%-44s %12.2f %14.0f   %s\n' "8 .log.gz, every core (--jobs 0: $(nproc))" "$all_s" \
  "$(rate "$all_s")" "${all_cpu[*]}"
printf '%-44s %12.2f   target >= 1.6 on 2 cores\n' "speed-up" "$ratio"
echo "($frames frames in the set)"
if [ "$(nproc)" -ge 2 ] && awk -v r="$ratio" 'BEGIN { exit !(r < 1.6) }'; then exit 1; fi
