#!/usr/bin/env bash
# Reproduces the paper's circle-tracking experiment (section 5.2, Figs 18 and
# 20, Table 3) in one command, from any directory:
#
#   bash scripts/reproduce_circle.sh [extra track_experiment options]
#
# Builds if needed (scripts/build.sh), runs build/bin/track_experiment with
# the defaults (radius 3.5 m, start (0, 0, 0), 0.5 m/s, dt 0.01 s, PID vs
# fuzzy-PID, config/robot.yaml + config/control.yaml, seed 1), prints the
# results table and writes into build/experiments/circle/:
#   results.json          the same figures as the table
#   fig18_trajectory.png  reference vs actual trajectory (Fig 18)
#   fig20_errors.png      position and angle error vs time (Fig 20a, 20b)
#   wheels_gains.png      wheel speeds and the fuzzy-scheduled gains
# Extra options are passed on (e.g. --seeds 10, --no-noise, --band-m 0.005;
# see build/bin/track_experiment --help). BUILD_DIR overrides build/.
# docs/controllers.md explains the set-up, the definitions and the results.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
OUT_DIR="$BUILD_DIR/experiments/circle"

if [ ! -x "$BUILD_DIR/bin/track_experiment" ] || [ ! -f "$BUILD_DIR/build.ninja" ]; then
  BUILD_DIR="$BUILD_DIR" bash scripts/build.sh
else
  # Up to date check: a no-op when nothing changed.
  cmake --build "$BUILD_DIR" --target track_experiment >/dev/null
fi

mkdir -p "$OUT_DIR"
"$BUILD_DIR/bin/track_experiment" --plots "$OUT_DIR" --json "$OUT_DIR/results.json" "$@"

echo
echo "outputs in $(pwd)/$OUT_DIR:"
for f in "$OUT_DIR"/results.json "$OUT_DIR"/*.png; do
  [ -e "$f" ] && echo "  $(pwd)/$f"
done
