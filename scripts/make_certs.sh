#!/usr/bin/env bash
# Certificates for the robot <-> server link (mutual TLS, docs/security.md):
# a CA, the server's certificate and one certificate per robot id. The robot
# id is the certificate's common name; pc_server accepts a Hello only when its
# robot id matches the certificate the robot authenticated with.
#
#   scripts/make_certs.sh [--out DIR] [--days N] [--server-name NAME]... [--force] ROBOT_ID...
#
# Writes DIR/ca.pem + ca.key (keep ca.key off the robots), DIR/server.pem +
# server.key, and DIR/<id>.pem + <id>.key per robot (default DIR: certs). Keys
# are EC P-256, mode 0600. Existing files are kept (safe to run again to add a
# robot); --force makes everything new. The server certificate names
# localhost, 127.0.0.1 and ::1 plus every --server-name (a DNS name or an IP
# address the robots use to reach the server).
set -euo pipefail

out=certs
days=825
force=0
server_names=()
ids=()
usage() { sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="${2:?--out needs a directory}"; shift 2 ;;
    --days) days="${2:?--days needs a number}"; shift 2 ;;
    --server-name) server_names+=("${2:?--server-name needs a name}"); shift 2 ;;
    --force) force=1; shift ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "make_certs: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) ids+=("$1"); shift ;;
  esac
done
if ! [[ "$days" =~ ^[0-9]+$ ]] || [ "$days" -lt 1 ]; then
  echo "make_certs: --days must be a positive whole number, got '$days'" >&2; exit 2
fi
for id in "${ids[@]}"; do
  if ! [[ "$id" =~ ^[A-Za-z0-9_-]{1,64}$ ]]; then
    echo "make_certs: robot id '$id' is not [A-Za-z0-9_-]{1,64} (the robot_id of client.yaml)" >&2; exit 2
  fi
  case "$id" in ca|server) echo "make_certs: '$id' is reserved, choose another robot id" >&2; exit 2 ;; esac
done
command -v openssl >/dev/null || { echo "make_certs: openssl not found (scripts/setup.sh installs it)" >&2; exit 1; }

mkdir -p "$out"
umask 077
# Several tests may ask for certificates at once: one at a time, so the CA is made once.
exec 9>"$out/.lock"
flock 9

if [ "$force" -eq 1 ]; then rm -f "$out"/*.pem "$out"/*.key "$out"/*.srl; fi

newkey() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1.tmp" 2>/dev/null && mv "$1.tmp" "$1"; }

# sign NAME SUBJECT EXTFILE: NAME.key + NAME.pem signed by the CA.
sign() {
  local name="$1" subj="$2" ext="$3"
  newkey "$out/$name.key"
  openssl req -new -key "$out/$name.key" -subj "$subj" -out "$out/$name.csr" 2>/dev/null
  openssl x509 -req -in "$out/$name.csr" -CA "$out/ca.pem" -CAkey "$out/ca.key" -CAcreateserial \
    -days "$days" -sha256 -extfile "$ext" -out "$out/$name.pem.tmp" 2>/dev/null
  mv "$out/$name.pem.tmp" "$out/$name.pem"
  rm -f "$out/$name.csr" "$ext"
  chmod 600 "$out/$name.key"
  chmod 644 "$out/$name.pem"
}

made=()
if [ ! -s "$out/ca.pem" ] || [ ! -s "$out/ca.key" ]; then
  rm -f "$out"/*.pem "$out"/*.key  # certificates of an old CA are useless
  newkey "$out/ca.key"
  openssl req -new -x509 -key "$out/ca.key" -subj "/O=inspect/CN=inspect link CA" -days "$days" -sha256 \
    -addext "basicConstraints=critical,CA:TRUE,pathlen:0" -addext "keyUsage=critical,keyCertSign,cRLSign" \
    -out "$out/ca.pem.tmp" 2>/dev/null
  mv "$out/ca.pem.tmp" "$out/ca.pem"
  chmod 644 "$out/ca.pem"
  made+=(ca)
fi

if [ ! -s "$out/server.pem" ] || [ ! -s "$out/server.key" ]; then
  san="DNS:localhost,IP:127.0.0.1,IP:::1"
  for n in "${server_names[@]}"; do
    if [[ "$n" =~ ^[0-9.]+$ || "$n" == *:* ]]; then san+=",IP:$n"; else san+=",DNS:$n"; fi
  done
  ext="$out/server.ext"
  printf '%s\n' "basicConstraints=critical,CA:FALSE" "keyUsage=critical,digitalSignature" \
    "extendedKeyUsage=serverAuth" "subjectAltName=$san" >"$ext"
  sign server "/O=inspect/CN=pc_server" "$ext"
  made+=(server)
fi

for id in "${ids[@]}"; do
  [ -s "$out/$id.pem" ] && [ -s "$out/$id.key" ] && continue
  ext="$out/$id.ext"
  printf '%s\n' "basicConstraints=critical,CA:FALSE" "keyUsage=critical,digitalSignature" \
    "extendedKeyUsage=clientAuth" >"$ext"
  sign "$id" "/O=inspect/CN=$id" "$ext"
  made+=("$id")
done

if [ ${#made[@]} -gt 0 ]; then
  echo "make_certs: made ${made[*]} in $out (valid $days days)"
else
  echo "make_certs: all present in $out"
fi
