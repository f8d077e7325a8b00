#!/usr/bin/env bash
# simulator_table.sh: the paper's Table III/IV style summary on the simulator's scenes.
# For each scene: cenote sim -> cenote run raw (no fusion) and fused -> cenote eval depth and cloud
# against the simulator's ground truth; prints one Markdown table (docs/EVALUATION.md) and leaves
# everything, including an HTML report per run, in OUT.
#   eval/scripts/simulator_table.sh CENOTE OUT [FRAMES] [SCENES...]
# Defaults: 30 frames of cave, reef and wreck at 800x600.
set -euo pipefail
cenote=$1
out=$2
frames=${3:-30}
shift $(($# >= 3 ? 3 : $#))
scenes=("$@")
[[ ${#scenes[@]} -gt 0 ]] || scenes=(cave reef wreck)
num() { /usr/bin/python3 -c "import json,sys; v=json.load(open(sys.argv[1]))[sys.argv[2]]; print('n/a' if v is None else ('%.1f' % (100*v) if len(sys.argv) > 3 and sys.argv[3] == '%' else '%.3f' % v))" "$@"; }
stage() { /usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['stages'].get(sys.argv[2]); print('n/a' if s is None else '%.0f' % s['median_ms'])" "$@"; }
config=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/config/default.yaml
fps() { /usr/bin/python3 -c "import json,sys; print('%.1f' % json.load(open(sys.argv[1]))['fps'])" "$1"; }

rows=()
for scene in "${scenes[@]}"; do
  data=$out/$scene/data
  [[ -d $data/mav0 ]] || "$cenote" sim --scene "$scene" --frames "$frames" --out "$data" --quiet >/dev/null
  for mode in raw fused; do
    run=$out/$scene/$mode
    views=()
    [[ $mode == raw ]] && views=(--fusion-views 1)
    "$cenote" run --dataset "$data" --config "$config" --write-depth "${views[@]}" --out "$run" >/dev/null 2>&1
    # Our depth maps are named by the runner's nanosecond timestamps, the ground truth by the
    # simulator's: the same instants, rounded differently (hence --name-tolerance, in ns).
    "$cenote" eval depth --estimate "$run/depth" --reference "$data/groundtruth/depth" --name-tolerance 1000 \
      --json "$run/depth.json" --plot "$run/plots" --heatmaps 2 >/dev/null
    "$cenote" eval cloud --source "$run/points.ply" --target "$data/groundtruth/surface.ply" --voxel 0.01 \
      --json "$run/cloud.json" --plot "$run/plots" >/dev/null
    "$cenote" eval report "$run" --title "cenote on the simulated $scene ($mode)" >/dev/null
  done
  r=$out/$scene/raw
  f=$out/$scene/fused
  rows+=("| $scene | $(num "$r/depth.json" mae) | $(num "$f/depth.json" mae) | $(num "$f/depth.json" mom) | \
$(num "$f/depth.json" coverage %) | $(num "$f/cloud.json" precision %) | $(num "$f/cloud.json" recall %) | \
$(num "$f/cloud.json" accuracy) | $(stage "$f/report.json" stereo) | $(stage "$f/report.json" fusion) | $(fps "$f/report.json") |")
done
echo "| scene | raw MAE (m) | fused MAE (m) | fused MoM (m) | fused coverage (%) | precision @0.1 m (%) | recall @0.1 m (%) | accuracy (m) | stereo ms | fusion ms | fps |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
