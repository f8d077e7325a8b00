#!/usr/bin/env bash
# bench.sh <build dir>: runs every benchmark; each prints cenote beside its peer, same run
# (server_bench starts its own cenote-server on loopback and compares it with the in-process map).
# The tables go into docs/PERFORMANCE.md by hand, with this command.
set -euo pipefail
build=${1:-build}
here=$(cd "$(dirname "$0")/.." && pwd)
for bench in "$build"/bench/*_bench; do
  echo "== $(basename "$bench")"
  "$bench"
  echo
done
echo "== run_throughput (cenote run on a simulated 800x600 cave, 112 disparities)"
echo "| run | fps | read+rectify ms | stereo ms | fusion ms | output ms | peak MiB | / paper's best |"
echo "|---|---|---|---|---|---|---|---|"
bash "$here/bench/run_throughput.sh" "$build/apps/cenote" "$here"
echo
echo "== recording_throughput bag (cenote run on a ROS 1 bag of JPEG pairs beside the same frames as PNG folders)"
bash "$here/bench/recording_throughput.sh" "$build/apps/cenote" "$here" "$build" bag
echo
echo "== recording_throughput mcap (cenote run on a ROS 2 MCAP of PNG pairs beside the same frames as PNG folders)"
cmake --build "$build" --target ros2_bag_data >/dev/null
bash "$here/bench/recording_throughput.sh" "$build/apps/cenote" "$here" "$build" mcap
echo
echo "== viewer_bench (cenote-server's live viewer: CPU per frame without / with a client, bytes sent)"
CENOTE_PYTHON_STUBS="$build/clients/python/gen" /usr/bin/python3 "$here/bench/viewer_bench.py" \
  "$build/apps/cenote" "$build/server/cenote-server" "$here"
