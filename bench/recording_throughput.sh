#!/usr/bin/env bash
# recording_throughput.sh <cenote binary> <source dir> <build dir> <bag|mcap> [frames]: `cenote run` per
# frame on a recording beside the same frames as EuRoC PNG folders, in the same run: a simulated 800x600
# cave dive, the default configuration, every frame (100 unless given). The recording is
#   bag:  a ROS 1 bag of JPEG pairs (quality 95, lz4 chunks, the SVIn2 rig's topics, Odometry poses),
#         written by ROS's own rosbag through tests/io/bag/euroc_to_bag.py;
#   mcap: a ROS 2 MCAP recording of PNG pairs (sensor_msgs/CompressedImage, zstd chunks, Odometry poses),
#         written by @mcap/core through tests/io/bag/gen/euroc_to_mcap.js; needs the build's ros2_bag_data
#         target (npm ci of tests/io/bag/gen).
# Prints the read+rectify stage (where the recording's reading, decompression and image decoding sit),
# the other stages, fps and the CPU time of the whole run per frame (user + system, all threads), and
# the recording's figures over the folder's.
set -euo pipefail
source "$(dirname "$0")/timed_run.sh"
cenote=$1
source_dir=$2
gen=$3/tests/io/bag/gen
format=$4
frames=${5:-100}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
calibration=(--calibration "$work/cave/mav0/cam0/sensor.yaml")
case "$format" in
  bag)
    name="ROS 1 bag, JPEG q95, lz4"
    ratio_name="bag / folder"
    args=(--dataset "$work/cave.bag" --pose-topic /odom --pose-frame body "${calibration[@]}")
    ;;
  mcap)
    name="ROS 2 MCAP, PNG, zstd"
    ratio_name="MCAP / folder"
    args=(--dataset "$work/cave.mcap" --left /cam0/image_raw/compressed --right /cam1/image_raw/compressed
          --pose-topic /odom --pose-frame body "${calibration[@]}")
    ;;
  *)
    echo "recording_throughput.sh: format '$format' is neither bag nor mcap" >&2
    exit 2
    ;;
esac
"$cenote" sim --scene cave --frames "$frames" --quiet --out "$work/cave" >/dev/null
if [ "$format" = bag ]; then
  /usr/bin/python3 "$source_dir/tests/io/bag/euroc_to_bag.py" "$work/cave" "$work/cave.bag" --images jpeg --compression lz4
else
  node "$gen/euroc_to_mcap.js" "$work/cave" "$work/cave.mcap" png zstd
fi
echo "| input | frames | read+rectify ms | stereo ms | fusion ms | fps | CPU ms/frame | peak MiB |"
echo "|---|---|---|---|---|---|---|---|"
for input in folder "$format"; do
  if [ "$input" = folder ]; then
    run_args=(--dataset "$work/cave")
    label="EuRoC PNG folders"
  else
    run_args=("${args[@]}")
    label=$name
  fi
  cpu=$(timed_cenote_run "$cenote" "$work/$input" "${run_args[@]}")
  /usr/bin/python3 - "$work/$input/report.json" "$label" "$cpu" "$work/ratio.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["stages"]
cpu = float(sys.argv[3])
print(f"| {sys.argv[2]} | {r['frames_processed']} | {s['read_rectify']['median_ms']:.1f} | {s['stereo']['median_ms']:.1f} | "
      f"{s['fusion']['median_ms']:.1f} | {r['fps']:.1f} | {cpu:.0f} | {r['peak_memory_mb']:.0f} |")
with open(sys.argv[4], "a") as f:
    f.write(f"{s['read_rectify']['median_ms']} {cpu} {r['fps']}\n")
PY
done
/usr/bin/python3 - "$work/ratio.txt" "$ratio_name" <<'PY'
import sys
(fr, fc, ff), (rr, rc, rf) = [map(float, l.split()) for l in open(sys.argv[1])]
print(f"| {sys.argv[2]} | | {rr / fr:.2f}x | | | {rf / ff:.2f}x | {rc / fc:.2f}x | |")
PY
