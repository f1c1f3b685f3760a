#!/usr/bin/env bash
# Long fuzzing runs of the libFuzzer harnesses (tests/fuzz, docs/testing.md).
#
#   scripts/fuzz.sh [--seconds N] [--json FILE] [--no-build] [target...]
#
# Builds the sanitizer build (build-asan/: clang, ASan + UBSan, libFuzzer;
# ASAN_BUILD_DIR overrides), then fuzzes each target (default: all of
# tests/fuzz/fuzz_*.cpp; names with or without the fuzz_ prefix) for N
# seconds (default 600), one after the other, and prints a table: runs,
# exec/s, corpus size, coverage gained (edges, start -> end) and crashes.
# A run that crashes is restarted for the time left (at most 5 crashes per
# target), so one finding does not end the run. Inputs found are kept in
# build-asan/fuzz-runs/<target>/corpus (the next run starts from them too),
# reproducers in build-asan/fuzz-runs/<target>/artifacts/; replay one with
#   build-asan/bin/fuzz_<target> <file>
# --json FILE also writes the table as JSON. Exits 1 when anything crashed.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

seconds=600
json=""
build=1
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=${2:?--seconds needs a number}; shift 2 ;;
    --json) json=${2:?--json needs a file}; shift 2 ;;
    --no-build) build=0; shift ;;
    -h|--help) sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) targets+=("${1#fuzz_}"); shift ;;
  esac
done
case "$seconds" in ''|*[!0-9]*) echo "fuzz.sh: --seconds must be a whole number" >&2; exit 2 ;; esac
if [ ${#targets[@]} -eq 0 ]; then
  for f in tests/fuzz/fuzz_*.cpp; do
    n=$(basename "$f" .cpp)
    targets+=("${n#fuzz_}")
  done
fi
for t in "${targets[@]}"; do
  [ -f "tests/fuzz/fuzz_$t.cpp" ] || { echo "fuzz.sh: no harness tests/fuzz/fuzz_$t.cpp" >&2; exit 2; }
done

ASAN_DIR=${ASAN_BUILD_DIR:-build-asan}
if [ $build -eq 1 ]; then
  bash scripts/setup.sh
  if [ ! -f "$ASAN_DIR/build.ninja" ]; then
    CC=clang CXX=clang++ cmake -S . -B "$ASAN_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only" \
      -DINSPECT_FUZZ=ON -DINSPECT_SANITIZE=address,undefined
  fi
  cmake --build "$ASAN_DIR" -j "${JOBS:-$(nproc)}" --target "${targets[@]/#/fuzz_}"
fi

export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
rows=()
any_crash=0
for t in "${targets[@]}"; do
  bin=$ASAN_DIR/bin/fuzz_$t
  work=$ASAN_DIR/fuzz-runs/$t
  mkdir -p "$work"
  opts=()
  [ -f "tests/fuzz/$t.dict" ] && opts+=("-dict=$ROOT/tests/fuzz/$t.dict")
  runs=0 crashes=0 cov0="" cov1=0 corp=0 news=0
  start=$(date +%s)
  left=$seconds
  echo "fuzz.sh: fuzz_$t for $seconds s (log: $work/fuzz.log)"
  : > "$work/fuzz.log"
  while [ "$left" -gt 0 ]; do
    log=$work/last.log
    rc=0
    bash tests/fuzz/run_fuzzer.sh "$bin" "$ROOT/tests/fuzz/corpus/$t" "$work" "$left" "${opts[@]}" > "$log" 2>&1 || rc=$?
    cat "$log" >> "$work/fuzz.log"
    r=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    n=$(sed -n 's/^stat::new_units_added: *//p' "$log" | tail -1)
    # Without final stats (a crash), count runs from the last status line.
    [ -z "$r" ] && r=$(grep -o '^#[0-9]*' "$log" | tail -1 | tr -d '#')
    runs=$((runs + ${r:-0}))
    news=$((news + ${n:-0}))
    c0=$(grep -m1 'INITED' "$log" | sed -n 's/.*cov: \([0-9]*\).*/\1/p')
    [ -z "$cov0" ] && cov0=${c0:-0}
    c1=$(grep -E '^#[0-9]+' "$log" | grep -o 'cov: [0-9]*' | tail -1 | cut -d' ' -f2)
    [ -n "$c1" ] && [ "$c1" -gt "$cov1" ] && cov1=$c1
    p=$(grep -E '^#[0-9]+' "$log" | grep -o 'corp: [0-9]*' | tail -1 | cut -d' ' -f2)
    [ -n "$p" ] && corp=$p
    left=$((seconds - ($(date +%s) - start)))
    if [ $rc -eq 0 ]; then break; fi
    crashes=$((crashes + 1))
    any_crash=1
    grep -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error|fuzz invariant broken|Test unit written' "$log" | head -5 | sed 's/^/  /'
    if [ $crashes -ge 5 ]; then echo "  fuzz_$t: 5 crashes, stopping this target"; break; fi
  done
  elapsed=$(( $(date +%s) - start ))
  [ "$elapsed" -gt 0 ] || elapsed=1
  [ "$cov1" -ge "${cov0:-0}" ] || cov1=$cov0
  artifacts=$(find "$work/artifacts" -type f 2>/dev/null | wc -l)
  rows+=("$t $runs $((runs / elapsed)) $corp ${cov0:-0} $cov1 $news $crashes $elapsed $artifacts")
done

printf '\n%-12s %11s %8s %7s %15s %9s %8s\n' target runs exec/s corpus "cov start->end" "new cov" crashes
for row in "${rows[@]}"; do
  read -r t runs eps corp c0 c1 news crashes _ _ <<< "$row"
  printf '%-12s %11s %8s %7s %15s %9s %8s\n' "$t" "$runs" "$eps" "$corp" "$c0->$c1" "+$((c1 - c0))" "$crashes"
done
echo "(cov = libFuzzer's covered edges; corpus = inputs in the in-memory corpus at the end; reproducers in $ASAN_DIR/fuzz-runs/<target>/artifacts/)"

if [ -n "$json" ]; then
  {
    echo "{\"seconds_per_target\": $seconds, \"targets\": ["
    sep=""
    for row in "${rows[@]}"; do
      read -r t runs eps corp c0 c1 news crashes elapsed artifacts <<< "$row"
      printf '%s  {"target": "%s", "seconds": %s, "runs": %s, "exec_per_s": %s, "corpus": %s, "new_units": %s, "cov_start": %s, "cov_end": %s, "new_cov": %s, "crashes": %s, "artifacts_dir": "%s", "artifacts": %s}' \
        "$sep" "$t" "$elapsed" "$runs" "$eps" "$corp" "$news" "$c0" "$c1" "$((c1 - c0))" "$crashes" \
        "$ASAN_DIR/fuzz-runs/$t/artifacts" "$artifacts"
      sep=$',\n'
    done
    printf '\n]}\n'
  } > "$json"
  echo "fuzz.sh: wrote $json"
fi
exit $any_crash
