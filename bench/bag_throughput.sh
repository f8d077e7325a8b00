#!/usr/bin/env bash
# bag_throughput.sh <cenote binary> <source dir> [frames]: `cenote run` per frame on a ROS 1 bag of
# JPEG pairs (quality 95, lz4 chunks, the SVIn2 rig's topics, Odometry poses) beside the same frames
# as EuRoC PNG folders, in the same run: a simulated 800x600 cave dive, the default configuration,
# every frame. Prints the read+rectify stage (where the bag's reading and JPEG decoding sit), the
# other stages, fps and the CPU time of the whole run per frame (user + system, all threads), and
# the bag's figure over the folder's.
set -euo pipefail
cenote=$1
source_dir=$2
frames=${3:-100}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cenote" sim --scene cave --frames "$frames" --quiet --out "$work/cave" >/dev/null
/usr/bin/python3 "$source_dir/tests/io/bag/euroc_to_bag.py" "$work/cave" "$work/cave.bag" --images jpeg --compression lz4
echo "| input | frames | read+rectify ms | stereo ms | fusion ms | fps | CPU ms/frame | peak MiB |"
echo "|---|---|---|---|---|---|---|---|"
TIMEFORMAT='%U %S'
for input in folder bag; do
  if [ "$input" = folder ]; then
    args=(--dataset "$work/cave")
  else
    args=(--dataset "$work/cave.bag" --pose-topic /odom --pose-frame body --calibration "$work/cave/mav0/cam0/sensor.yaml")
  fi
  { time "$cenote" run "${args[@]}" --out "$work/$input" >/dev/null 2>&1; } 2>"$work/cpu-$input.txt"
  /usr/bin/python3 - "$work/$input/report.json" "$input" "$work/cpu-$input.txt" "$work/ratio.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["stages"]
user, system = map(float, open(sys.argv[3]).read().split())
cpu = (user + system) * 1000.0 / max(r["frames_processed"], 1)
name = "EuRoC PNG folders" if sys.argv[2] == "folder" else "ROS 1 bag, JPEG q95, lz4"
print(f"| {name} | {r['frames_processed']} | {s['read_rectify']['median_ms']:.1f} | {s['stereo']['median_ms']:.1f} | "
      f"{s['fusion']['median_ms']:.1f} | {r['fps']:.1f} | {cpu:.0f} | {r['peak_memory_mb']:.0f} |")
with open(sys.argv[4], "a") as f:
    f.write(f"{s['read_rectify']['median_ms']} {cpu} {r['fps']}\n")
PY
done
/usr/bin/python3 - "$work/ratio.txt" <<'PY'
import sys
(fr, fc, ff), (br, bc, bf) = [map(float, l.split()) for l in open(sys.argv[1])]
print(f"| bag / folder | | {br / fr:.2f}x | | | {bf / ff:.2f}x | {bc / fc:.2f}x | |")
PY
