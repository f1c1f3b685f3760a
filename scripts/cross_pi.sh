#!/usr/bin/env bash
# Cross-builds what runs on the robot for arm64 (a 64-bit Raspberry Pi OS /
# Debian 12 on a Pi 4 or 5) and runs its unit tests under qemu-user
# (docs/deploy.md):
#
#   scripts/cross_pi.sh [--no-tests]
#
# 1. The host gets Debian's cross compiler (g++-aarch64-linux-gnu), qemu-user
#    and mmdebstrap (scripts/setup.sh).
# 2. An arm64 sysroot in build-arm64-sysroot/ (SYSROOT overrides): the arm64
#    -dev packages of packaging/robot-client/build-depends.txt, extracted by mmdebstrap (no
#    maintainer scripts run). Not dpkg's multiarch on the host: the arm64 and
#    amd64 -dev packages of OpenCV and yaml-cpp cannot be installed side by
#    side (apt would remove the host's). Made again only when the package
#    list changes.
# 3. build-arm64/ (ARM64_BUILD_DIR overrides): cmake/toolchain-aarch64.cmake,
#    INSPECT_ROBOT_ONLY=ON (robot_client, mcu_sim, their libraries and unit
#    tests; no server), -Werror: a warning on arm64 fails the build.
# 4. ctest -L unit there: every test program runs under qemu-aarch64 with the
#    sysroot's loader and libraries (the serial codec and framing, the
#    decision core, control, fuzzy, behaviour, navigation, gas, video RTP).
# Prints the time of each step.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SYSROOT=${SYSROOT:-$ROOT/build-arm64-sysroot}
DIR=${ARM64_BUILD_DIR:-build-arm64}
tests=1
case "${1:-}" in
  --no-tests) tests=0 ;;
  -h|--help) sed -n '2,22p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  "") ;;
  *) echo "cross_pi.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
esac
t0=$(date +%s)
step() { echo "cross_pi: $1 took $(( $(date +%s) - $2 )) s"; }

bash scripts/setup.sh g++-aarch64-linux-gnu qemu-user mmdebstrap
t_setup=$(date +%s); step "host packages" "$t0"

# The robot's build packages: the one list scripts/setup.sh installs on the
# host too; the unit test robot_build_packages checks that it names every
# header and library the robot's targets use.
mapfile -t SYSROOT_PACKAGES < <(grep '^[a-z]' packaging/robot-client/build-depends.txt)
stamp="$SYSROOT/.inspect-packages"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "${SYSROOT_PACKAGES[*]}" ]; then
  rm -rf "$SYSROOT"
  include=$(IFS=,; echo "${SYSROOT_PACKAGES[*]}")
  mmdebstrap --quiet --variant=extract --architectures=arm64 --include="$include" bookworm "$SYSROOT" \
    "deb http://deb.debian.org/debian bookworm main" \
    "deb http://deb.debian.org/debian bookworm-updates main" \
    "deb http://deb.debian.org/debian-security bookworm-security main"
  echo "${SYSROOT_PACKAGES[*]}" > "$stamp"
fi
# What the packages' maintainer scripts would have set up with
# update-alternatives and mmdebstrap's extract did not run: the reference
# BLAS and LAPACK that OpenCV's core links.
for lib in blas/libblas.so.3 lapack/liblapack.so.3; do
  ln -sfn "$lib" "$SYSROOT/usr/lib/aarch64-linux-gnu/${lib#*/}"
done
t_sysroot=$(date +%s); step "arm64 sysroot ($(du -sh "$SYSROOT" | cut -f1))" "$t_setup"

cmake_args=(-G Ninja -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/toolchain-aarch64.cmake" -DINSPECT_SYSROOT="$SYSROOT"
            -DINSPECT_ROBOT_ONLY=ON -DCMAKE_BUILD_TYPE=${BUILD_TYPE:-RelWithDebInfo} -DCMAKE_CXX_FLAGS=-Werror)
if command -v ccache >/dev/null; then
  # ccache with the project's settings (cmake/ccache_launcher.sh).
  cmake_args+=("-DCMAKE_CXX_COMPILER_LAUNCHER=$ROOT/cmake/ccache_launcher.sh"
               "-DCMAKE_C_COMPILER_LAUNCHER=$ROOT/cmake/ccache_launcher.sh")
fi
if [ ! -f "$DIR/build.ninja" ]; then cmake -S . -B "$DIR" "${cmake_args[@]}"; fi
cmake --build "$DIR" -j "${JOBS:-$(nproc)}"
t_build=$(date +%s); step "arm64 build" "$t_sysroot"
file "$DIR/bin/robot_client" | sed 's/^/cross_pi: /'

if [ $tests -eq 1 ]; then
  rc=0
  # Not VideoStreamOverload: it checks that the real encoder keeps up with
  # 30 fps and drops frames rather than queue them when it cannot; emulated,
  # x264 runs about ten times slower (9 frames where it wants > 30), which
  # says nothing of a Pi (docs/deploy.md has the Pi's budget).
  (cd "$DIR" && ctest -j "$(nproc)" -L '^unit$' -E '^VideoStreamOverload(_[0-9]+)?$' --output-on-failure) || rc=$?
  step "unit tests under qemu-aarch64" "$t_build"
  echo "cross_pi: $([ $rc -eq 0 ] && echo passed || echo FAILED) in $(( $(date +%s) - t0 )) s"
  exit $rc
fi
echo "cross_pi: built in $(( $(date +%s) - t0 )) s"
