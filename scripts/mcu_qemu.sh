#!/usr/bin/env bash
# Runs the MCU firmware in QEMU (docs/firmware.md): the QEMU board's image on
# QEMU's netduinoplus2 (an STM32F405), its USART1 (the Pi's serial line) on a
# pseudo-terminal linked at PATH, for robot_client --serial PATH.
#
#   scripts/mcu_qemu.sh --serial-link PATH [--elf FILE] [--mcu-sim PROGRAM] [--realtime-priority N]
#                       [--cpu N] [--hil-link PATH2 | --world FILE [mcu_sim options...]]
#
# --world FILE [options]: the simulated world attached: `mcu_sim --hil` on
#   USART2, the hardware-in-the-loop link, with the world file and the mcu_sim
#   options after it (--truth, --duration, --camera ...; mcu_sim --help).
# --hil-link PATH2: USART2 on a pty linked at PATH2 instead, for an mcu_sim
#   started by hand (`mcu_sim --hil PATH2 --world ...`).
# Neither: the world is held still (the wheels at rest, nothing in range, gas
#   at 4 mA, the battery full).
# --elf FILE: the image (default <tree>/build-firmware/inspect-mcu-qemu.elf,
#   built by scripts/build_firmware.sh when missing).
# --mcu-sim PROGRAM: default <tree>/build/bin/mcu_sim.
# --realtime-priority N: QEMU (the MCU, a chip of its own) runs SCHED_FIFO at N
#   in [1, 99] when this user may (root, CAP_SYS_NICE; else a warning), and so
#   does the attached mcu_sim (its peripherals: an option after --world
#   overrides); 0 = normal (default).
# --cpu N: QEMU on CPU N alone, mcu_sim on the others (taskset): the chip's
#   clock is then not held up by the world's steps (docs/firmware.md).
# Runs until SIGINT/SIGTERM (or mcu_sim's --duration); QEMU's own messages go
# to stderr. Stops what it started and removes its links.
set -euo pipefail
self=$(readlink -f "$0")
# Paths are the caller's (relative to where it was called from), defaults the tree's.
root=$(cd "$(dirname "$self")/.." && pwd)
link="" hil_link="" elf="" world="" mcu_sim=$root/build/bin/mcu_sim priority=0 cpu=
sim_args=()
while [ $# -gt 0 ]; do
  case $1 in
    --serial-link) link=$2; shift 2 ;;
    --hil-link) hil_link=$2; shift 2 ;;
    --elf) elf=$2; shift 2 ;;
    --mcu-sim) mcu_sim=$2; shift 2 ;;
    --realtime-priority) priority=$2; shift 2 ;;
    --cpu) cpu=$2; shift 2 ;;
    --world) world=$2; shift 2; sim_args=("$@"); break ;;
    -h|--help) sed -n '2,25p' "$self" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "mcu_qemu: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
if [ -z "$link" ]; then
  echo "mcu_qemu: --serial-link PATH is required (try --help)" >&2
  exit 2
fi
if ! [[ "$priority" =~ ^[0-9]+$ ]] || [ "$priority" -gt 99 ]; then
  echo "mcu_qemu: --realtime-priority: '$priority' is not a whole number in [0, 99]" >&2
  exit 2
fi
pin_qemu=() pin_sim=()
if [ -n "$cpu" ]; then
  ncpu=$(nproc --all)
  if ! [[ "$cpu" =~ ^[0-9]+$ ]] || [ "$cpu" -ge "$ncpu" ] || [ "$ncpu" -lt 2 ]; then
    echo "mcu_qemu: --cpu: '$cpu' is not one of CPUs 0-$((ncpu - 1)) with another left for mcu_sim" >&2
    exit 2
  fi
  others=$(seq 0 $((ncpu - 1)) | grep -vx "$cpu" | paste -sd,)
  pin_qemu=(taskset -c "$cpu") pin_sim=(taskset -c "$others")
fi
rt=()
if [ "$priority" -gt 0 ]; then
  if chrt -f "$priority" true 2>/dev/null; then
    rt=(chrt -f "$priority")
  else
    echo "mcu_qemu: warning: QEMU runs at normal priority: SCHED_FIFO $priority not permitted" >&2
  fi
fi
if [ -n "$world" ] && [ -n "$hil_link" ]; then
  echo "mcu_qemu: --world starts mcu_sim on the HIL link itself; --hil-link is for one started by hand" >&2
  exit 2
fi
if [ -n "$world" ]; then
  [ -x "$mcu_sim" ] || { echo "mcu_qemu: no mcu_sim at $mcu_sim (scripts/build.sh, or --mcu-sim)" >&2; exit 1; }
  hil_link=$(mktemp -u "${TMPDIR:-/tmp}/mcu-qemu-hil-XXXXXX")
fi
if ! command -v qemu-system-arm >/dev/null; then
  echo "mcu_qemu: qemu-system-arm is missing: run scripts/setup.sh (qemu-system-arm)" >&2
  exit 1
fi
if [ -z "$elf" ]; then
  elf=$root/build-firmware/inspect-mcu-qemu.elf
  [ -f "$elf" ] || (cd "$root" && bash scripts/build_firmware.sh >&2)
fi
if [ ! -f "$elf" ]; then
  echo "mcu_qemu: no firmware image at $elf" >&2
  exit 1
fi

log=$(mktemp)
second=null
[ -n "$hil_link" ] && second=pty
# QEMU and mcu_sim end with this script even when it is killed outright (SIGTERM on its death).
setpriv --pdeathsig TERM "${pin_qemu[@]}" "${rt[@]}" qemu-system-arm -M netduinoplus2 -display none -monitor none -serial pty -serial "$second" \
  -kernel "$elf" >"$log" 2>&1 &
qemu=$!
sim=""
cleanup() {
  [ -n "$sim" ] && { kill "$sim" 2>/dev/null || true; wait "$sim" 2>/dev/null || true; }
  kill "$qemu" 2>/dev/null || true
  wait "$qemu" 2>/dev/null || true
  rm -f "$log"
  [ -L "$link" ] && rm -f "$link"
  [ -n "$hil_link" ] && [ -L "$hil_link" ] && rm -f "$hil_link"
  return 0
}
trap 'cleanup; exit 0' INT TERM
trap cleanup EXIT
# QEMU names its ptys on stderr: "char device redirected to /dev/pts/N (label serial0)".
pty_of() { sed -n "s|.*redirected to \(/dev/pts/[0-9]*\) (label $1).*|\1|p" "$log" | head -n 1; }
for _ in $(seq 1 100); do
  [ -n "$(pty_of serial0)" ] && { [ -z "$hil_link" ] || [ -n "$(pty_of serial1)" ]; } && break
  kill -0 "$qemu" 2>/dev/null || break
  sleep 0.05
done
usart1=$(pty_of serial0)
if [ -z "$usart1" ]; then
  echo "mcu_qemu: QEMU did not start:" >&2
  cat "$log" >&2
  exit 1
fi
if [ -n "$hil_link" ]; then
  ln -sfn "$(pty_of serial1)" "$hil_link"
  echo "mcu_qemu: USART2 (HIL link) $(pty_of serial1) at $hil_link"
fi
tail -n +1 -f "$log" >&2 &
tailer=$!
if [ -n "$world" ]; then
  # The world first: the Pi's line is linked once mcu_sim speaks to the board,
  # so that robot_client never reads the held-still world's frames (gas at 4
  # mA: an oxygen channel would read 0 %vol and raise its alarm).
  sim_out=$(mktemp)
  # At the MCU's priority too, unless the options after --world say otherwise (the last one counts).
  sim_prio=()
  [ "$priority" -gt 0 ] && sim_prio=(--realtime-priority "$priority")
  setpriv --pdeathsig TERM "${pin_sim[@]}" "$mcu_sim" --hil "$hil_link" --world "$world" "${sim_prio[@]}" "${sim_args[@]}" \
    > >(tee "$sim_out") &
  sim=$!
  # "hil board answered": the board took mcu_sim's first readings (QEMU reads
  # the HIL pty only once its 1 s poll saw mcu_sim open it: until then the
  # board reads the held-still world, gas at 4 mA, oxygen 0 %vol).
  for _ in $(seq 1 200); do
    grep -q '^mcu_sim: hil board answered' "$sim_out" && break
    kill -0 "$sim" 2>/dev/null || break
    sleep 0.05
  done
  sleep 0.05  # a frame period: the first frame the Pi reads has them
  rm -f "$sim_out"
fi
ln -sfn "$usart1" "$link"
echo "mcu_qemu: firmware $elf, USART1 (serial line) $usart1 at $link"
if [ -n "$world" ]; then
  # Until either ends: mcu_sim's --duration, or QEMU stopped.
  while kill -0 "$sim" 2>/dev/null && kill -0 "$qemu" 2>/dev/null; do sleep 0.2; done
  rc=0
  wait "$sim" || rc=$?
  sim=""
  kill "$tailer" 2>/dev/null || true
  exit $rc
fi
wait "$qemu" || true
kill "$tailer" 2>/dev/null || true
