#!/usr/bin/env bash
# ctest fixture: installs the MCAP reader's locked dependencies (@mcap/core
# from the npm registry) into its folder in the build tree, $1.
set -uo pipefail
command -v npm >/dev/null || { echo 'record_npm_ci: npm not found: the MCAP reader tests need Node.js and npm' >&2; exit 1; }
npm ci --prefix "$1" --no-audit --no-fund ||
  { echo 'record_npm_ci: npm ci failed (no network or registry?): cannot install @mcap/core for the MCAP reader tests' >&2; exit 1; }
