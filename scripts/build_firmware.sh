#!/usr/bin/env bash
# Builds the MCU firmware (docs/firmware.md) with Debian's arm-none-eabi
# toolchain (scripts/setup.sh installs it):
#
#   scripts/build_firmware.sh [--robot FILE] [--out DIR] [--settings-gen PROGRAM]
#
# 1. The settings header from the robot config (default config/robot.yaml),
#    written by mcu_settings_gen (default build/bin/mcu_settings_gen, built by
#    scripts/build.sh when missing): a wrong value is named and stops here.
# 2. firmware/mcu configured with cmake/toolchain-arm-none-eabi.cmake and built
#    in DIR (default build-firmware/): the core for the Cortex-M4 (C++20,
#    -fno-exceptions -fno-rtti), the instance made of the settings, and the two
#    boards' images: DIR/inspect-mcu.elf (the STM32F405/F407 board,
#    scripts/flash_mcu.sh) and DIR/inspect-mcu-qemu.elf (scripts/mcu_qemu.sh).
# 3. Checks that nothing built needs the heap, exceptions or RTTI (no
#    malloc/free, operator new/delete, __cxa_throw, typeinfo: arm-none-eabi-nm)
#    and prints each image's flash and RAM against the budgets (64 and 16 KiB),
#    failing over them.
set -euo pipefail
self=$(readlink -f "$0")
cd "$(dirname "$self")/.."
ROOT=$PWD
robot=config/robot.yaml out=build-firmware gen=""
while [ $# -gt 0 ]; do
  case $1 in
    --robot) robot=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --settings-gen) gen=$2; shift 2 ;;
    -h|--help) sed -n '2,19p' "$self" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "build_firmware: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
if ! command -v arm-none-eabi-g++ >/dev/null; then
  echo "build_firmware: arm-none-eabi-g++ is missing: run scripts/setup.sh (gcc-arm-none-eabi)" >&2
  exit 1
fi
if [ -z "$gen" ]; then
  gen=build/bin/mcu_settings_gen
  [ -x "$gen" ] || bash scripts/build.sh --target mcu_settings_gen >/dev/null
fi
mkdir -p "$out/generated"
"$gen" --robot "$robot" --out "$out/generated/mcu_settings_gen.hpp"
cmake -S firmware/mcu -B "$out" -G Ninja -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/toolchain-arm-none-eabi.cmake" \
  -DCMAKE_BUILD_TYPE=MinSizeRel -DINSPECT_MCU_SETTINGS_DIR="$(cd "$out/generated" && pwd)" >/dev/null
cmake --build "$out"

libs=("$out/libinspect_mcu_core.a" "$out/libinspect_mcu_instance.a" "$out/libinspect_mcu_stm32f4.a")
images=("$out/inspect-mcu.elf" "$out/inspect-mcu-qemu.elf")
# What a bare-metal build without heap, exceptions and RTTI must never reference
# (the libraries' undefined symbols) nor contain (the images' symbols).
forbidden='^(malloc|calloc|realloc|free|_Znw[jm].*|_Zna[jm].*|_Zdl.*|_Zda.*|__cxa_throw|__cxa_allocate_exception|__cxa_begin_catch|__gxx_personality_v0|__cxa_guard_acquire|__dynamic_cast|_ZTI.*)$'
bad=$( (arm-none-eabi-nm -u "${libs[@]}"; arm-none-eabi-nm "${images[@]}") 2>/dev/null | awk '{print $NF}' | grep -E "$forbidden" | sort -u || true)
if [ -n "$bad" ]; then
  echo "build_firmware: the firmware needs what bare metal does not have:" >&2
  echo "$bad" | sed 's/^/  /' >&2
  exit 1
fi
echo "build_firmware: no heap, exceptions or RTTI referenced"
# Flash = text + data (its initial values); RAM = data + bss + the 4 KiB the
# linker script keeps for the stack at least (firmware/boards/stm32f4/stm32f405.ld).
for elf in "${images[@]}"; do
  arm-none-eabi-size "$elf" | tail -n 1 | awk -v name="$(basename "$elf")" '{
    flash = $1 + $2; ram = $2 + $3 + 4096
    printf "build_firmware: %s: flash %d B (%.1f KiB of 64), RAM %d B (%.1f KiB of 16, with a 4 KiB stack)\n",
           name, flash, flash / 1024, ram, ram / 1024
    if (flash > 65536 || ram > 16384) { print "build_firmware: " name " is over its budget" > "/dev/stderr"; exit 1 }
  }'
done
