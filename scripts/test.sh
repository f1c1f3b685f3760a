#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite through ctest.
# Then a second stage (docs/testing.md): the sanitizer build in build-asan/
# (clang, AddressSanitizer + UndefinedBehaviorSanitizer, libFuzzer) builds
# the fuzz harnesses and the fast unit-level test programs and runs them:
# each harness for a short while from its seed corpus (ctest label `fuzz`)
# and those programs' tests (label `sanitize`). INSPECT_SKIP_SANITIZE=1 skips
# the second stage. Arguments go to the first stage's ctest. Exits non-zero
# when either stage fails.
set -euo pipefail
cd "$(dirname "$0")/.."

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

# --- stage 1: the normal build (g++) and the whole suite ---------------------
start=$(date +%s)
bash scripts/setup.sh
bash scripts/build.sh
built=$(date +%s)
echo "test: build took $((built - start)) s"
stage1=0
rm -f "${BUILD_DIR:-build}/Testing/Temporary/LastTestsFailed.log"
(cd "${BUILD_DIR:-build}" && ctest --output-on-failure -j "$(nproc)" "$@") || stage1=$?
done1=$(date +%s)
echo "test: suite took $((done1 - built)) s"
summary1="stage 1 (g++ build, whole suite): $([ $stage1 -eq 0 ] && echo passed || echo FAILED),"
summary1+=" build $((built - start)) s, tests $((done1 - built)) s"

# --- stage 2: sanitizers and fuzzing (clang) -----------------------------------
stage2=0
if [ "${INSPECT_SKIP_SANITIZE:-0}" = 1 ]; then
  summary2="stage 2 (ASan+UBSan build, fuzz + unit tests): skipped (INSPECT_SKIP_SANITIZE=1)"
else
  ASAN_DIR=${ASAN_BUILD_DIR:-build-asan}
  if [ ! -f "$ASAN_DIR/build.ninja" ]; then
    # -O1 with line tables: quicker to build than -O2 -g, still readable stacks; asserts on.
    CC=clang CXX=clang++ cmake -S . -B "$ASAN_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only" \
      -DINSPECT_FUZZ=ON -DINSPECT_SANITIZE=address,undefined || stage2=$?
  fi
  # sanitize_tests (tests/fuzz/CMakeLists.txt): the harnesses and the selected test programs.
  [ $stage2 -ne 0 ] || cmake --build "$ASAN_DIR" -j "$(nproc)" --target sanitize_tests || stage2=$?
  built2=$(date +%s)
  echo "test: sanitizer build took $((built2 - done1)) s"
  if [ $stage2 -eq 0 ]; then
    export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
    rm -f "$ASAN_DIR/Testing/Temporary/LastTestsFailed.log"
    (cd "$ASAN_DIR" && ctest --output-on-failure -j "$(nproc)" -L '^(fuzz|sanitize)$') || stage2=$?
  fi
  done2=$(date +%s)
  echo "test: sanitizer tests took $((done2 - built2)) s"
  summary2="stage 2 (ASan+UBSan build, fuzz + unit tests): $([ $stage2 -eq 0 ] && echo passed || echo FAILED),"
  summary2+=" build $((built2 - done1)) s, tests $((done2 - built2)) s"
fi

[ $stage1 -eq 0 ] || report_failures "${BUILD_DIR:-build}" 1
[ $stage2 -eq 0 ] || [ "${INSPECT_SKIP_SANITIZE:-0}" = 1 ] || report_failures "${ASAN_DIR}" 2
echo "test: $summary1"
echo "test: $summary2"
[ $stage1 -eq 0 ] && [ $stage2 -eq 0 ]
