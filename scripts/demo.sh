#!/usr/bin/env bash
# One command: install what is missing, build, and run the main job (the
# simulated robot driven by the operator console). See scripts/run_demo.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
exec bash scripts/run_demo.sh "$@"
