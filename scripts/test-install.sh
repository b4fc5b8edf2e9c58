#!/usr/bin/env bash
# What a team meets after installing: `cmake --install` into a temporary prefix, the installed
# programs run from another folder, a program of its own built against the installed package
# with find_package(ssl_formation) reads the live predictions of the installed daemons (on
# loopback test groups), the installed Python client imports, and `cpack -G DEB` makes a package
# whose listing holds the programs, the library and the CMake package. Called by scripts/test.sh;
# exit status non-zero on any failure.
#   SSLF_BUILD_DIR  the configured and built folder (default: build)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="$(cd "${SSLF_BUILD_DIR:-$SSLF_ROOT/build}" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sslf-install.XXXXXX")"
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "test-install: FAIL: $*" >&2; exit 1; }

prefix="$work/prefix"
cmake --install "$build_dir" --prefix "$prefix" >"$work/install.log" || fail "cmake --install"
cd "$work"
for program in ssl-producer ssl-record ssl-trainer ssl-predictor ssl-evaluate; do
  "$prefix/bin/$program" --help >/dev/null || fail "installed $program --help"
done
echo "test-install: the installed programs run from $work"

# A team's own program against the installed package.
cmake -S "$SSLF_ROOT/docs/examples/client" -B "$work/client" -DCMAKE_PREFIX_PATH="$prefix" \
  >"$work/client-configure.log" 2>&1 || { cat "$work/client-configure.log" >&2; fail "find_package"; }
cmake --build "$work/client" >"$work/client-build.log" 2>&1 ||
  { cat "$work/client-build.log" >&2; fail "the example client does not build"; }

# The installed daemons on groups of their own (never the defaults), predicting without a
# table (constant velocity), and the example reading three predictions.
port=$((20000 + RANDOM % 20000))
vision="239.255.77.$((RANDOM % 200 + 10)):$port"
referee="239.255.78.$((RANDOM % 200 + 10)):$((port + 1))"
predictions="239.255.79.$((RANDOM % 200 + 10)):$((port + 2))"
"$prefix/bin/ssl-predictor" --vision-address "$vision" --referee-address "$referee" \
  --prediction-address "$predictions" --model constant-velocity --table "$work/none.bin" \
  --http-port 0 --quiet >"$work/predictor.log" 2>&1 &
pids+=($!)
"$prefix/bin/ssl-producer" --vision-address "$vision" --referee-address "$referee" \
  --duration 60 >"$work/producer.log" 2>&1 &
pids+=($!)
"$work/client/read-predictions" --group "$predictions" --count 3 --timeout-s 20 \
  >"$work/read.log" 2>&1 || { cat "$work/read.log" "$work/predictor.log" >&2; fail "no prediction read"; }
grep -q "constant-velocity" "$work/read.log" || { cat "$work/read.log" >&2; fail "unexpected output"; }
echo "test-install: the example built with find_package(ssl_formation) read: $(head -1 "$work/read.log" | cut -c1-100)"

# The installed Python client: the module imports, and the command finds its .proto.
PYTHONPATH="$prefix/share/ssl-formation/python" python3 -c "import ssl_prediction_client" ||
  fail "the installed Python module does not import"
"$prefix/bin/ssl-prediction-client" --group "$predictions" --count 2 --duration 20 \
  >"$work/python.log" 2>&1 || { cat "$work/python.log" >&2; fail "the installed Python client"; }

# The Debian package.
(cd "$build_dir" && cpack -G DEB -B "$work/package" >"$work/cpack.log" 2>&1) ||
  { cat "$work/cpack.log" >&2; fail "cpack -G DEB"; }
package="$(ls "$work"/package/*.deb | head -1)"
listing="$(dpkg -c "$package")"
for path in ./usr/bin/ssl-predictor ./usr/bin/ssl-trainer ./usr/bin/ssl-producer ./usr/bin/ssl-record \
  ./usr/bin/ssl-evaluate ./usr/bin/ssl-prediction-client ./usr/lib/libsslf_client.a \
  ./usr/lib/cmake/ssl_formation/ssl_formationConfig.cmake \
  ./usr/include/ssl_formation/client/predictions.hpp \
  ./usr/share/ssl-formation/proto/formation_prediction.proto; do
  grep -q " $path\$" <<<"$listing" || fail "$(basename "$package") lacks $path"
done
echo "test-install: PASS ($(basename "$package"), $(grep -c . <<<"$listing") entries)"
