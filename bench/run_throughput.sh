#!/usr/bin/env bash
# run_throughput.sh <cenote binary> <source dir> [frames]: end-to-end throughput of `cenote run` on
# a simulated 800x600 cave dive with 112 disparities, every frame, beside the paper's figure
# (2.8-10.2 fps over all frames on an 8-core i7-10700K, keyframes only). The map stage is included:
# every fused batch is integrated into the occupancy map (`--map`), which is written at the end.
# Besides the wall-clock fps it prints the CPU time of the whole run per frame (user + system, all
# threads, start-up included) and the rate two cores would sustain at that cost (2000 / CPU ms):
# on a machine shared with other work the wall clock says how busy the machine was, the CPU time
# what the pipeline costs. A second table splits the run's CPU time per frame by stage (each
# stage's thread with its OpenMP threads, from the run's own report: cpu_ms_per_frame in
# report.json, pipeline/runner/runner.h), with "other" the rest of the process during the run and
# "start-up + save" the process's time outside the run (loading, writing the map at the end).
set -euo pipefail
source "$(dirname "$0")/timed_run.sh"
cenote=$1
source_dir=$2
frames=${3:-150}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cenote" sim --scene cave --frames "$frames" --quiet --out "$work/cave" >/dev/null
echo "| run | fps | read+rectify ms | stereo ms | fusion ms | output ms | map ms | peak MiB | / paper's best | CPU ms/frame | 2-core fps |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for paths in 4 8; do
  # The default configuration with only the number of paths changed.
  /usr/bin/python3 - "$source_dir/config/default.yaml" "$paths" "$work/config.yaml" <<'PY'
import sys
text = open(sys.argv[1]).read().replace("num_paths: 4", "num_paths: " + sys.argv[2], 1)
open(sys.argv[3], "w").write(text)
PY
  cpu_ms=$(timed_cenote_run "$cenote" "$work/run$paths" --dataset "$work/cave" --config "$work/config.yaml" \
    --map "$work/run$paths/map.vdb")
  /usr/bin/python3 - "$work/run$paths/report.json" "$paths" "$frames" "$cpu_ms" "$work/cpu_table.txt" \
    >>"$work/table.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["stages"]
cpu_ms = float(sys.argv[4])
print(f"| cenote run, {sys.argv[2]} paths, {sys.argv[3]} frames | {r['fps']:.1f} | "
      + " | ".join(f"{s[k]['median_ms']:.1f}" for k in ("read_rectify", "stereo", "fusion", "output", "map"))
      + f" | {r['peak_memory_mb']:.0f} | {r['fps'] / 10.2:.1f}x | {cpu_ms:.0f} | {2000.0 / cpu_ms:.1f} |")
c = r["cpu_ms_per_frame"]
print(f"| cenote run, {sys.argv[2]} paths, {sys.argv[3]} frames | "
      + " | ".join(f"{c.get(k, 0.0):.1f}" for k in ("read_rectify", "stereo", "fusion", "output", "map", "other", "total"))
      + f" | {cpu_ms - c['total']:.1f} | {cpu_ms:.1f} |", file=open(sys.argv[5], "a"))
PY
done
cat "$work/table.txt"
echo "| paper (8-core i7-10700K, keyframes only) | 2.8-10.2 | | 323-399 | 375-678 | | | | 1.0x | | |"
echo
echo "CPU ms per frame processed, by stage (user + system, each stage's thread with its OpenMP threads):"
echo "| run | read+rectify | stereo | fusion | output | map | other | run total | start-up + save | process |"
echo "|---|---|---|---|---|---|---|---|---|---|"
cat "$work/cpu_table.txt"
