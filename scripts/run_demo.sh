#!/usr/bin/env bash
# Runs the main job on an already built tree: mcu_sim (gas_lab world: two
# leaks, a technician in the aisle) on a pty, robot_client on that pty,
# pc_server on loopback running scripts/demo/gas_inspection.console (a
# recorded gas inspection round, alarms, report), then prints what happened.
#
#   scripts/run_demo.sh [--interactive|--batch] [--port N] [--foxglove-port N] [--tuning] [--out DIR]
#                       [--client-config FILE] [--server-config FILE] [--rate F] [--firmware [--elf FILE]]
#
# --tuning runs the fuzzy-PID tuning job instead (scripts/demo/tuning.console
# on config/worlds/tuning_floor.yaml, whose robot has worn, slower motors):
# identification wheel test, identify, circle with the paper's gains, tune,
# push the tuned gains, circle again (docs/tuning.md).
#
# The robot's camera is mcu_sim's (--camera): the simulated world as the PTZ
# camera on the robot sees it, handed to robot_client (--video-source sim:...)
# through a frame slot in /dev/shm (docs/video.md), so the operator's video
# and the recorded runs/<id>/video.mp4 show the world the robot is in.
#
# Watch it live in Foxglove or Lichtblick: the demo prints the bridge's URL
# with its token (ws://127.0.0.1:8765/?token=..., loopback, no TLS;
# docs/foxglove.md); import config/foxglove/inspect_live.json as the layout.
#
# --interactive (default when stdin is a terminal) leaves you in the console
# after the script; --batch exits when the script ends. --port 0 picks a free
# port for the robot link and the Foxglove bridge (the defaults are 7600 and
# 8765; --foxglove-port N sets the bridge's alone). --out DIR keeps the logs, ground truth, runs and
# video there (default: a new folder under $TMPDIR); the demo's test reads them.
# --client-config FILE gives robot_client other settings than config/client.yaml
# (the demo's test: a sensor timeout for a shared test host, docs/testing.md);
# --server-config FILE pc_server other settings than config/server.yaml (the
# demo's test: the Sparkplug edge node on a broker of its own, docs/sparkplug.md).
# --rate F runs the simulated world F times faster than real time (mcu_sim
# --rate; the robot's loop runs on the MCU's clock, so it controls the same):
# the demo's test takes 2 to check the same round in less time.
# --firmware puts the robot's real MCU firmware on the line instead of
# mcu_sim's emulator: its QEMU image (scripts/build_firmware.sh brings
# build-firmware/ up to date first; --elf FILE: that image instead) under
# scripts/mcu_qemu.sh, with mcu_sim --hil keeping the world (docs/firmware.md).
# Real time only (not with --rate).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BUILD_DIR:-build}/bin
PORT=7600
FOX_PORT=
MODE=auto
JOB=gas
OUT=
CLIENT_CONFIG=config/client.yaml
SERVER_CONFIG=
RATE=
FIRMWARE=0
ELF=
while [ $# -gt 0 ]; do
  case "$1" in
    --interactive) MODE=interactive ;;
    --batch) MODE=batch ;;
    --port) PORT=$2; shift ;;
    --foxglove-port) FOX_PORT=$2; shift ;;
    --tuning) JOB=tuning ;;
    --out) OUT=${2:?--out needs a folder}; shift ;;
    --client-config)  # relative to where the script was called from
      CLIENT_CONFIG=${2:?--client-config needs a file}; [ "${CLIENT_CONFIG#/}" != "$CLIENT_CONFIG" ] || CLIENT_CONFIG=$OLDPWD/$CLIENT_CONFIG; shift ;;
    --server-config)  # relative to where the script was called from
      SERVER_CONFIG=${2:?--server-config needs a file}; [ "${SERVER_CONFIG#/}" != "$SERVER_CONFIG" ] || SERVER_CONFIG=$OLDPWD/$SERVER_CONFIG; shift ;;
    --rate) RATE=${2:?--rate needs a factor}; shift ;;
    --firmware) FIRMWARE=1 ;;
    --elf)  # relative to where the script was called from
      ELF=${2:?--elf needs a file}; [ "${ELF#/}" != "$ELF" ] || ELF=$OLDPWD/$ELF; shift ;;
    -h|--help) sed -n '2,40p' "$0"; exit 0 ;;
    *) echo "run_demo: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [ "$FIRMWARE" = 1 ] && [ -n "$RATE" ]; then
  echo "run_demo: --firmware runs in real time: not with --rate" >&2
  exit 2
fi
if [ -z "$FOX_PORT" ]; then if [ "$PORT" = 0 ]; then FOX_PORT=0; else FOX_PORT=8765; fi; fi
if [ "$MODE" = auto ]; then
  if [ -t 0 ] && [ -t 1 ]; then MODE=interactive; else MODE=batch; fi
fi

if [ -n "${OUT:-}" ]; then mkdir -p "$OUT"; else OUT=$(mktemp -d "${TMPDIR:-/tmp}/inspect-demo-XXXXXX"); fi
# The camera's frame slot: in memory when /dev/shm is there (mcu_sim removes it at its end).
if [ -d /dev/shm ] && [ -w /dev/shm ]; then CAM=/dev/shm/inspect-demo-$$.camera; else CAM=$OUT/camera.slot; fi
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -f "$CAM"
}
trap cleanup EXIT

echo "demo: logs and ground truth in $OUT"
# Mutual TLS: certificates in certs/ (made once; the programs' default paths), docs/security.md.
bash scripts/make_certs.sh --out certs robot1 | sed 's/^/demo: /'
if [ "$JOB" = tuning ]; then
  WORLD=config/worlds/tuning_floor.yaml; SCRIPT=scripts/demo/tuning.console; SIM_ARGS=()
else
  WORLD=config/worlds/gas_lab.yaml; SCRIPT=scripts/demo/gas_inspection.console; SIM_ARGS=(--people-wait-motion)
fi
if [ -n "$RATE" ]; then SIM_ARGS+=(--rate "$RATE"); fi
# The real-time loops make themselves SCHED_FIFO once started when this user
# may (root, CAP_SYS_NICE; else a warning in their logs): the simulated MCU
# at 20, above the robot's control loop (realtime_priority: 10 in
# config/client.yaml), so a busy machine does not starve them into a
# stale-sensor failsafe (docs/testing.md, "Scheduling").
if [ "$FIRMWARE" = 1 ]; then
  if [ -z "$ELF" ]; then
    # Incremental: an image older than the firmware's sources or config/robot.yaml is rebuilt.
    bash scripts/build_firmware.sh --settings-gen "$BIN/mcu_settings_gen" | sed 's/^/demo: /'
    ELF=build-firmware/inspect-mcu-qemu.elf
  fi
  # QEMU (the MCU) and its mcu_sim at the hardware's priority, above robot_client's loop.
  bash scripts/mcu_qemu.sh --serial-link "$OUT/mcu" --elf "$ELF" --mcu-sim "$BIN/mcu_sim" --realtime-priority 20 \
    --world "$WORLD" --robot config/robot.yaml "${SIM_ARGS[@]}" --camera "$CAM" \
    --truth "$OUT/truth.csv" >"$OUT/mcu_sim.out" 2>"$OUT/mcu_sim.err" &
else
  "$BIN/mcu_sim" --realtime-priority 20 --world "$WORLD" --robot config/robot.yaml "${SIM_ARGS[@]}" --camera "$CAM" \
    --pty-link "$OUT/mcu" --truth "$OUT/truth.csv" >"$OUT/mcu_sim.out" 2>"$OUT/mcu_sim.err" &
fi
SIM=$!
PIDS+=("$SIM")
for _ in $(seq 400); do [ -e "$OUT/mcu" ] && break; sleep 0.05; done
[ -e "$OUT/mcu" ] || { echo "demo: mcu_sim did not start:"; cat "$OUT/mcu_sim.err"; exit 1; }
head -n 1 "$OUT/mcu_sim.out"

# robot_client starts once pc_server has reported its port.
(
  for _ in $(seq 200); do [ -s "$OUT/port" ] && [ -s "$OUT/video_port" ] && break; sleep 0.05; done
  exec "$BIN/robot_client" --config "$CLIENT_CONFIG" --robot-config config/robot.yaml \
    --serial "$OUT/mcu" --server "127.0.0.1:$(cat "$OUT/port")" --video-port "$(cat "$OUT/video_port")" \
    --map "$WORLD" --id robot1 --video-source "sim:$CAM" 2>"$OUT/robot_client.err"
) &
CLIENT=$!
PIDS+=("$CLIENT")

# Video on an ephemeral UDP port (5600 may be taken); SDP and snapshots in $OUT/video.
ARGS=(--config "${SERVER_CONFIG:-config/server.yaml}" --bind 127.0.0.1 --port "$PORT" --port-file "$OUT/port"
      --video-port 0 --video-port-file "$OUT/video_port" --video-dir "$OUT/video" --runs-dir "$OUT/runs"
      --operator-socket "$OUT/operator.sock" --script "$SCRIPT"
      --foxglove-port "$FOX_PORT" --foxglove-port-file "$OUT/foxglove_port" --foxglove-token-file "$OUT/foxglove.token")
# The Foxglove URL once the bridge listens (its token is made at start, mode 0600).
(
  for _ in $(seq 200); do [ -s "$OUT/foxglove_port" ] && [ -s "$OUT/foxglove.token" ] && break; sleep 0.05; done
  [ -s "$OUT/foxglove_port" ] || exit 0
  echo "demo: live in Foxglove / Lichtblick (open connection -> Foxglove WebSocket; layout config/foxglove/inspect_live.json):"
  echo "        ws://127.0.0.1:$(cat "$OUT/foxglove_port")/?token=$(head -n 1 "$OUT/foxglove.token")"
) &
PIDS+=("$!")
echo "demo: link: mutual TLS with certs/ (scripts/make_certs.sh); a second operator (observer; 'help control'):"
echo "        $BIN/pc_server --attach $OUT/operator.sock"
echo "demo: camera: the simulated world seen by the robot's camera (mcu_sim --camera $CAM), streamed as"
echo "      $OUT/video/robot1.sdp (play it while the console runs:"
echo "        ffplay -protocol_whitelist file,udp,rtp -fflags nobuffer -flags low_delay $OUT/video/robot1.sdp)"
echo "      snapshots: $OUT/video/robot1_latest.png (refreshed every 5 s), 'snapshot' at the console" 
status=0
if [ "$MODE" = interactive ]; then
  echo "demo: the script runs first; then the console is yours (try 'help', 'teleop', 'quit')"
  # Straight to the terminal (no tee), so the console has its live status line.
  "$BIN/pc_server" "${ARGS[@]}" --interactive 2>"$OUT/pc_server.err" || status=$?
else
  "$BIN/pc_server" "${ARGS[@]}" 2>"$OUT/pc_server.err" | tee "$OUT/pc_server.out" || status=$?
fi

kill "$CLIENT" 2>/dev/null || true
wait "$CLIENT" 2>/dev/null || true
kill -TERM "$SIM" 2>/dev/null || true
wait "$SIM" 2>/dev/null || true

echo
echo "=== what the robot did"
grep -E '^mcu_sim: (final pose|serial|hil |camera .* frames=)' "$OUT/mcu_sim.out" || true
awk -F, '$1=="T"{ if(!n){x0=$4;y0=$5;t0=$6;n=1} x=$4;y=$5;t=$6 }
  END{ if(!n) exit; dx=x-x0; dy=y-y0; c=cos(t0); s=sin(t0);
       d=t-t0; while(d>3.14159265)d-=6.2831853; while(d<-3.14159265)d+=6.2831853;
       printf "ground truth, relative to the start pose: x=%.3f m  y=%.3f m  theta=%.3f rad\n", c*dx+s*dy, -s*dx+c*dy, d }' "$OUT/truth.csv"
LAST=$(grep -E '^robot1 \| .* x [-+]?[0-9]' "$OUT/pc_server.out" 2>/dev/null | tail -n 1 || true)
[ -n "$LAST" ] && echo "last telemetry status line:               $LAST"
ls "$OUT"/video/*.png 2>/dev/null | sed 's/^/camera snapshot:                          /' || true
if [ "$status" -eq 0 ]; then echo "demo: all console checks passed"; else echo "demo: console checks FAILED (exit $status)"; fi
exit "$status"
