#!/usr/bin/env bash
# Runs one libFuzzer harness for a while, from its seed corpus, keeping what
# it finds inside the build tree (ctest label `fuzz`, and scripts/fuzz.sh).
#   run_fuzzer.sh BINARY SEED_DIR WORK_DIR SECONDS [libFuzzer options...]
# WORK_DIR/corpus receives the new inputs (the seed directory is only read),
# WORK_DIR/artifacts the crashing, leaking or slow inputs (crash-*, leak-*,
# timeout-*, oom-*). Exits non-zero when the harness found something.
set -uo pipefail
bin=$1 seeds=$2 work=$3 secs=$4
shift 4
mkdir -p "$work/corpus" "$work/artifacts"
"$bin" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$@" "$work/corpus" "$seeds"
rc=$?
if [ $rc -ne 0 ]; then
  echo "run_fuzzer: $(basename "$bin") failed (exit $rc); reproducer(s):" >&2
  ls -1 "$work"/artifacts/* 2>/dev/null | sed 's/^/  /' >&2
  echo "  replay one with: $bin <file>" >&2
fi
exit $rc
