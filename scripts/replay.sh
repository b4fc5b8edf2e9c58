#!/usr/bin/env bash
# Replays an official SSL log file (.log or .log.gz, e.g. from ssl-record or a RoboCup match
# archive) onto multicast with its recorded timing, as SSL-Vision sent it, so ssl-trainer and
# ssl-predictor (or any SSL software) can watch it. Builds the project first if needed.
#
#   scripts/replay.sh FILE [--speed X] [--loop] [--start S] [--end S] [--count N]
#                          [--vision-address GROUP:PORT] [--referee-address GROUP:PORT|none]
#                          [--tracker-address GROUP:PORT|none] [--interface IP] [--ttl N]
#
#   --speed X          1 = as recorded (default), 10 = ten times faster, 0 = as fast as possible
#   --loop             start over at the end, until Ctrl-C (or --count packets)
#   --start S, --end S seconds from the log's first packet to start and stop at (--end 0 = end)
#   --count N          packets to send, then stop (0 = no limit)
#   --vision-address   where the vision goes (default 224.5.23.2:10006, SSL-Vision's;
#                      224.5.23.2:10020 for software set up for grSim)
#   --referee-address  where the log's referee messages go (default 224.5.23.1:10003, the game
#                      controller's); none: not sent
#   --tracker-address  where the log's tracked vision goes (default 224.5.23.2:10010, the
#                      trackers'); none: not sent
#   --interface IP     interface to send from (default 127.0.0.1: this machine only)
#   --ttl N            multicast TTL (default 1)
#   --status-interval S seconds between status lines (default 5)
#
# Vision packets (types 4 and 2) go to --vision-address, the log's referee messages (type 3) and
# tracked vision (type 5) to --referee-address and --tracker-address, each in its place in the
# log: a team replaying a match hears its game controller too. With a real game controller on the
# network, give --referee-address none. Index and unknown messages are skipped and counted; the
# last line says how many of each kind were sent. Logs whose receive times are in microseconds
# (older recorders) or zero are timed by the frames' own t_capture. A damaged file is replayed up
# to the damage, then the script exits with status 1 and names the byte offset. All options:
# build/producer/ssl-producer --help.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

# The comment block above, without the '#'.
usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; }
case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  ""|-*) echo "replay.sh: the first argument must be the log file" >&2; usage >&2; exit 2 ;;
esac
file="$1"
shift
[ -r "$file" ] || { echo "replay.sh: cannot read $file" >&2; exit 1; }

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
sslf_install_packages
sslf_build_quietly "$build_dir" || exit 1
exec "$build_dir/producer/ssl-producer" --replay "$file" "$@"
