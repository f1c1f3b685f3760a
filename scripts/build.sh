#!/usr/bin/env bash
# Configures (once) and builds into build/; programs land in build/bin/.
#
#   scripts/build.sh [--sanitize] [--target T]...
#
# --sanitize: the sanitizer build instead, in build-asan/ (ASAN_BUILD_DIR
# overrides): clang, AddressSanitizer + UndefinedBehaviorSanitizer, the
# libFuzzer harnesses (docs/testing.md). --target builds only those targets
# (default: all). BUILD_DIR overrides build/, BUILD_TYPE the build type
# (RelWithDebInfo), JOBS the parallel jobs (the number of cores).
#
# With ccache installed (scripts/setup.sh installs it) every compile goes
# through it: its cache is outside the tree (ccache's default,
# ~/.cache/ccache, or CCACHE_DIR), paths are made relative to the tree, so
# two clones in different folders share hits. The last line gives the hit
# rate of this build.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
sanitize=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize) sanitize=1; shift ;;
    --target) targets+=(--target "${2:?--target needs a name}"); shift 2 ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "build.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done

cmake_args=(-G Ninja)
if [ $sanitize -eq 1 ]; then
  DIR=${ASAN_BUILD_DIR:-build-asan}
  # -O1 with line tables: quicker to build than -O2 -g, still readable stacks; asserts on.
  export CC=clang CXX=clang++
  cmake_args+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only"
               -DINSPECT_FUZZ=ON -DINSPECT_SANITIZE=address,undefined)
else
  DIR=${BUILD_DIR:-build}
  cmake_args+=(-DCMAKE_BUILD_TYPE=${BUILD_TYPE:-RelWithDebInfo})
fi

if command -v ccache >/dev/null; then
  # Every compile through ccache with the project's settings (relative paths,
  # the precompiled headers' checksums): cmake/ccache_launcher.sh says which.
  cmake_args+=("-DCMAKE_CXX_COMPILER_LAUNCHER=$ROOT/cmake/ccache_launcher.sh"
               "-DCMAKE_C_COMPILER_LAUNCHER=$ROOT/cmake/ccache_launcher.sh")
  # This build's own counters (the cache's totals are shared by every build).
  mkdir -p "$DIR"
  export CCACHE_STATSLOG=$ROOT/$DIR/ccache-stats.log
  rm -f "$CCACHE_STATSLOG"
fi

# Configured once; again when the compiler launcher differs from the one
# above (a folder configured before cmake/ccache_launcher.sh, or ccache
# installed since).
launcher=$(sed -n 's/^CMAKE_CXX_COMPILER_LAUNCHER:[A-Z]*=//p' "$DIR/CMakeCache.txt" 2>/dev/null || true)
wanted=$(command -v ccache >/dev/null && echo "$ROOT/cmake/ccache_launcher.sh" || true)
if [ ! -f "$DIR/build.ninja" ] || [ "$launcher" != "$wanted" ]; then
  cmake -S . -B "$DIR" "${cmake_args[@]}"
fi
cmake --build "$DIR" -j "${JOBS:-$(nproc)}" "${targets[@]}"

if [ -n "${CCACHE_STATSLOG:-}" ] && [ -s "$CCACHE_STATSLOG" ]; then
  # "Hits: 123 / 130 (94.62 %)" from this build's stats log.
  hits=$(ccache --show-log-stats 2>/dev/null | sed -n 's/^ *Hits: *\(.*\)$/\1/p' | head -n 1)
  echo "build: $DIR: ccache hits ${hits:-unknown}"
elif [ -n "${CCACHE_STATSLOG:-}" ]; then
  echo "build: $DIR: ccache hits 0 / 0 (nothing compiled)"
else
  echo "build: $DIR: no ccache (scripts/setup.sh installs it)"
fi
