#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite through ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
bash scripts/setup.sh
bash scripts/build.sh
built=$(date +%s)
echo "test: build took $((built - start)) s"
cd "${BUILD_DIR:-build}"
ctest --output-on-failure -j "$(nproc)" "$@"
echo "test: suite took $(( $(date +%s) - built )) s"
