#!/usr/bin/env bash
# Builds the project and runs every test (ctest). Installs missing Debian packages first.
# Exit status is non-zero if anything fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
sslf_install_packages
mkdir -p "$(dirname "$build_dir")"
sslf_build "$build_dir" -DCMAKE_BUILD_TYPE=Release
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" --timeout 600
