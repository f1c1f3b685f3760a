#!/usr/bin/env bash
# Builds the Debian packages and checks them (docs/deploy.md):
#
#   scripts/package.sh            build/packages/inspect-robot-client_<v>_amd64.deb
#                                 build/packages/inspect-pc-server_<v>_amd64.deb
#   scripts/package.sh --arm64    build-arm64/packages/inspect-robot-client_<v>_arm64.deb
#                                 (the cross build of scripts/cross_pi.sh, no tests)
#
# Then: `lintian` on each package (no errors allowed), `systemd-analyze
# verify` on each unit (its programs taken from the unpacked package), and
# for amd64 the install test (tests/packaging/install_test.sh, also `ctest -L
# package`: both packages installed into a clean Debian 12 root, run against
# mcu_sim, removed and purged; needs root; --no-install-test skips it).
# Install a package with `apt install ./<file>.deb`.
set -euo pipefail
cd "$(dirname "$0")/.."
arch=amd64
install_test=1
for a in "$@"; do
  case "$a" in
    --arm64) arch=arm64; install_test=0 ;;
    --no-install-test) install_test=0 ;;
    -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "package.sh: unknown option $a (see --help)" >&2; exit 2 ;;
  esac
done

bash scripts/setup.sh lintian dpkg-dev fakeroot mmdebstrap
if [ "$arch" = arm64 ]; then
  bash scripts/cross_pi.sh --no-tests
  dir=${ARM64_BUILD_DIR:-build-arm64}
else
  bash scripts/build.sh
  dir=${BUILD_DIR:-build}
fi
rm -rf "$dir/packages"
(cd "$dir" && cpack -G DEB >/dev/null)

status=0
for deb in "$dir"/packages/*.deb; do
  echo "package: $deb ($(du -k "$deb" | cut -f1) kB)"
  # lintian: errors fail; warnings are printed. The tags overridden are the
  # ones a locally built, not-in-Debian package has by design.
  if ! lintian --fail-on error --suppress-tags \
      no-manual-page,initial-upload-closes-no-bugs,changelog-file-missing-in-native-package,extended-description-is-probably-too-short \
      "$deb"; then
    status=1
  fi
  unpacked=$(mktemp -d)
  dpkg-deb -x "$deb" "$unpacked"
  mkdir "$unpacked/.units"
  for unit in "$unpacked"/lib/systemd/system/*.service; do
    # The unit as installed, its programs looked up in the unpacked package
    # (the install test verifies it again inside an installed root).
    sed "s|/usr/bin/|$unpacked/usr/bin/|g" "$unit" > "$unpacked/.units/$(basename "$unit")"
    if systemd-analyze verify "$unpacked/.units/$(basename "$unit")"; then
      echo "package: $(basename "$unit") verifies"
    else
      status=1
    fi
  done
  rm -rf "$unpacked"
done
if [ "$arch" = amd64 ]; then
  # The arm64 package's Depends (packaging/robot-client/depends.txt) must name
  # the libraries dpkg-shlibdeps found for the amd64 one.
  shlib=$(dpkg-deb -f "$dir"/packages/inspect-robot-client_*_amd64.deb Depends | tr ',' '\n' |
          sed 's/([^)]*)//g; s/|.*//; s/ //g' | grep -v -x -e adduser -e init-system-helpers -e '' | sort -u)
  listed=$(grep '^[a-z]' packaging/robot-client/depends.txt | sort -u)
  if [ "$shlib" = "$listed" ]; then
    echo "package: packaging/robot-client/depends.txt names what dpkg-shlibdeps found"
  else
    echo "package: packaging/robot-client/depends.txt differs from dpkg-shlibdeps' list:" >&2
    diff <(echo "$listed") <(echo "$shlib") >&2 || true
    status=1
  fi
fi
if [ $status -eq 0 ] && [ $install_test = 1 ]; then
  bash tests/packaging/install_test.sh "$dir" || status=1
fi
[ $status -eq 0 ] && echo "package: all packages built and checked in $dir/packages" || echo "package: checks failed" >&2
exit $status
