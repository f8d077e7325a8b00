#!/usr/bin/env bash
# End-to-end test of ROS 1 bags in `cenote run` and `cenote bag info`: a simulated dive (`cenote sim`,
# EuRoC layout) converted to bags by ROS's own rosbag (tests/io/bag/euroc_to_bag.py) gives the same
# map as the folder it came from: the same voxels (and the same points.ply, byte for byte) with raw
# or PNG images and uncompressed, bz2 or lz4 chunks, and with the calibration from CameraInfo and
# poses from TF; with JPEG at quality 95 the points and voxels of OpenCV's decoding of the same bytes,
# and at least 99 % of the voxels agreeing within one voxel with the folder's (strictly about 92 %);
# with Bayer mosaics the points of OpenCV's demosaicing and an F-score near the folder's. Jittered
# right stamps with one right image dropped: every other frame paired, one unpaired image counted. A keyframe-only pose topic or TUM
# file gives keyframe-only processing. A bag cut mid-chunk runs and says where it stopped; a damaged chunk is
# stepped over and named. Memory does not grow with the bag. Bad input: the exact messages.
# Usage: cli_bag_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../../support/cli_test_lib.sh"
source "$(dirname "${BASH_SOURCE[0]}")/jpeg_map_check.sh"
py=/usr/bin/python3
to_bag() { $py "$source_dir/tests/io/bag/euroc_to_bag.py" "$work/dive" "$@" || fail "euroc_to_bag.py $*"; }
frames=24

simulate_reef $frames "$work/dive"
run() {  # run NAME ARGS...: cenote run into $work/NAME-out with a map $work/NAME.vdb
  local name=$1
  shift
  "$cenote" run "$@" --out "$work/$name-out" --map "$work/$name.vdb" >"$work/$name.txt" 2>&1 ||
    fail "cenote run ($name) failed: $(tail -5 "$work/$name.txt")"
}
agreement() {  # agreement NAME: the voxel agreement of $work/NAME.vdb with the folder's map
  "$cenote" eval map --estimate "$work/$1.vdb" --reference "$work/euroc.vdb" --json "$work/$1-agreement.json" \
    >/dev/null 2>&1 || fail "cenote eval map ($1) failed"
  json "$work/$1-agreement.json" 'd["agreement"]'
}
calib="$work/dive/mav0/cam0/sensor.yaml"
bag_run() {  # bag_run NAME BAG ARGS...
  local name=$1 bag=$2
  shift 2
  run "$name" --dataset "$bag" --pose-topic /odom --pose-frame body "$@"
}

run euroc --dataset "$work/dive"
[ "$(json "$work/euroc-out/report.json" 'd["frames_processed"]')" = $frames ] || fail "EuRoC run: not every frame processed"

# Raw and PNG images, each compression: the same points and the same voxels.
for variant in "raw none" "raw bz2" "png lz4" "png none"; do
  set -- $variant
  to_bag "$work/$1-$2.bag" --images "$1" --compression "$2"
  bag_run "$1-$2" "$work/$1-$2.bag" --calibration "$calib"
  [ "$(json "$work/$1-$2-out/report.json" 'd["frames_processed"]')" = $frames ] || fail "$1-$2: frames not all processed"
  cmp -s "$work/euroc-out/points.ply" "$work/$1-$2-out/points.ply" || fail "$1-$2: points.ply differs from the folder's"
  a=$(agreement "$1-$2")
  echo "$1 images, $2 chunks: voxel agreement $a"
  [ "$a" = 1.0 ] || fail "$1-$2: voxel agreement $a, expected 1.0 (the same voxels)"
done

# The SVIn2 preset's topics are found without --left/--right. JPEG at quality 95: the bag's images
# decode to OpenCV's pixels (a folder of the same JPEG bytes decoded by cv2.imdecode gives the same
# points and voxels), and the map is the folder's within one voxel. Strictly, voxel for voxel, only
# ~92 % agree: stereo depth noise here (8 px of disparity) is a voxel, and any change of the pixels
# re-draws which voxels of a surface's shell are hit (docs/DATASETS.md: +-1 grey level on 10 % of
# the pixels gives 95 %); the strict numbers are printed and kept from falling. A map off by two
# voxels (poses 10 cm off) fails the within-a-voxel bar, and against ground truth the JPEG run's
# points lose less than 1.5 points of F-score.
to_bag "$work/jpeg.bag" --images jpeg --compression lz4 --decoded-folder "$work/jpeg-pixels"
bag_run jpeg "$work/jpeg.bag" --calibration "$calib"
grep -q "/slave1/image_raw/compressed + /slave2/image_raw/compressed" "$work/jpeg.txt" || fail "svin2 preset not used"
run jpeg-pixels --dataset "$work/jpeg-pixels"
cmp -s "$work/jpeg-pixels-out/points.ply" "$work/jpeg-out/points.ply" || fail "jpeg: points differ from OpenCV's decoding's"
expect_jpeg_map "jpeg q95 images" "$work/jpeg.vdb" "$work/jpeg-pixels.vdb" "$work/euroc.vdb" 0.92 0.955
awk '/^#/ { print; next } { $2 = sprintf("%.9f", $2 + 0.1); print }' "$work/dive/groundtruth/cam0.tum" >"$work/shifted.tum"
run shifted --dataset "$work/dive" --trajectory "$work/shifted.tum" --pose-frame camera
agreement shifted >/dev/null
shifted=$(json "$work/shifted-agreement.json" 'd["agreement_within_voxel"]')
echo "poses 10 cm off: voxel agreement within one voxel $shifted"
$py -c "import sys; sys.exit(0 if $shifted < 0.99 else 1)" || fail "poses 10 cm off: agreement within one voxel $shifted >= 0.99"
for name in euroc jpeg; do
  "$cenote" eval cloud --source "$work/$name-out/points.ply" --target "$work/dive/groundtruth/surface.ply" --threshold 0.05 \
    --json "$work/$name-cloud.json" >/dev/null 2>&1 || fail "cenote eval cloud ($name) failed"
done
f_png=$(json "$work/euroc-cloud.json" 'd["fscore"]')
f_jpeg=$(json "$work/jpeg-cloud.json" 'd["fscore"]')
echo "F-score at 5 cm against the true surface: PNG folder $f_png, JPEG bag $f_jpeg"
$py -c "import sys; sys.exit(0 if $f_jpeg >= $f_png - 0.015 else 1)" || fail "jpeg: F-score $f_jpeg, PNG's $f_png"

# A raw colour camera's Bayer mosaics (bayer_rggb8, made by numpy): the points of OpenCV's Python
# demosaicing of the same mosaics, and against the true surface at most 4 points of F-score below
# the PNG folder's (a mosaic holds a third of the colour samples; 2.4 points here).
to_bag "$work/bayer.bag" --images bayer --decoded-folder "$work/bayer-pixels"
bag_run bayer "$work/bayer.bag" --calibration "$calib"
run bayer-pixels --dataset "$work/bayer-pixels"
cmp -s "$work/bayer-pixels-out/points.ply" "$work/bayer-out/points.ply" || fail "bayer: points differ from OpenCV's demosaicing's"
"$cenote" eval cloud --source "$work/bayer-out/points.ply" --target "$work/dive/groundtruth/surface.ply" --threshold 0.05 \
  --json "$work/bayer-cloud.json" >/dev/null 2>&1 || fail "cenote eval cloud (bayer) failed"
f_bayer=$(json "$work/bayer-cloud.json" 'd["fscore"]')
echo "F-score at 5 cm against the true surface: Bayer bag $f_bayer"
$py -c "import sys; sys.exit(0 if $f_bayer >= $f_png - 0.04 else 1)" || fail "bayer: F-score $f_bayer, PNG's $f_png"

# Calibration from the two CameraInfo topics (K, D, R, P from cv2.stereoRectify), camera poses
# (T_world_body * T_BS, composed by numpy) from TF: >= 99.9 % (1.0 here).
to_bag "$work/info.bag" --images raw --camera-info --poses tf --pose-of camera
run info --dataset "$work/info.bag" --pose-topic /tf --tf-parent world --tf-child cam0
grep -q "CameraInfo /left/camera_info, /right/camera_info" "$work/info.txt" || fail "calibration not from CameraInfo"
a=$(agreement info)
echo "CameraInfo calibration, TF camera poses: voxel agreement $a"
$py -c "import sys; sys.exit(0 if $a >= 0.999 else 1)" || fail "CameraInfo / TF: voxel agreement $a < 0.999"

# Approximate sync: right stamps jittered by up to 3 ms, right image 5 dropped.
to_bag "$work/jitter.bag" --images raw --right-jitter-ms 3 --drop-right 5
bag_run jitter "$work/jitter.bag" --calibration "$calib"
[ "$(json "$work/jitter-out/report.json" 'd["source"]["unpaired_images"]')" = 1 ] || fail "jitter: unpaired images not 1"
[ "$(json "$work/jitter-out/report.json" 'd["frames_in"]')" = $((frames - 1)) ] || fail "jitter: frames_in not $((frames - 1))"

# A keyframe-only pose topic (a VIO's keyframe odometry: the left camera's pose at every 5th image):
# keyframe-only processing, said in the report, with the points of the folder run on the same
# keyframes as a TUM file.
to_bag "$work/keyframes.bag" --images raw --keyframe-poses 5
run keyframes --dataset "$work/keyframes.bag" --pose-topic /odom --pose-frame camera --calibration "$calib"
awk '!/^#/ { if (k++ % 5 == 0) print }' "$work/dive/groundtruth/cam0.tum" >"$work/keyframes.tum"
run keyframes-folder --dataset "$work/dive" --trajectory "$work/keyframes.tum" --pose-frame camera
keyframes=$(( (frames + 4) / 5 ))
for name in keyframes keyframes-folder; do
  [ "$(json "$work/$name-out/report.json" 'd.get("pose_keyframes_only")')" = $keyframes ] || fail "$name: keyframe-only poses not reported"
  [ "$(json "$work/$name-out/report.json" 'd["frames_processed"]')" = $keyframes ] || fail "$name: not the $keyframes keyframes processed"
  [ "$(json "$work/$name-out/report.json" 'd["frames_skipped"]["no_pose"]')" = $((frames - keyframes)) ] ||
    fail "$name: $((frames - keyframes)) frames without pose expected"
done
grep -q "note: the poses are keyframes only ($keyframes): only the frames at a keyframe are processed" "$work/keyframes.txt" ||
  fail "keyframe-only pose topic: no note"
cmp -s "$work/keyframes-folder-out/points.ply" "$work/keyframes-out/points.ply" || fail "keyframes: points differ from the folder's"
# Keyframes at every 2nd image as a TUM file (ORB-SLAM3's KeyFrameTrajectory.txt) for the bag: its
# stamp-paired frames are read once for their header stamps to tell, and only the 12 keyframes are
# processed (interpolating within pose_max_gap_s would pose 23), as in the folder run on the same file.
awk '!/^#/ { if (k++ % 2 == 0) print }' "$work/dive/groundtruth/cam0.tum" >"$work/keyframes2.tum"
run keyframes2-folder --dataset "$work/dive" --trajectory "$work/keyframes2.tum" --pose-frame camera
run keyframes2-bag --dataset "$work/raw-none.bag" --trajectory "$work/keyframes2.tum" --pose-frame camera \
  --calibration "$calib"
for name in keyframes2-folder keyframes2-bag; do
  [ "$(json "$work/$name-out/report.json" 'd.get("pose_keyframes_only")')" = $((frames / 2)) ] ||
    fail "$name: keyframe-only poses not reported"
  [ "$(json "$work/$name-out/report.json" 'd["frames_processed"]')" = $((frames / 2)) ] ||
    fail "$name: $(json "$work/$name-out/report.json" 'd["frames_processed"]') frames processed, not the $((frames / 2)) keyframes"
done
cmp -s "$work/keyframes2-folder-out/points.ply" "$work/keyframes2-bag-out/points.ply" ||
  fail "keyframes2.tum on the bag: points differ from the folder's"
[ "$(json "$work/raw-none-out/report.json" "'pose_keyframes_only' in d")" = False ] || fail "200 Hz poses taken as keyframes"

# A bag cut mid-chunk (the recorder killed): every complete message before the cut, and where.
size=$(stat -c %s "$work/raw-none.bag")
head -c $((size * 3 / 5)) "$work/raw-none.bag" >"$work/cut.bag"
bag_run cut "$work/cut.bag" --calibration "$calib"
truncation=$(json "$work/cut-out/report.json" 'd["source"]["truncation"]')
case "$truncation" in
  "cut at byte $((size * 3 / 5)), inside the chunk at byte "*"complete messages read") ;;
  *) fail "cut bag: truncation '$truncation'" ;;
esac
processed=$(json "$work/cut-out/report.json" 'd["frames_processed"]')
[ "$processed" -gt 0 ] && [ "$processed" -lt $frames ] || fail "cut bag: $processed frames processed"
"$cenote" bag info "$work/cut.bag" >"$work/cut-info.txt" 2>&1 || fail "bag info on the cut bag failed"
grep -qF "cut short:   $truncation" "$work/cut-info.txt" || fail "bag info does not say where the bag was cut"

# A damaged chunk (bytes overwritten inside one holding images): stepped over, named with its
# offset in the report, the frames of the other chunks mapped. rosbag's own index says which
# images the chunk held: the pairs it broke are not in the run, their survivors are unpaired.
read -r chunk lost unpaired < <($py - "$work/raw-bz2.bag" "$work/damaged.bag" <<'PY'
import sys, rosbag
src, out = sys.argv[1], sys.argv[2]
with rosbag.Bag(src) as bag:
    headers = bag._chunk_headers
    def stamps(chunk_pos):
        held = {"/left/image_raw": set(), "/right/image_raw": set()}
        for conn, entries in bag._connection_indexes.items():
            topic = bag._connections[conn].topic
            if topic in held:
                held[topic] |= {e.time.to_nsec() for e in entries if e.chunk_pos == chunk_pos}
        return held
    chunk = next(c for c in bag._chunks[1:] if all(stamps(c.pos).values()))
    held = stamps(chunk.pos)
    data_pos = headers[chunk.pos].data_pos
raw = bytearray(open(src, "rb").read())
raw[data_pos + 40:data_pos + 56] = b"junk" * 4
open(out, "wb").write(raw)
lost = held["/left/image_raw"] | held["/right/image_raw"]
print(chunk.pos, len(lost), len(lost) - len(held["/left/image_raw"] & held["/right/image_raw"]))
PY
) || fail "damaging a chunk failed"
bag_run damaged "$work/damaged.bag" --calibration "$calib"
[ "$(json "$work/damaged-out/report.json" 'd["source"]["damaged_chunks_skipped"]')" = 1 ] || fail "damaged: not one chunk skipped"
[ "$(json "$work/damaged-out/report.json" 'd["frames_in"]')" = $((frames - lost)) ] || fail "damaged: frames_in not $((frames - lost))"
[ "$(json "$work/damaged-out/report.json" 'd["source"]["unpaired_images"]')" = "$unpaired" ] || fail "damaged: unpaired not $unpaired"
[ "$(json "$work/damaged-out/report.json" 'd["source"]["skipped"][0].startswith("bag '"$work"'/damaged.bag, byte '"$chunk"' (chunk): bz2 data are corrupt")')" = True ] ||
  fail "damaged: report does not name the chunk: $(json "$work/damaged-out/report.json" 'd["source"]')"
grep -q "source damaged: bag $work/damaged.bag, byte $chunk (chunk): bz2 data are corrupt" "$work/damaged.txt" ||
  fail "damaged: the run does not say which chunk it skipped"
echo "damaged chunk at byte $chunk: $lost frames lost, $unpaired images unpaired, $((frames - lost)) frames in"

# Bounded memory: a bag five times as long peaks within 10 % of the short one.
"$cenote" sim --scene reef --frames $((5 * frames)) --width 320 --height 240 --quiet --out "$work/long" >/dev/null 2>&1 ||
  fail "cenote sim (long) failed"
$py "$source_dir/tests/io/bag/euroc_to_bag.py" "$work/long" "$work/long.bag" --images png --compression lz4 ||
  fail "euroc_to_bag.py (long)"
for name in png-lz4 long; do  # no map: the map grows with the volume seen, the reading must not
  dive=$work/dive
  [ $name = long ] && dive=$work/long
  "$cenote" run --dataset "$work/$name.bag" --pose-topic /odom --pose-frame body --calibration "$dive/mav0/cam0/sensor.yaml" \
    --out "$work/$name-memory" >/dev/null 2>&1 || fail "cenote run ($name, no map) failed"
done
short_mb=$(json "$work/png-lz4-memory/report.json" 'd["peak_memory_mb"]')
long_mb=$(json "$work/long-memory/report.json" 'd["peak_memory_mb"]')
echo "peak memory: $frames-frame bag $short_mb MiB, $((5 * frames))-frame bag $long_mb MiB"
if [ -n "${CENOTE_SANITIZED:-}" ]; then
  echo "bounded memory not judged: AddressSanitizer's quarantine holds freed memory"
else
  $py -c "import sys; sys.exit(0 if $long_mb <= 1.1 * $short_mb else 1)" ||
    fail "memory grows with the bag: $short_mb MiB for $frames frames, $long_mb MiB for $((5 * frames))"
fi

# bag info: topics, types, counts and rates, compression.
"$cenote" bag info "$work/png-lz4.bag" >"$work/baginfo.txt" 2>&1 || fail "cenote bag info failed"
grep -qE "/odom +[0-9]+ msgs @ 200.0 Hz : nav_msgs/Odometry" "$work/baginfo.txt" || fail "bag info: /odom line: $(cat "$work/baginfo.txt")"
grep -qE "/slave1/image_raw/compressed +$frames msgs @ 15.0 Hz : sensor_msgs/CompressedImage" "$work/baginfo.txt" ||
  fail "bag info: image line: $(cat "$work/baginfo.txt")"
grep -qE "^compression: lz4 \[[0-9]+/[0-9]+ chunks\]" "$work/baginfo.txt" || fail "bag info: compression: $(cat "$work/baginfo.txt")"

# Bad input: the exact messages.
expect_error 1 "error: topic /cam_fl/image_raw is not in $work/raw-none.bag; its image topics: /left/image_raw (sensor_msgs/Image, $frames messages), /right/image_raw (sensor_msgs/Image, $frames messages)" \
  run --dataset "$work/raw-none.bag" --left /cam_fl/image_raw --right /right/image_raw --calibration "$calib" --pose-topic /odom --out "$work/x"
expect_error 1 "error: pose topic /vio/odom is not in $work/raw-none.bag; its pose topics: /odom (nav_msgs/Odometry)" \
  run --dataset "$work/raw-none.bag" --calibration "$calib" --pose-topic /vio/odom --out "$work/x"
expect_error 1 "error: pose topic /left/image_raw in $work/raw-none.bag has type sensor_msgs/Image, not nav_msgs/Odometry, geometry_msgs/PoseStamped, geometry_msgs/TransformStamped or tf2_msgs/TFMessage" \
  run --dataset "$work/raw-none.bag" --calibration "$calib" --pose-topic /left/image_raw --out "$work/x"
expect_error 1 "error: recording $work/raw-none.bag has no CameraInfo topic /left/camera_info for the calibration; give --calibration FILE" \
  run --dataset "$work/raw-none.bag" --pose-topic /odom --out "$work/x"
$py "$source_dir/tests/io/bag/write_test_bags.py" "$work/small" || fail "write_test_bags.py failed"
expect_error 1 "error: topic /cam/float: image encoding 32FC1 is not read; cenote reads mono8/16, bgr8/16, rgb8/16, bgra8/16, rgba8/16, bayer_{rggb,bggr,gbrg,grbg}8/16, yuv422 (uyvy) and yuv422_yuy2 (yuyv)" \
  run --dataset "$work/small/messages.bag" --left /cam/float --right /cam/mono --calibration "$calib" --pose-topic /odom --out "$work/x"
expect_error 1 "error: calibration $calib is for 320x240 images, but those on /cam/mono are 3x2" \
  run --dataset "$work/small/messages.bag" --left /cam/mono --right /cam/bgr --calibration "$calib" --pose-topic /odom --out "$work/x"
expect_error 1 "error: topic /odom in $work/small/messages.bag has type nav_msgs/Odometry, not sensor_msgs/Image or sensor_msgs/CompressedImage" \
  run --dataset "$work/small/messages.bag" --left /odom --right /cam/bgr --calibration "$calib" --pose-topic /odom --out "$work/x"
chunk=$(json "$work/small/expected.json" 'd["zstd.bag"]["first_chunk_pos"]')
expect_error 1 "error: bag $work/small/zstd.bag, byte $chunk (chunk): unknown compression 'zstd' (a ROS 1 bag's chunks are none, bz2 or lz4)" \
  bag info "$work/small/zstd.bag"
echo "cli_bag_test: ok"
