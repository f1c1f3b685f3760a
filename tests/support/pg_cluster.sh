#!/usr/bin/env bash
# A throw-away PostgreSQL server for the tests (docs/testing.md): initdb and
# pg_ctl (Debian's postgresql) in a fresh directory under /tmp, listening on
# a Unix socket in that directory only (no TCP port to collide), trust
# authentication for the role `inspect`, fsync off. Run as root (CI), the
# server runs as the unprivileged user postgres: PostgreSQL refuses root.
#
#   pg_cluster.sh start FILE   starts one; writes its directory (the socket's) to FILE
#   pg_cluster.sh stop FILE    stops the one FILE names; removes it and FILE
#   pg_cluster.sh halt FILE    stops it, keeping its data (an outage)
#   pg_cluster.sh resume FILE  starts the halted one again
set -euo pipefail
cmd=${1:-}
file=${2:-}
if [ -z "$cmd" ] || [ -z "$file" ]; then
  echo "usage: pg_cluster.sh start|stop|halt|resume FILE" >&2
  exit 2
fi
bindir=$(pg_config --bindir 2>/dev/null || true)
if [ ! -x "$bindir/initdb" ]; then
  bindir=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
fi
if [ ! -x "$bindir/initdb" ]; then
  echo "pg_cluster.sh: no initdb (install Debian's postgresql: scripts/setup.sh)" >&2
  exit 1
fi
as_server() {
  if [ "$(id -u)" = 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi
}
pg_ctl_start() {
  local dir=$1
  as_server "$bindir/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 30 \
    -o "-k $dir -c listen_addresses= -c fsync=off -c synchronous_commit=off -c full_page_writes=off" start >/dev/null
}

case $cmd in
  start)
    if [ -s "$file" ]; then bash "$0" stop "$file" || true; fi
    dir=$(mktemp -d /tmp/inspect-pg-XXXXXX)
    chmod 0755 "$dir"
    if [ "$(id -u)" = 0 ]; then chown postgres: "$dir"; fi
    as_server "$bindir/initdb" -D "$dir/data" -U inspect -A trust --no-sync -E UTF8 --no-locale >"$dir/initdb.log" 2>&1 ||
      { cat "$dir/initdb.log" >&2; exit 1; }
    pg_ctl_start "$dir" || { cat "$dir/server.log" >&2; exit 1; }
    echo "$dir" > "$file"
    echo "pg_cluster.sh: PostgreSQL $("$bindir/postgres" --version | awk '{print $3}') on $dir/.s.PGSQL.5432"
    ;;
  stop)
    dir=$(cat "$file" 2>/dev/null || true)
    if [ -n "$dir" ] && [ -d "$dir" ]; then
      as_server "$bindir/pg_ctl" -D "$dir/data" -m immediate -w stop >/dev/null 2>&1 || true
      rm -rf "$dir"
    fi
    rm -f "$file"
    ;;
  halt)
    dir=$(cat "$file")
    as_server "$bindir/pg_ctl" -D "$dir/data" -m fast -w stop >/dev/null
    ;;
  resume)
    dir=$(cat "$file")
    pg_ctl_start "$dir"
    ;;
  *)
    echo "pg_cluster.sh: unknown command '$cmd' (start, stop, halt or resume)" >&2
    exit 2
    ;;
esac
