#!/usr/bin/env bash
# The compiler launcher of both builds when ccache is installed
# (scripts/build.sh passes it as CMAKE_<LANG>_COMPILER_LAUNCHER): runs the
# compile through ccache with the settings this project needs, whoever starts
# the build (scripts/build.sh, cmake --build or ninja by hand).
#
#   cmake/ccache_launcher.sh <compiler> <arguments...>
#
# - Paths relative to the tree and no working directory in the hash: the same
#   source in another clone is a hit.
# - The sloppiness ccache needs to cache a unit compiled with a precompiled
#   header (cmake/InspectPch.cmake): the PCH is hashed, not its macros' text
#   or times.
# - A precompiled header is not the same byte for byte from one clone to the
#   next (clang's holds the absolute paths of the tree it was made in), so
#   every unit compiled with it missed in another clone (a warm sanitizer
#   build hit 16 of 97). When this launcher makes a PCH (clang's -emit-pch,
#   g++'s -x c++-header) it writes <pch>.sum beside it: a checksum of what
#   the PCH is made of (the compiler, its arguments with the tree's path
#   taken out, and the text of every header it read, from its depfile).
#   ccache hashes that file instead of the PCH (pch_external_checksum). The
#   old .sum is removed before the compile, so a PCH that fails or is made
#   without this launcher never carries a stale one.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export CCACHE_BASEDIR=$root CCACHE_NOHASHDIR=1 CCACHE_PCH_EXTSUM=1
export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime

out="" dep="" pch=0
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  case "${args[i]}" in
    -emit-pch|c++-header) pch=1 ;;
    -o) out=${args[i + 1]:-} ;;
    -MF) dep=${args[i + 1]:-} ;;
  esac
done
if [ $pch -eq 0 ] || [ -z "$out" ] || [ -z "$dep" ]; then
  exec ccache "$@"
fi

rm -f "$out.sum"
ccache "$@" || exit $?
# The depfile: "<target>: <header> <header> \" lines; paths without spaces.
if ! headers=$(sed -e 's/\\$//' -e '1s/^[^:]*://' "$dep" | tr -s ' \t' '\n\n' | sed '/^$/d'); then
  echo "ccache_launcher.sh: cannot read the PCH's depfile $dep; no $out.sum (ccache hashes the PCH)" >&2
  exit 0
fi
{
  "$1" --version
  printf '%s\n' "$@" | sed "s|$root|@|g"
  while IFS= read -r h; do
    printf '%s\n' "${h#"$root"}"
    cat -- "$h"
  done <<<"$headers"
} | sha256sum | cut -d' ' -f1 >"$out.sum.tmp" && mv "$out.sum.tmp" "$out.sum"
exit 0
