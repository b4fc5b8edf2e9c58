#!/usr/bin/env bash
# Builds the project and runs every test (ctest), then runs the unit tests and the daemon tests
# again under AddressSanitizer and UndefinedBehaviorSanitizer in a second build folder (the daemon
# tests then start the sanitizer-built programs), and checks the installed programs, package and
# client library (scripts/test-install.sh). Checks first that every C++ file follows
# .clang-format (scripts/check-format.sh). Installs missing Debian packages first. Exit
# status is non-zero if anything fails.
#   SSLF_BUILD_DIR        build folder (default: build)
#   SSLF_SKIP_SANITIZERS  set to 1 to skip the sanitizer pass
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
# The field view's browser test drives Debian's Chromium with playwright-core from npm (it
# downloads no browser). It needs node 20 or newer; where there is none, that test is skipped
# and says why.
SSLF_PACKAGES+=(chromium fonts-dejavu-core python3 python3-protobuf clang-format)
sslf_install_packages
"$SSLF_ROOT/scripts/check-format.sh"
if command -v node >/dev/null && command -v npm >/dev/null &&
  [ "$(node -p 'process.versions.node.split(".")[0]' 2>/dev/null || echo 0)" -ge 20 ]; then
  if [ ! -d "$SSLF_ROOT/tests/web/node_modules/playwright-core" ]; then
    npm ci --prefix "$SSLF_ROOT/tests/web" --no-audit --no-fund --loglevel=error ||
      echo "warning: npm ci failed: the browser test will be skipped" >&2
  fi
else
  echo "note: node 20+ not found: the browser test of the field view will be skipped" >&2
fi
mkdir -p "$(dirname "$build_dir")"
sslf_build "$build_dir" -DCMAKE_BUILD_TYPE=Release

# The unit and daemon tests again, under AddressSanitizer and UndefinedBehaviorSanitizer. The
# reliability (load, SIGKILL timing) and browser tests are left to the Release build.
sanitized=(common_tests app_tests simulation_tests producer_tests trainer_tests predictor_tests
  net_tests daemon_tests)
sanitize_dir="$build_dir-sanitize"
sanitize_build=""
if [ "${SSLF_SKIP_SANITIZERS:-0}" != 1 ]; then
  # -O1 and line tables only: the sanitized build is half the suite's time, and -O1 halves it
  # (10 instead of 20 minutes on 2 cores) while the sanitizers still see everything they check.
  # GCC's -Wmaybe-uninitialized misfires at -O1 under the sanitizers (std::optional copies).
  cmake -S "$SSLF_ROOT" -B "$sanitize_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG -Wno-maybe-uninitialized" \
    -DSSLF_SANITIZE=ON -DSSLF_BUILD_BENCHMARKS=OFF >"$sanitize_dir.configure.log" 2>&1 ||
    { cat "$sanitize_dir.configure.log" >&2; exit 1; }
  # Built while the Release tests and the install check run, at a lower priority: those wait on
  # sockets and timers much of the time, and the build takes what they leave of the cores.
  echo "== Building the sanitized tests in the background ($sanitize_dir.build.log)"
  nice -n 10 ninja -C "$sanitize_dir" -j "$(nproc)" "${sanitized[@]}" \
    >"$sanitize_dir.build.log" 2>&1 &
  sanitize_build=$!
  trap '[ -n "$sanitize_build" ] && kill "$sanitize_build" 2>/dev/null || true' EXIT
fi

ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" --timeout 600
echo "== Installed: cmake --install, find_package(ssl_formation), cpack -G DEB"
SSLF_BUILD_DIR="$build_dir" "$SSLF_ROOT/scripts/test-install.sh"

if [ -n "$sanitize_build" ]; then
  echo "== Unit and daemon tests under AddressSanitizer and UndefinedBehaviorSanitizer ($sanitize_dir)"
  if ! wait "$sanitize_build"; then
    sanitize_build=""
    tail -50 "$sanitize_dir.build.log" >&2
    echo "error: the sanitized build failed ($sanitize_dir.build.log)" >&2
    exit 1
  fi
  sanitize_build=""
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  # Each binary's tests in one shard per core, side by side (the tests already run in parallel
  # under ctest, each on its own groups and files); a shard's output is shown when it is done.
  shards="$(nproc)"
  failed=()
  for binary in "${sanitized[@]}"; do
    echo "== $binary (sanitized, $shards shards)"
    pids=()
    for ((shard = 0; shard < shards; ++shard)); do
      GTEST_TOTAL_SHARDS="$shards" GTEST_SHARD_INDEX="$shard" \
        "$sanitize_dir/tests/$binary" --gtest_brief=1 >"$sanitize_dir/$binary.$shard.log" 2>&1 &
      pids+=("$!")
    done
    for ((shard = 0; shard < shards; ++shard)); do
      if ! wait "${pids[$shard]}"; then failed+=("$binary shard $shard"); fi
      cat "$sanitize_dir/$binary.$shard.log"
    done
  done
  if [ ${#failed[@]} -gt 0 ]; then
    echo "error: sanitized tests failed: ${failed[*]}" >&2
    exit 1
  fi
fi
