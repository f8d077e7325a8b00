#!/usr/bin/env bash
# mcap_throughput.sh <cenote binary> <source dir> <build dir> [frames]: `cenote run` per frame on a ROS 2
# MCAP recording of PNG pairs (sensor_msgs/CompressedImage, zstd chunks, Odometry poses; written by
# @mcap/core through tests/io/bag/gen/euroc_to_mcap.js) beside the same frames as EuRoC PNG folders, in
# the same run: a simulated 800x600 cave dive, the default configuration, every frame. Prints the
# read+rectify stage (where the recording's reading, zstd and PNG decoding sit), the other stages, fps
# and the CPU time of the whole run per frame (user + system, all threads), and the MCAP's figures over
# the folder's. Needs the build's ros2_bag_data target (npm ci of tests/io/bag/gen).
set -euo pipefail
cenote=$1
source_dir=$2
gen=$3/tests/io/bag/gen
frames=${4:-100}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cenote" sim --scene cave --frames "$frames" --quiet --out "$work/cave" >/dev/null
node "$gen/euroc_to_mcap.js" "$work/cave" "$work/cave.mcap" png zstd
echo "| input | frames | read+rectify ms | stereo ms | fusion ms | fps | CPU ms/frame | peak MiB |"
echo "|---|---|---|---|---|---|---|---|"
TIMEFORMAT='%U %S'
for input in folder mcap; do
  if [ "$input" = folder ]; then
    args=(--dataset "$work/cave")
  else
    args=(--dataset "$work/cave.mcap" --left /cam0/image_raw/compressed --right /cam1/image_raw/compressed
          --pose-topic /odom --pose-frame body --calibration "$work/cave/mav0/cam0/sensor.yaml")
  fi
  { time "$cenote" run "${args[@]}" --out "$work/$input" >/dev/null 2>&1; } 2>"$work/cpu-$input.txt"
  /usr/bin/python3 - "$work/$input/report.json" "$input" "$work/cpu-$input.txt" "$work/ratio.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["stages"]
user, system = map(float, open(sys.argv[3]).read().split())
cpu = (user + system) * 1000.0 / max(r["frames_processed"], 1)
name = "EuRoC PNG folders" if sys.argv[2] == "folder" else "ROS 2 MCAP, PNG, zstd"
print(f"| {name} | {r['frames_processed']} | {s['read_rectify']['median_ms']:.1f} | {s['stereo']['median_ms']:.1f} | "
      f"{s['fusion']['median_ms']:.1f} | {r['fps']:.1f} | {cpu:.0f} | {r['peak_memory_mb']:.0f} |")
with open(sys.argv[4], "a") as f:
    f.write(f"{s['read_rectify']['median_ms']} {cpu} {r['fps']}\n")
PY
done
/usr/bin/python3 - "$work/ratio.txt" <<'PY'
import sys
(fr, fc, ff), (mr, mc, mf) = [map(float, l.split()) for l in open(sys.argv[1])]
print(f"| MCAP / folder | | {mr / fr:.2f}x | | | {mf / ff:.2f}x | {mc / fc:.2f}x | |")
PY
