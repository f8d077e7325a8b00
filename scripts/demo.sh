#!/usr/bin/env bash
# demo.sh <build dir> <output dir>: a simulated cave dive through the whole pipeline, judged
# against the simulator's ground truth, plus dense stereo on a real Middlebury pair.
set -euo pipefail
build=${1:-build}
out=${2:-out/demo}
cenote="$build/apps/cenote"
server="$build/server/cenote-server"
cli="$build/clients/cli/cenote-cli"
here=$(cd "$(dirname "$0")/.." && pwd)
frames=${CENOTE_DEMO_FRAMES:-60}
rm -rf "$out"
mkdir -p "$out"

echo "== 1. simulate a ${frames}-frame cave dive (800x600, 15 Hz, EuRoC layout + ground truth)"
"$cenote" sim --scene cave --frames "$frames" --out "$out/cave"

echo "== 2. run the real-time pipeline: rectify, stereo (SAD 3x3, 4-path SGM), 3-view fusion"
"$cenote" run --dataset "$out/cave" --config "$here/config/default.yaml" --out "$out/run" --write-depth \
  --voxel 0.01 --map "$out/run/map.vdb"
"$cenote" map info "$out/run/map.vdb" || true

echo "== 3. fused points against the simulated surface (precision / recall at 0.1 m, the paper's;"
echo "      recall counts the whole surface the cameras saw, also beyond the 4 m working range)"
"$cenote" eval cloud --source "$out/run/points.ply" --target "$out/cave/groundtruth/surface.ply" \
  --threshold 0.1 --voxel 0.01 --json "$out/run/cloud_metrics.json" --plot "$out/run/plots" || true
"$cenote" eval report "$out/run" --out "$out/report.html" || true

echo "== 4. dense stereo on a real pair (Middlebury 2014 Motorcycle, from Debian's python3-skimage)"
if [ -f "$here/data/motorcycle/motorcycle_left.png" ]; then
  "$cenote" stereo --left "$here/data/motorcycle/motorcycle_left.png" --right "$here/data/motorcycle/motorcycle_right.png" \
    --disparities 64 --out-disparity "$out/motorcycle.disparity.pfm" --out-confidence "$out/motorcycle.confidence.pfm" \
    --out-preview "$out/motorcycle.preview.png" --repeat 5
else
  echo "(Motorcycle not unpacked: scripts/fetch-test-data.sh)"
fi

echo "== 5. stream the dive into cenote-server at camera rate, watch it live, and ask it what a planner asks"
if [ -x "$server" ] && [ -x "$cli" ]; then
  rm -f "$out/server.port"
  "$server" --config "$here/config/default.yaml" --calibration "$out/cave" --listen 127.0.0.1:0 \
    --viewer-listen "127.0.0.1:${CENOTE_DEMO_VIEWER_PORT:-0}" --port-file "$out/server.port" \
    --snapshot-dir "$out/snapshots" > "$out/server.log" 2>&1 &
  server_pid=$!
  for _ in $(seq 1 600); do [ -f "$out/server.port" ] && break; sleep 0.1; done
  address="127.0.0.1:$(cat "$out/server.port")"
  for _ in $(seq 1 100); do grep -q "viewer on http://" "$out/server.log" && break; sleep 0.1; done
  viewer_url=$(grep -o "viewer on http://[^ ]*" "$out/server.log" | sed 's/^viewer on //' || true)
  echo "server on $address"
  echo "LIVE VIEW of the dive: open $viewer_url in a browser (or Foxglove / Lichtblick: ${viewer_url/http/ws}; docs/VIEWER.md)"
  # A person watching gets time to open the page first (CENOTE_DEMO_WAIT_S, 10 s on a terminal).
  wait_s=${CENOTE_DEMO_WAIT_S:-$([ -t 1 ] && echo 10 || echo 0)}
  [ "$wait_s" -gt 0 ] && echo "streaming starts in $wait_s s" && sleep "$wait_s"
  /usr/bin/python3 "$here/clients/python/examples/stream_dive.py" --server "$address" \
    --stubs "$build/clients/python/gen" "$out/cave"
  "$cli" --server "$address" info
  echo "-- voxel states 1 m and 2 m ahead of the start, and 0.5 m to the side (x y z state probability):"
  "$cli" --server "$address" state 1,0,0 2,0,0 0,0.5,0 0,2,0
  echo "-- is the straight path 3 m ahead clear for a 0.2 m-radius vehicle?"
  "$cli" --server "$address" segment 0,0,0 3,0,0 --radius 0.2 || true
  echo "-- the three nearest frontiers:"
  "$cli" --server "$address" frontiers --max 3
  "$cli" --server "$address" snapshot map.mesh.ply > /dev/null
  # The viewer stays up for a look at the finished map (CENOTE_DEMO_VIEW_S, 30 s on a terminal).
  view_s=${CENOTE_DEMO_VIEW_S:-$([ -t 1 ] && echo 30 || echo 0)}
  [ "$view_s" -gt 0 ] && echo "the live view stays up for $view_s s ($viewer_url)" && sleep "$view_s"
  kill -TERM "$server_pid" && wait "$server_pid"
else
  echo "(cenote-server or cenote-cli not built)"
fi

echo
echo "demo outputs in $out/:"
echo "  cave/                       simulated EuRoC dataset with groundtruth/ (depth, poses, surface.ply)"
echo "  run/points.ply              fused coloured points, one per 1 cm voxel, world frame (MeshLab, CloudCompare)"
echo "  run/map.vdb                 OpenVDB occupancy map (cenote map info / export / query)"
echo "  run/depth/                  fused depth and confidence maps (PFM)"
echo "  run/report.json             frames, per-stage ms (median, p95), fps, peak memory"
echo "  report.html                 one-page report with metrics and plots"
echo "  motorcycle.preview.png      colour-mapped disparity of a real pair"
echo "  snapshots/                  written by cenote-server from the streamed dive: map.mesh.ply (asked for), map.vdb (on shutdown)"
echo
echo "live view of the dive's map (browser, or Foxglove / Lichtblick at ws://127.0.0.1:8765; docs/VIEWER.md):"
echo "  $cenote view $out/run/map.vdb   then open http://127.0.0.1:8765/"
