#!/usr/bin/env bash
# bench.sh <build dir>: runs every benchmark; each prints cenote beside its peer, same run.
# The tables go into docs/PERFORMANCE.md by hand, with this command.
set -euo pipefail
build=${1:-build}
for bench in "$build"/bench/*_bench; do
  echo "== $(basename "$bench")"
  "$bench"
  echo
done
