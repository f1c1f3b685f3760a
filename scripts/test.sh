#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite through
# ctest, in two stages (docs/testing.md):
#   1. the normal build (g++, build/) and every test but the long ones
#      (ctest -L long runs those by hand), in two phases: the unit-level
#      tests (label `unit`, ctest -j <2 x cores>), then the real-time stack
#      tests (`stack`, at most four at once) and the benchmarks' smoke runs
#      (`bench`, alone); tests/InspectTest.cmake says how tests are scheduled;
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
jobs=$((2 * $(nproc)))
# At most four stack tests at once, whatever -j (tests/InspectTest.cmake).
resources=(--resource-spec-file "$PWD/tests/ctest_resources.json")
# The tests' folders (logs, truth files, recordings) in memory when the
# machine has /dev/shm: the recorder's fdatasync of MCAP chunks on a shared
# disk stalls the other tests' writes for tens of ms, which a real-time stack
# test can take for a stalled sensor line. Removed at the end.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then
  export TMPDIR=$(mktemp -d /dev/shm/inspect-tests-XXXXXX)
  trap 'rm -rf "$TMPDIR"' EXIT
fi

# After both stages: the tests that failed in the ctest run whose logs are
# $1 (LastTestsFailed.log) and $2 (LastTest.log), and the last lines of each
# one's output, so that the end of the log (all a CI viewer may keep) names
# what failed and why. ctest's own --output-on-failure output stays where it
# happened.
report_failures() {
  local failed=$1 log=$2 stage=$3
  [ -s "$failed" ] || return 0
  echo "test: $stage failed tests: $(cut -d: -f2- "$failed" | paste -sd' ')"
  cut -d: -f2- "$failed" | head -n 5 | while IFS= read -r name; do
    echo "test: --- last lines of $name ($stage) ---"
    awk -v name="$name" '
      $0 ~ "^[0-9]+/[0-9]+ Test: " && substr($0, index($0, "Test: ") + 6) == name { on = 1; n = 0; next }
      on && /^<end of output>$/ { on = 0; next }
      on && /^(Running main|Note: Google Test filter|\[(==========|----------|  PASSED  )\]|$)/ { next }
      on && /^(Command: |Directory: |"[^"]*" start time: |Output:$|-+$)/ { next }
      on { buf[n++ % 25] = $0 }
      END { for (i = (n > 25 ? n - 25 : 0); i < n; ++i) print "  " buf[i % 25] }
    ' "$log" || true
  done
  return 0
}

# Runs ctest in build dir $1 with the arguments after it, keeping its two
# logs as $1/Testing/<phase>-failed.log and <phase>.log ($PHASE); its status.
run_ctest() {
  local dir=$1
  shift
  rm -f "$dir/Testing/Temporary/LastTestsFailed.log" "$dir/Testing/$PHASE-failed.log" "$dir/Testing/$PHASE.log"
  local rc=0
  (cd "$dir" && ctest --output-on-failure "$@") || rc=$?
  cp "$dir/Testing/Temporary/LastTestsFailed.log" "$dir/Testing/$PHASE-failed.log" 2>/dev/null || true
  cp "$dir/Testing/Temporary/LastTest.log" "$dir/Testing/$PHASE.log" 2>/dev/null || true
  return $rc
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
# Two phases. The unit-level tests are CPU-bound; the stack tests run the
# real programs in real time, and a machine whose two cores are both busy
# stalls them for 100-250 ms whatever their priority (measured here, a
# virtual machine: docs/testing.md), which a robot takes for a dead sensor
# line. So they do not share the machine: first the unit phase, all cores
# busy; then the stack phase, at most four stack tests at once (the resource
# spec) beside nothing CPU-bound, the benchmarks and latency measurements alone.
t_unit=$t_built
if [ $stage1 -eq 0 ]; then
  PHASE=unit run_ctest "$BUILD" -j "$jobs" -L '^unit$' "$@" || stage1=$?
  t_unit=$(date +%s)
  echo "test: unit phase took $((t_unit - t_built)) s"
  if [ $quick -eq 0 ]; then
    PHASE=stack run_ctest "$BUILD" -j "$jobs" "${resources[@]}" -L '^(stack|bench)$' "$@" || stage1=$?
    echo "test: stack phase took $(($(date +%s) - t_unit)) s"
  fi
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
    # Two more jobs than cores: the server and video programs wait on sockets
    # (measured on 2 cores, one built tree: -j3 197 s, -j4 172 s).
    PHASE=sanitize run_ctest "$ASAN_DIR" -j "$(($(nproc) + 2))" -L '^(fuzz|sanitize)$' || stage2=$?
  fi
  t_done2=$(date +%s)
  echo "test: sanitizer tests took $((t_done2 - t_built2)) s"
  summary2="stage 2 (ASan+UBSan build, fuzz + unit tests): $([ $stage2 -eq 0 ] && echo passed || echo FAILED),"
  summary2+=" build $((t_built2 - t_suite)) s (ccache hits ${hits2:-?}), tests $((t_done2 - t_built2)) s"
fi

# The one command that reruns just the failed tests of build dir $1, whose
# phases' failed lists are the files after it: they become ctest's own
# LastTestsFailed.log (each phase's run overwrote it), so that
# `ctest --rerun-failed` takes exactly those.
rerun_hint() {
  local dir=$1
  shift
  local merged=$dir/Testing/Temporary/LastTestsFailed.log
  mkdir -p "$(dirname "$merged")"
  cat "$@" 2>/dev/null | sort -t: -k1,1n -u > "$merged" || true
  [ -s "$merged" ] || return 0
  echo "test: rerun just the failed ones: (cd $dir && ctest --rerun-failed --output-on-failure)"
}
rerun1="" rerun2=""
if [ $stage1 -ne 0 ]; then
  for phase in unit stack; do
    report_failures "$BUILD/Testing/$phase-failed.log" "$BUILD/Testing/$phase.log" "stage 1 ($phase phase)"
  done
  rerun1=$(rerun_hint "$BUILD" "$BUILD/Testing/unit-failed.log" "$BUILD/Testing/stack-failed.log")
fi
if [ $stage2 -ne 0 ] && [ -n "${log2:-}" ]; then
  report_failures "$ASAN_DIR/Testing/sanitize-failed.log" "$ASAN_DIR/Testing/sanitize.log" "stage 2"
  rerun2=$(rerun_hint "$ASAN_DIR" "$ASAN_DIR/Testing/sanitize-failed.log")
fi
echo "test: setup $((t_setup - t0)) s, all $(($(date +%s) - t0)) s"
echo "test: $summary1"
echo "test: $summary2"
for hint in "$rerun1" "$rerun2"; do [ -z "$hint" ] || echo "$hint"; done
[ $stage1 -eq 0 ] && [ $stage2 -eq 0 ]
