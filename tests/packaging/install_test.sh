#!/usr/bin/env bash
# The amd64 packages installed into a clean Debian 12 root, run and removed
# (docs/deploy.md "Install test"):
#
#   tests/packaging/install_test.sh BUILD_DIR
#
# 1. A minimal Debian 12 root with the packages' dependencies and systemd (mmdebstrap,
#    cached as BUILD_DIR/pkgroot-base.tar, made again when the Depends
#    change), unpacked into a fresh folder.
# 2. `dpkg -i` of inspect-robot-client and inspect-pc-server inside it (a
#    chroot: the maintainer scripts run and make the user `inspect`).
# 3. Certificates in /etc/inspect/certs; mcu_sim (from the build tree) on a
#    pty the root sees as its serial port (group dialout, as a Pi's UART);
#    pc_server and robot_client started from /usr/bin in the chroot as the
#    user `inspect`, with the installed configs in /etc/inspect; an attached
#    operator console drives 2 s at 0.3 m/s and checks the odometry.
# 4. `dpkg -r`: only conffiles and what the service made (/var/lib/inspect
#    data, the certificates we put there) stay; `dpkg -P`: the conffiles go.
# Needs root (chroot, mounts). Prints PASS/FAIL per check; exit 1 on a failure.
set -euo pipefail
BUILD=$(cd "${1:?usage: install_test.sh BUILD_DIR}" && pwd)
SRC=$(cd "$(dirname "$0")/../.." && pwd)
CACHE=$BUILD/pkgroot-base.tar
fail=0
check() {  # check NAME COMMAND...
  local name=$1; shift
  if "$@"; then echo "PASS $name"; else echo "FAIL $name"; fail=1; fi
}

debs=("$BUILD"/packages/inspect-robot-client_*_amd64.deb "$BUILD"/packages/inspect-pc-server_*_amd64.deb)
for d in "${debs[@]}"; do [ -f "$d" ] || { echo "install_test: no $d (scripts/package.sh makes it)" >&2; exit 2; }; done

# 1. The root.
deps=$(for d in "${debs[@]}"; do dpkg-deb -f "$d" Depends; done | tr ',' '\n' |
       sed 's/([^)]*)//g; s/|.*//; s/ //g' | grep -v '^$' | sort -u | paste -sd, -)
if [ ! -f "$CACHE" ] || [ "$(cat "$CACHE.deps" 2>/dev/null)" != "$deps" ]; then
  t=$(date +%s)
  mmdebstrap --quiet --variant=minbase --include="$deps,systemd" bookworm "$CACHE.part.tar" \
    "deb http://deb.debian.org/debian bookworm main" \
    "deb http://deb.debian.org/debian bookworm-updates main" \
    "deb http://deb.debian.org/debian-security bookworm-security main"
  mv "$CACHE.part.tar" "$CACHE"
  echo "$deps" > "$CACHE.deps"
  echo "install_test: clean root with the dependencies made in $(( $(date +%s) - t )) s ($(du -m "$CACHE" | cut -f1) MB)"
fi
ROOT=$(mktemp -d "${TMPDIR:-/tmp}/inspect-pkgroot-XXXXXX")
pids=()
# Every process whose root is the test's root (pc_server and robot_client run
# there through chroot, under a subshell whose pid is not theirs), then the
# ones started here: TERM, 5 s, KILL. Says what it stopped.
stop_all() {
  local p left=() names=()
  for p in /proc/[0-9]*; do
    [ "$(readlink "$p/root" 2>/dev/null)" = "$ROOT" ] && left+=("${p#/proc/}")
  done
  left+=("${pids[@]}")
  for p in "${left[@]}"; do
    kill -0 "$p" 2>/dev/null || continue
    names+=("$(cat "/proc/$p/comm" 2>/dev/null || echo "$p")[$p]")
    kill -TERM "$p" 2>/dev/null || true
  done
  for _ in $(seq 50); do
    local alive=0
    for p in "${left[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  for p in "${left[@]}"; do kill -KILL "$p" 2>/dev/null && echo "install_test: $p did not stop in 5 s: killed"; done
  wait 2>/dev/null || true
  pids=()
  [ ${#names[@]} -eq 0 ] || echo "install_test: stopped ${names[*]}"
}
cleanup() {
  stop_all
  for m in dev/pts dev proc; do umount "$ROOT/$m" 2>/dev/null || true; done
  if grep -q " $ROOT/" /proc/mounts; then
    echo "install_test: $ROOT still has mounts ($(grep " $ROOT/" /proc/mounts | cut -d' ' -f2 | paste -sd' ')): not removed" >&2
  elif [ -z "${KEEP_TEST_DIRS:-}" ]; then rm -rf "$ROOT"; else echo "install_test: kept $ROOT"; fi
}
trap cleanup EXIT
tar -C "$ROOT" -xf "$CACHE"
mount --bind /dev "$ROOT/dev"
mount --bind /dev/pts "$ROOT/dev/pts"
mount -t proc proc "$ROOT/proc"
in_root() { chroot "$ROOT" "$@"; }
# The user the units run as, by number (chroot would look names up on the host).
as_inspect() {
  chroot --userspec="$(in_root id -u inspect):$(in_root id -g inspect)" \
    --groups="$(in_root getent group dialout | cut -d: -f3),$(in_root getent group video | cut -d: -f3)" "$ROOT" "$@"
}
# Every path in the root but the kernel's, dpkg's own records and logs.
snapshot() {
  (cd "$ROOT" && find . -xdev \( -path ./proc -o -path ./dev -o -path ./tmp -o -path ./run \
     -o -path ./var/lib/dpkg -o -path ./var/log -o -path ./var/cache \) -prune -o -print | sort)
}
snapshot > "$ROOT/tmp/before.txt"

# 2. Install.
cp "${debs[@]}" "$ROOT/tmp/"
check "dpkg -i both packages" in_root sh -c 'dpkg -i /tmp/*.deb > /tmp/dpkg-install.log 2>&1' || cat "$ROOT/tmp/dpkg-install.log"
check "programs in /usr/bin" test -x "$ROOT/usr/bin/robot_client" -a -x "$ROOT/usr/bin/pc_server"
check "user inspect in dialout and video" sh -c "chroot '$ROOT' id -nG inspect | grep -qw dialout && chroot '$ROOT' id -nG inspect | grep -qw video"
conffiles=$(in_root dpkg-query -W -f='${Conffiles}\n' inspect-robot-client inspect-pc-server | awk 'NF {print $1}' | sort)
check "conffiles are the 5 configs in /etc/inspect" test "$(echo "$conffiles" | grep -c '^/etc/inspect/.*\.yaml$')" = 5
for unit in inspect-robot-client.service inspect-pc-server.service; do
  check "$unit verifies where it is installed" in_root systemd-analyze verify "/lib/systemd/system/$unit"
done

# 3. Run them.
bash "$SRC/scripts/make_certs.sh" --out "$ROOT/etc/inspect/certs" robot1 > /dev/null
in_root sh -c 'chgrp inspect /etc/inspect/certs/*.key && chmod 0640 /etc/inspect/certs/*.key && rm /etc/inspect/certs/ca.key'
install -d -m 0750 "$ROOT/run/inspect"; in_root chown inspect:inspect /run/inspect
"$BUILD/bin/mcu_sim" --world "$SRC/config/worlds/empty.yaml" --robot "$SRC/config/robot.yaml" \
  --pty-link "$ROOT/tmp/mcu" > "$ROOT/tmp/mcu_sim.out" 2> "$ROOT/tmp/mcu_sim.err" &
pids+=($!)
for _ in $(seq 100); do [ -e "$ROOT/tmp/mcu" ] && break; sleep 0.1; done
pty=$(readlink "$ROOT/tmp/mcu")
chgrp "$(in_root getent group dialout | cut -d: -f3)" "$pty" && chmod 0660 "$pty"   # as a Pi's UART: root:dialout 0660
as_inspect sh -c 'cd /usr/share/inspect-pc-server && exec /usr/bin/pc_server --config /etc/inspect/server.yaml \
  --no-console --port 0 --port-file /var/lib/inspect/port --video-port 0 --video-port-file /var/lib/inspect/video_port \
  --foxglove-port 0' > "$ROOT/tmp/pc_server.out" 2> "$ROOT/tmp/pc_server.err" &
pids+=($!)
for _ in $(seq 100); do [ -s "$ROOT/var/lib/inspect/video_port" ] && [ -S "$ROOT/run/inspect/operator.sock" ] && break; sleep 0.1; done
port=$(cat "$ROOT/var/lib/inspect/port" 2>/dev/null || echo 0)
vport=$(cat "$ROOT/var/lib/inspect/video_port" 2>/dev/null || echo 0)
check "pc_server listening (port $port)" test "$port" -gt 0
as_inspect sh -c "cd /usr/share/inspect-robot-client && exec /usr/bin/robot_client --config /etc/inspect/client.yaml \
  --robot-config /etc/inspect/robot.yaml --control-config /etc/inspect/control.yaml \
  --behavior-config /etc/inspect/behavior.yaml --serial /tmp/mcu --server 127.0.0.1:$port --video-port $vport \
  --video-source synthetic --id robot1" > "$ROOT/tmp/robot_client.out" 2> "$ROOT/tmp/robot_client.err" &
pids+=($!)
cat > "$ROOT/tmp/drive.console" <<'SCRIPT'
expect robots >= 1 within 20
expect sensor_hz > 50 within 5
drive 0.3 0
wait 2
stop
wait 1
expect v ~ 0 0.02 within 2
expect x ~ 0.6 0.1
quit
SCRIPT
# The script through a pipe that stays open while it runs: an attached
# console's `drive` is leased, and the attach client's keep-alives (only
# while its input is open) say the operator is there through `wait 2`. An
# attached session's failed expect does not change the attach client's exit
# status, so the output is checked: all four expects held.
if as_inspect sh -c '(cat /tmp/drive.console; sleep 12) | timeout 60 /usr/bin/pc_server --attach /run/inspect/operator.sock' \
     > "$ROOT/tmp/drive.out" 2>&1 && ! grep -q "EXPECT FAILED" "$ROOT/tmp/drive.out" &&
   [ "$(grep -c '^expect ok' "$ROOT/tmp/drive.out")" = 4 ]; then drive=0; else drive=1; fi
cat "$ROOT/tmp/drive.out"
check "drive through the installed programs (4 expects held)" test $drive = 0
check "the service user made the runs and the catalog" test -f "$ROOT/var/lib/inspect/runs/catalog.sqlite"
stop_all
check "nothing left running in the root" sh -c "! for p in /proc/[0-9]*; do [ \"\$(readlink \$p/root 2>/dev/null)\" = '$ROOT' ] && echo \$p; done | grep -q ."
[ $fail = 0 ] || for f in pc_server.err robot_client.err mcu_sim.err dpkg-install.log; do
  echo "---- $f"; tail -20 "$ROOT/tmp/$f"; done

# 4. Remove, then purge.
check "dpkg -r both" in_root sh -c 'dpkg -r inspect-robot-client inspect-pc-server > /tmp/dpkg-remove.log 2>&1'
snapshot > "$ROOT/tmp/after-remove.txt"
left=$(comm -13 "$ROOT/tmp/before.txt" "$ROOT/tmp/after-remove.txt" | sed 's|^\.||' |
       grep -v -x -F -f <(echo "$conffiles"; echo /etc/inspect) |
       grep -v -e '^/var/lib/inspect' -e '^/etc/inspect/certs' -e '^/var/lib/systemd/deb-systemd-helper' \
               -e '^/etc/systemd/system' || true)
echo "after dpkg -r, besides conffiles, service data and certificates: ${left:-nothing}"
check "dpkg -r leaves only conffiles (and the service's data)" test -z "$left"
check "conffiles kept by dpkg -r" test -f "$ROOT/etc/inspect/server.yaml" -a -f "$ROOT/etc/inspect/client.yaml"
check "dpkg -P both" in_root sh -c 'dpkg -P inspect-robot-client inspect-pc-server > /tmp/dpkg-purge.log 2>&1'
check "dpkg -P removes the conffiles" test ! -e "$ROOT/etc/inspect/server.yaml" -a ! -e "$ROOT/etc/inspect/client.yaml"
snapshot > "$ROOT/tmp/after-purge.txt"
left=$(comm -13 "$ROOT/tmp/before.txt" "$ROOT/tmp/after-purge.txt" | sed 's|^\.||' |
       grep -v -e '^/var/lib/inspect' -e '^/etc/inspect' || true)
echo "after dpkg -P, besides service data and certificates: ${left:-nothing}"
check "dpkg -P leaves nothing of the packages" test -z "$left"
[ $fail = 0 ] && echo "install_test: all checks passed" || echo "install_test: FAILED" >&2
exit $fail
