#!/usr/bin/env bash
# demo.sh <build dir> <output dir>: runs cenote on real data and says where the outputs are.
# Today: dense stereo on the Middlebury pairs (beside the project, or unpacked from Debian
# packages by scripts/fetch-test-data.sh). When the simulator and runner land, a cave dive.
set -euo pipefail
build=${1:-build}
out=${2:-out/demo}
cenote="$build/apps/cenote"
mkdir -p "$out"
here=$(cd "$(dirname "$0")/.." && pwd)

run_pair() {
  local name=$1 left=$2 right=$3 disparities=$4
  [ -f "$left" ] && [ -f "$right" ] || { echo "demo: $name not available, skipped"; return; }
  echo "== $name: $(basename "$left") + $(basename "$right"), $disparities disparities"
  "$cenote" stereo --left "$left" --right "$right" --disparities "$disparities" \
    --out-disparity "$out/$name.disparity.pfm" --out-confidence "$out/$name.confidence.pfm" \
    --out-preview "$out/$name.preview.png" --repeat 10
}

run_pair motorcycle "$here/data/motorcycle/motorcycle_left.png" "$here/data/motorcycle/motorcycle_right.png" 64
run_pair cones "$here/../shared/data/middlebury/cones/im2.png" "$here/../shared/data/middlebury/cones/im6.png" 64
run_pair cloth3 "$here/../shared/data/middlebury/Cloth3/view1.png" "$here/../shared/data/middlebury/Cloth3/view5.png" 128
echo
echo "demo outputs in $out/:"
ls -1 "$out"
