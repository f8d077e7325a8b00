#!/usr/bin/env bash
# End-to-end test of ROS 2 MCAP recordings in `cenote run` and `cenote bag info`: a simulated dive
# (`cenote sim`, EuRoC layout) converted to MCAP by the MCAP team's own writer (tests/io/bag/gen/
# euroc_to_mcap.js: @mcap/core, CDR from Foxglove's serialiser) gives the same points.ply, byte for
# byte, and the same voxels as the folder it came from, with raw (sensor_msgs/Image) or PNG
# (CompressedImage) images and uncompressed, zstd or lz4 chunks; with JPEG images at quality 95 those of
# OpenCV's decoding of the same bytes, and the folder's voxels within one voxel; so does a ROS 2 sqlite3 bag of the
# same messages (mcap_to_db3.py), with or without its metadata.yaml, or compressed by rosbag2's zstd
# compression of each message or each file. A recording cut short runs to the
# cut and says where it stopped. A damaged chunk is skipped and named, the other frames as in the folder.
# Usage: cli_mcap_test.sh <cenote binary> <source dir> <build dir of tests/io/bag/gen (node_modules)>
set -u
cenote=$1
source_dir=$2
gen=$3
source "$(dirname "${BASH_SOURCE[0]}")/../../support/cli_test_lib.sh"
source "$(dirname "${BASH_SOURCE[0]}")/jpeg_map_check.sh"
py=/usr/bin/python3
frames=20

simulate_reef $frames "$work/dive"
$py "$source_dir/tests/io/bag/gen/dump_pixels.py" "$work/dive" "$work/pixels" "$work/jpeg-pixels" || fail "dump_pixels.py failed"
to_mcap() {  # to_mcap NAME IMAGES COMPRESSION
  node "$gen/euroc_to_mcap.js" "$work/dive" "$work/$1.mcap" "$2" "$3" "$work/pixels" || fail "euroc_to_mcap.js $*"
}
run() {  # run NAME ARGS...: cenote run into $work/NAME-out with a map $work/NAME.vdb
  local name=$1
  shift
  "$cenote" run "$@" --config "$source_dir/config/default.yaml" --out "$work/$name-out" --map "$work/$name.vdb" \
    >"$work/$name.txt" 2>&1 || fail "cenote run ($name) failed: $(tail -5 "$work/$name.txt")"
}
mcap_run() {  # mcap_run NAME SUFFIX ARGS...: the recording $work/NAME.mcap, image topics /camN/SUFFIX
  local name=$1 suffix=$2
  shift 2
  run "$name" --dataset "$work/$name.mcap" --left "/cam0/$suffix" --right "/cam1/$suffix" --pose-topic /odom \
    --pose-frame body --calibration "$work/dive/mav0/cam0/sensor.yaml" "$@"
}

run euroc --dataset "$work/dive"
for variant in "raw none image_raw" "raw zstd image_raw" "png lz4 image_raw/compressed" "png none image_raw/compressed"; do
  set -- $variant
  to_mcap "$1-$2" "$1" "$2"
  mcap_run "$1-$2" "$3"
  [ "$(json "$work/$1-$2-out/report.json" 'd["frames_processed"]')" = $frames ] || fail "$1-$2: frames not all processed"
  cmp -s "$work/euroc-out/points.ply" "$work/$1-$2-out/points.ply" || fail "$1-$2: points.ply differs from the folder's"
  "$cenote" eval map --estimate "$work/$1-$2.vdb" --reference "$work/euroc.vdb" --json "$work/$1-$2.json" >/dev/null 2>&1 ||
    fail "cenote eval map ($1-$2) failed"
  [ "$(json "$work/$1-$2.json" 'd["agreement"] == 1.0 and d["known_either"] == d["known_both"] > 0')" = True ] ||
    fail "$1-$2: the voxels differ from the folder's: $(head -c 400 "$work/$1-$2.json")"
  echo "$1 images, $2 chunks: the folder's points and voxels"
done

# JPEG at quality 95 (OpenCV's bytes, CompressedImage "bgr8; jpeg compressed bgr8"): the points and
# voxels of a folder of OpenCV's decoding of the same bytes, and the folder's map within one voxel
# (jpeg_map_check.sh; strictly about 92 % of the voxels agree).
to_mcap jpeg jpeg lz4
mcap_run jpeg image_raw/compressed
run jpeg-pixels --dataset "$work/jpeg-pixels"
cmp -s "$work/jpeg-pixels-out/points.ply" "$work/jpeg-out/points.ply" || fail "jpeg: points differ from OpenCV's decoding's"
expect_jpeg_map "MCAP jpeg q95 images" "$work/jpeg.vdb" "$work/jpeg-pixels.vdb" "$work/euroc.vdb" 0.92 0.955

# The same messages in a ROS 2 sqlite3 bag (mcap_to_db3.py: Python's sqlite3, rosbag2's tables): the
# folder's points and voxels too, also from the .db3 file alone without its metadata.yaml.
$py "$source_dir/tests/io/bag/gen/mcap_to_db3.py" "$work/raw-none.mcap" "$work/dive_db3" || fail "mcap_to_db3.py failed"
run db3 --dataset "$work/dive_db3" --left /cam0/image_raw --right /cam1/image_raw --pose-topic /odom --pose-frame body \
  --calibration "$work/dive/mav0/cam0/sensor.yaml"
cmp -s "$work/euroc-out/points.ply" "$work/db3-out/points.ply" || fail "db3: points.ply differs from the folder's"
"$cenote" eval map --estimate "$work/db3.vdb" --reference "$work/euroc.vdb" --json "$work/db3.json" >/dev/null 2>&1 ||
  fail "cenote eval map (db3) failed"
[ "$(json "$work/db3.json" 'd["agreement"] == 1.0 and d["known_either"] == d["known_both"] > 0')" = True ] ||
  fail "db3: the voxels differ from the folder's"
rm "$work/dive_db3/metadata.yaml"
run db3-unfinished --dataset "$work/dive_db3" --left /cam0/image_raw --right /cam1/image_raw --pose-topic /odom \
  --pose-frame body --calibration "$work/dive/mav0/cam0/sensor.yaml"
cmp -s "$work/euroc-out/points.ply" "$work/db3-unfinished-out/points.ply" || fail "db3 without metadata.yaml: other points"
grep -q "no metadata.yaml (the recorder did not finish): read the 1 .db3 file in the folder" "$work/db3-unfinished.txt" ||
  fail "a bag without metadata.yaml is not reported: $(grep -i metadata "$work/db3-unfinished.txt")"
# rosbag2's zstd compression (mcap_to_db3.py MESSAGE / FILE, python3-zstandard): the uncompressed
# bag's points byte for byte; FILE's decompressed copy lives in TMPDIR while it is read, then goes.
for mode in MESSAGE FILE; do
  $py "$source_dir/tests/io/bag/gen/mcap_to_db3.py" "$work/raw-none.mcap" "$work/db3_$mode" $mode ||
    fail "mcap_to_db3.py $mode failed"
  mkdir -p "$work/tmp-$mode"
  TMPDIR="$work/tmp-$mode" run "db3-$mode" --dataset "$work/db3_$mode" --left /cam0/image_raw --right /cam1/image_raw \
    --pose-topic /odom --pose-frame body --calibration "$work/dive/mav0/cam0/sensor.yaml"
  cmp -s "$work/db3-out/points.ply" "$work/db3-$mode-out/points.ply" || fail "db3 $mode: points.ply differs from the plain bag's"
  [ "$(json "$work/db3-$mode-out/report.json" 'd["frames_processed"]')" = $frames ] || fail "db3 $mode: frames not all processed"
  [ -z "$(ls -A "$work/tmp-$mode")" ] || fail "db3 $mode: temporary files left: $(ls "$work/tmp-$mode")"
done
grep -qF "zstd by message (compression_mode MESSAGE)" "$work/db3-MESSAGE.txt" || fail "the run does not say MESSAGE"
grep -qF "zstd by file (compression_mode FILE): each file is decompressed into $work/tmp-FILE (TMPDIR) while it is read" \
  "$work/db3-FILE.txt" || fail "the run does not say where FILE's copies go: $(head -3 "$work/db3-FILE.txt")"
ls "$work/db3_FILE" | grep -qx "db3_FILE_0.db3.zstd" || fail "the FILE bag has no db3_FILE_0.db3.zstd: $(ls "$work/db3_FILE")"
echo "ROS 2 .db3 bag: the folder's points and voxels, also zstd-compressed by message and by file"

# `cenote bag info` lists the MCAP's topics with their counts.
"$cenote" bag info "$work/raw-zstd.mcap" >"$work/info.txt" 2>&1 || fail "cenote bag info failed: $(cat "$work/info.txt")"
grep -Eq "/cam0/image_raw +$frames msgs" "$work/info.txt" || fail "bag info: $(cat "$work/info.txt")"
grep -Eq "/odom +295 msgs" "$work/info.txt" || fail "bag info lacks the 295 poses: $(cat "$work/info.txt")"

# Cut short at 60 % of its bytes (no summary, no footer, a partial chunk): the run reads to the cut.
size=$(stat -c %s "$work/raw-zstd.mcap")
head -c $((size * 6 / 10)) "$work/raw-zstd.mcap" >"$work/cut.mcap"
mcap_run cut image_raw
processed=$(json "$work/cut-out/report.json" 'd["frames_processed"]')
[ "$processed" -gt 0 ] && [ "$processed" -lt $frames ] || fail "cut recording: $processed frames processed"
grep -q "source cut short: cut at byte $((size * 6 / 10)) inside the chunk record at byte" "$work/cut.txt" ||
  fail "the cut is not reported: $(grep -i cut "$work/cut.txt")"
echo "MCAP: the folder's map with raw and PNG images, none/zstd/lz4 chunks; a cut recording read to the cut"

# A damaged chunk (tests/io/bag/damage_chunk.py: bytes of an uncompressed chunk's records, of a zstd
# chunk's compressed data): skipped, counted and named in the report; the run goes on, and its points
# are those of the folder without the frames and poses the chunk held (byte for byte).
for variant in "raw-none record" "raw-zstd data"; do
  set -- $variant
  name=bad-$2
  $py "$source_dir/tests/io/bag/damage_chunk.py" "$work/$1.mcap" "$work/$name.mcap" --mode "$2" --euroc "$work/dive" \
    --euroc-out "$work/$name-dive" >"$work/$name.json" || fail "damage_chunk.py $name"
  mcap_run "$name" image_raw
  run "$name-folder" --dataset "$work/$name-dive"
  cmp -s "$work/$name-folder-out/points.ply" "$work/$name-out/points.ply" || fail "$name: points.ply differs from the trimmed folder's"
  [ "$(json "$work/$name-out/report.json" 'd["frames_processed"]')" = "$(json "$work/$name-folder-out/report.json" 'd["frames_processed"]')" ] ||
    fail "$name: frames processed differ from the trimmed folder's"
  [ "$(json "$work/$name-out/report.json" 'd["source"]["damaged_chunks_skipped"]')" = 1 ] || fail "$name: damaged_chunks_skipped not 1"
  skipped=$(json "$work/$name-out/report.json" 'd["source"]["skipped"][0]')
  prefix="$work/$name.mcap: chunk at byte $(json "$work/$name.json" 'd["offset"]'): CRC mismatch: the chunk stores"
  suffix="uncompressed bytes give"
  [ $2 = record ] && prefix="$prefix $(json "$work/$name.json" 'd["stored_crc"]'), its $(json "$work/$name.json" 'd["size"]')" &&
    suffix="$suffix $(json "$work/$name.json" 'd["actual_crc"]')"
  # The counts per topic are those of the Message Index records after the chunk.
  held=$(json "$work/$name.json" 'd["held_text"]')
  case "$skipped" in
    "$prefix "*"$suffix"*"; skipped the chunk ($held)") ;;
    *) fail "$name: skipped '$skipped', expected '$prefix ... $suffix ...; skipped the chunk ($held)'" ;;
  esac
  [ $2 = record ] && [ "$skipped" != "$prefix $suffix; skipped the chunk ($held)" ] &&
    fail "$name: skipped '$skipped', expected '$prefix $suffix; skipped the chunk ($held)'"
done
echo "MCAP: a damaged chunk skipped and named, the other frames as in the folder"
