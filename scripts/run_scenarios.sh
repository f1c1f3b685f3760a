#!/usr/bin/env bash
# Runs the scenario suite (docs/scenarios.md) in one command, from any
# directory:
#
#   bash scripts/run_scenarios.sh [extra scenario_suite options]
#
# Builds if needed (scripts/build.sh), runs build/bin/scenario_suite over
# config/scenarios/suite.yaml with the fuzzy strategy and both baselines
# (plain tracking, stop-and-wait), prints a table per scenario and the paper's
# timings, and writes into build/scenarios/:
#   results.json      every figure of the tables
#   <scenario>.png    paths with time marks, speed, distance with the zones
# Extra options are passed on (e.g. --only crossing,encountering, --seed 3;
# see build/bin/scenario_suite --help). BUILD_DIR overrides build/.
# Exit status: 0 when the strategy succeeds in every scenario.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
OUT_DIR="$BUILD_DIR/scenarios"

if [ ! -x "$BUILD_DIR/bin/scenario_suite" ] || [ ! -f "$BUILD_DIR/build.ninja" ]; then
  BUILD_DIR="$BUILD_DIR" bash scripts/build.sh
else
  cmake --build "$BUILD_DIR" --target scenario_suite >/dev/null
fi
mkdir -p "$OUT_DIR"
exec "$BUILD_DIR/bin/scenario_suite" --plots "$OUT_DIR" --json "$OUT_DIR/results.json" "$@"
