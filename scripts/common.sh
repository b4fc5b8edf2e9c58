#!/usr/bin/env bash
# Shared by the scripts: installs what the build needs from Debian and configures and builds the
# project. Sourced, not run.

SSLF_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Debian 12 packages the build and the tests need.
SSLF_PACKAGES=(cmake ninja-build g++ pkg-config protobuf-compiler libprotobuf-dev
  libboost-dev libboost-program-options-dev libboost-iostreams-dev
  libspdlog-dev libfmt-dev zlib1g-dev libisal-dev libgtest-dev libgmock-dev libbenchmark-dev)

sslf_install_packages() {
  local missing=()
  local package
  for package in "${SSLF_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
      missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "Installing from Debian: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "error: need root (or sudo) to install: ${missing[*]}" >&2; return 1; }
    sudo="sudo"
  fi
  $sudo apt-get update -qq || return 1
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" || return 1
}

# sslf_build BUILD_DIR [cmake args...]
sslf_build() {
  local build_dir="$1"
  shift
  cmake -S "$SSLF_ROOT" -B "$build_dir" -G Ninja "$@" >"$build_dir.configure.log" 2>&1 || {
    cat "$build_dir.configure.log" >&2
    return 1
  }
  cmake --build "$build_dir" -j "$(nproc)"
}

# sslf_build_quietly BUILD_DIR: a Release build whose output goes to BUILD_DIR.build.log, of which
# the last 50 lines are shown if it fails. Returns the build's status.
sslf_build_quietly() {
  local build_dir="$1"
  mkdir -p "$(dirname "$build_dir")"
  sslf_build "$build_dir" -DCMAKE_BUILD_TYPE=Release >"$build_dir.build.log" 2>&1 || {
    tail -50 "$build_dir.build.log" >&2
    return 1
  }
}

# sslf_recording BUILD_DIR USER_FILE SEED DEST: makes DEST a recorded match for the benchmarks.
# USER_FILE, when given (a .log or .log.gz of your own: grSim's, a real match's), is copied as it
# is; else ssl-producer writes a simulated match there (600 s, Division A, 4 cameras, SEED).
# DEST's name says the format (.log or .log.gz): USER_FILE is converted when it differs.
sslf_recording() {
  local build_dir="$1" user_file="$2" seed="$3" dest="$4"
  if [ -n "$user_file" ]; then
    [ -f "$user_file" ] || { echo "error: recording $user_file not found" >&2; return 1; }
    case "$user_file:$dest" in
      *.gz:*.gz) cp "$user_file" "$dest" ;;
      *.gz:*) gzip -dc "$user_file" >"$dest" ;;
      *:*.gz) gzip -c "$user_file" >"$dest" ;;
      *) cp "$user_file" "$dest" ;;
    esac
    return
  fi
  "$build_dir/producer/ssl-producer" --simulation match -o "$dest" --duration 600 \
    --cameras 4 --seed "$seed" 2>"$dest.producer.log" || {
    cat "$dest.producer.log" >&2
    return 1
  }
  rm -f "$dest.producer.log"
}
