#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite through
# ctest, in two stages (docs/testing.md):
#   1. the normal build (g++, build/) and every test but the long ones
#      (ctest -L long runs those by hand), in parallel: ctest -j <3 x cores>,
#      the unit-level tests at low CPU priority beside the real-time stack
#      tests (tests/InspectTest.cmake says how tests are scheduled);
#   2. the sanitizer build (clang, ASan + UBSan, build-asan/): the fuzz
#      harnesses, each for a short while from its seed corpus (label `fuzz`),
#      and the unit-level test programs chosen for it (label `sanitize`).
#
#   scripts/test.sh [--quick] [ctest arguments...]
#
# --quick: the inner loop: builds and runs the unit-level tests only (label
# `unit`: no stack tests, no benchmarks, no sanitizer stage).
# INSPECT_SKIP_SANITIZE=1 skips the second stage. Other arguments go to the
# first stage's ctest (-R, -L, ...). Prints the time of every step and the
# compiler cache's hit rate of each build; exits non-zero when a stage fails.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
if [ "${1:-}" = --quick ]; then quick=1; shift; fi
jobs=$((3 * $(nproc)))

# After both stages: the tests that failed in build dir $1 and the last lines
# of each one's output, so that the end of the log (all a CI viewer may keep)
# names what failed and why. ctest's own --output-on-failure output stays where
# it happened.
report_failures() {
  local dir=$1 stage=$2 failed="$1/Testing/Temporary/LastTestsFailed.log"
  [ -s "$failed" ] || return 0
  echo "test: stage $stage failed tests: $(cut -d: -f2- "$failed" | paste -sd' ')"
  cut -d: -f2- "$failed" | head -n 5 | while IFS= read -r name; do
    echo "test: --- last lines of $name (stage $stage) ---"
    awk -v name="$name" '
      $0 ~ "^[0-9]+/[0-9]+ Test: " && substr($0, index($0, "Test: ") + 6) == name { on = 1; n = 0; next }
      on && /^<end of output>$/ { on = 0; next }
      on && /^(Running main|Note: Google Test filter|\[(==========|----------|  PASSED  )\]|$)/ { next }
      on { buf[n++ % 25] = $0 }
      END { for (i = (n > 25 ? n - 25 : 0); i < n; ++i) print "  " buf[i % 25] }
    ' "$dir/Testing/Temporary/LastTest.log" || true
  done
  return 0
}

# The "ccache hits ..." figure of the build whose output is in $1.
hits_of() { sed -n 's/^build: .*: ccache hits \(.*\)$/\1/p; s/^build: .*: no ccache.*$/no ccache/p' "$1" | tail -n 1; }

t0=$(date +%s)
bash scripts/setup.sh
t_setup=$(date +%s)
echo "test: setup took $((t_setup - t0)) s"

# --- stage 1: the normal build (g++) and the suite -----------------------------
BUILD=${BUILD_DIR:-build}
log1=$(mktemp)
stage1=0
bash scripts/build.sh 2>&1 | tee "$log1" || stage1=$?
t_built=$(date +%s)
hits1=$(hits_of "$log1")
echo "test: build took $((t_built - t_setup)) s (ccache hits ${hits1:-?})"
if [ $quick -eq 1 ]; then
  labels=(-L '^unit$')
else
  labels=(-LE '^long$')
fi
rm -f "$BUILD/Testing/Temporary/LastTestsFailed.log"
if [ $stage1 -eq 0 ]; then
  (cd "$BUILD" && ctest --output-on-failure -j "$jobs" "${labels[@]}" "$@") || stage1=$?
fi
t_suite=$(date +%s)
echo "test: suite took $((t_suite - t_built)) s"
summary1="stage 1 (g++ build, $([ $quick -eq 1 ] && echo 'unit tests' || echo 'whole suite')):"
summary1+=" $([ $stage1 -eq 0 ] && echo passed || echo FAILED), build $((t_built - t_setup)) s"
summary1+=" (ccache hits ${hits1:-?}), tests $((t_suite - t_built)) s"

# --- stage 2: sanitizers and fuzzing (clang) -------------------------------------
stage2=0
ASAN_DIR=${ASAN_BUILD_DIR:-build-asan}
if [ $quick -eq 1 ]; then
  summary2="stage 2 (ASan+UBSan build, fuzz + unit tests): skipped (--quick)"
elif [ "${INSPECT_SKIP_SANITIZE:-0}" = 1 ]; then
  summary2="stage 2 (ASan+UBSan build, fuzz + unit tests): skipped (INSPECT_SKIP_SANITIZE=1)"
else
  log2=$(mktemp)
  # sanitize_tests (tests/fuzz/CMakeLists.txt): the harnesses and the chosen test programs.
  bash scripts/build.sh --sanitize --target sanitize_tests 2>&1 | tee "$log2" || stage2=$?
  t_built2=$(date +%s)
  hits2=$(hits_of "$log2")
  echo "test: sanitizer build took $((t_built2 - t_suite)) s (ccache hits ${hits2:-?})"
  if [ $stage2 -eq 0 ]; then
    export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
    rm -f "$ASAN_DIR/Testing/Temporary/LastTestsFailed.log"
    (cd "$ASAN_DIR" && ctest --output-on-failure -j "$(nproc)" -L '^(fuzz|sanitize)$') || stage2=$?
  fi
  t_done2=$(date +%s)
  echo "test: sanitizer tests took $((t_done2 - t_built2)) s"
  summary2="stage 2 (ASan+UBSan build, fuzz + unit tests): $([ $stage2 -eq 0 ] && echo passed || echo FAILED),"
  summary2+=" build $((t_built2 - t_suite)) s (ccache hits ${hits2:-?}), tests $((t_done2 - t_built2)) s"
fi

[ $stage1 -eq 0 ] || report_failures "$BUILD" 1
[ $stage2 -eq 0 ] || [ -z "${log2:-}" ] || report_failures "$ASAN_DIR" 2
echo "test: setup $((t_setup - t0)) s, all $(($(date +%s) - t0)) s"
echo "test: $summary1"
echo "test: $summary2"
[ $stage1 -eq 0 ] && [ $stage2 -eq 0 ]
