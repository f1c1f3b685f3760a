#!/usr/bin/env bash
# Writes the firmware into the robot's STM32F405/F407 through an ST-LINK probe
# on its SWD pins (docs/firmware.md: the wiring), with Debian's openocd or
# st-flash (installed when missing), then resets it and verifies.
#
#   scripts/flash_mcu.sh [--elf FILE] [--tool openocd|st-flash] [--robot FILE]
#
# --elf FILE: the image (default build-firmware/inspect-mcu.elf, built by
#   scripts/build_firmware.sh --robot FILE when missing).
# --tool: openocd (default: interface/stlink.cfg, target/stm32f4x.cfg,
#   "program ... verify reset") or st-flash (stlink-tools: the image as a
#   binary at 0x08000000, then --reset).
set -euo pipefail
self=$(readlink -f "$0")
cd "$(dirname "$self")/.."
elf="" tool=openocd robot=config/robot.yaml
while [ $# -gt 0 ]; do
  case $1 in
    --elf) elf=$2; shift 2 ;;
    --tool) tool=$2; shift 2 ;;
    --robot) robot=$2; shift 2 ;;
    -h|--help) sed -n '2,12p' "$self" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "flash_mcu: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
case $tool in
  openocd) package=openocd ;;
  st-flash) package=stlink-tools ;;
  *) echo "flash_mcu: --tool is openocd or st-flash, not '$tool'" >&2; exit 2 ;;
esac
if [ -z "$elf" ]; then
  elf=build-firmware/inspect-mcu.elf
  [ -f "$elf" ] || bash scripts/build_firmware.sh --robot "$robot"
fi
[ -f "$elf" ] || { echo "flash_mcu: no firmware image at $elf" >&2; exit 1; }
if ! command -v "$tool" >/dev/null; then
  bash scripts/setup.sh "$package"
fi
echo "flash_mcu: writing $elf with $tool"
if [ "$tool" = openocd ]; then
  openocd -f interface/stlink.cfg -f target/stm32f4x.cfg -c "program $elf verify reset exit"
else
  bin=$(mktemp --suffix=.bin)
  trap 'rm -f "$bin"' EXIT
  arm-none-eabi-objcopy -O binary "$elf" "$bin"
  st-flash --reset write "$bin" 0x08000000
fi
echo "flash_mcu: done; the MCU runs the new firmware"
