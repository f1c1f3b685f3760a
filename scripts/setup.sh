#!/usr/bin/env bash
# Installs every Debian package the project needs. Idempotent: when all are
# present it only checks (well under a second) and installs nothing.
#
#   scripts/setup.sh [PACKAGE...]
#
# PACKAGEs are installed too (scripts/cross_pi.sh adds its cross tools so).
# The robot's build packages come from packaging/robot-client/build-depends.txt
# (the one list, which the arm64 sysroot of scripts/cross_pi.sh is made of too).
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t ROBOT_BUILD_PACKAGES < <(grep '^[a-z]' packaging/robot-client/build-depends.txt)

PACKAGES=(
  g++ cmake ninja-build pkg-config git ccache
  clang libclang-rt-14-dev
  "${ROBOT_BUILD_PACKAGES[@]}"
  openssl protobuf-compiler python3-protobuf
  libsqlite3-dev sqlite3
  libpq-dev postgresql
  libmosquitto-dev mosquitto python3-paho-mqtt
  libnlopt-cxx-dev
  libzstd-dev zlib1g-dev
  fuzzylite libfuzzylite-dev
  gnuplot-nox
  ffmpeg opencv-data
  gstreamer1.0-tools gstreamer1.0-plugins-base gstreamer1.0-plugins-good gstreamer1.0-plugins-ugly gstreamer1.0-libav
  libgstreamer1.0-dev
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-dev qemu-system-arm
  "$@"
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "setup: missing packages (${missing[*]}) and not root; run as root or install sudo" >&2
    exit 1
  fi
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
