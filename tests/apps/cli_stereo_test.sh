#!/usr/bin/env bash
# End-to-end test of `cenote stereo`: real image files in, PFM/PNG files out, exit codes and error
# messages for bad input. Usage: cli_stereo_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

# A textured pair written by the test itself: disparity 7 px everywhere.
python_png() {
  /usr/bin/python3 - "$@" <<'PY'
import sys, zlib, struct, random
def png(path, w, h, shift):
    random.seed(3)
    base = [[random.randrange(256) for _ in range(w + 16)] for _ in range(h)]
    rows = b"".join(b"\x00" + bytes(base[y][x + shift] for x in range(w)) for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) \
        + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    open(path, "wb").write(data)
png(sys.argv[1], 120, 80, 0)   # left: pixel x shows base[x]
png(sys.argv[2], 120, 80, 7)   # right: pixel x - 7 shows base[x] too
png(sys.argv[3], 120, 79, 7)   # a right image one row short
PY
}
python_png "$work/left.png" "$work/right.png" "$work/short.png"

# 1. A pair in, every output written, timing printed.
if "$cenote" stereo --left "$work/left.png" --right "$work/right.png" --disparities 16 \
    --out-disparity "$work/d.pfm" --out-confidence "$work/c.pfm" --out-preview "$work/p.png" \
    --out-depth "$work/z.pfm" --focal-px 100 --baseline-m 0.1 --repeat 3 >"$work/run.txt" 2>&1; then
  grep -q '^stereo_ms_median=[0-9.]*$' "$work/run.txt" || fail "no stereo_ms_median line: $(cat "$work/run.txt")"
  for f in d.pfm c.pfm p.png z.pfm; do [ -s "$work/$f" ] || fail "missing output $f"; done
  head -c 3 "$work/d.pfm" | grep -q "Pf" || fail "disparity is not a PFM file"
  # The disparity at the image centre is 7 and the depth f b / d = 100 * 0.1 / 7.
  /usr/bin/python3 - "$work/d.pfm" "$work/z.pfm" <<'PY' || fail "disparity or depth value wrong"
import struct, sys
def value(path, x, y):
    data = open(path, "rb").read()
    lines = data.split(b"\n", 3)
    w, h = map(int, lines[1].split())
    row = h - 1 - y
    return struct.unpack_from("<f", lines[3], (row * w + x) * 4)[0]
d, z = value(sys.argv[1], 60, 40), value(sys.argv[2], 60, 40)
assert abs(d - 7.0) < 0.25, d
assert abs(z - 10.0 / d) < 1e-4, (z, d)
PY
else
  fail "cenote stereo on a valid pair failed: $(cat "$work/run.txt")"
fi

# 2. Bad input: clear messages, non-zero exit.
expect_error 1 "no such file" stereo --left "$work/missing.png" --right "$work/right.png" --out-disparity "$work/x.pfm"
expect_error 1 "is 120x79 but left image" stereo --left "$work/left.png" --right "$work/short.png" --out-disparity "$work/x.pfm"
echo "not an image" >"$work/text.png"
expect_error 1 "not a readable image" stereo --left "$work/text.png" --right "$work/right.png" --out-disparity "$work/x.pfm"
expect_error 1 "stereo.num_disparities = 100" stereo --left "$work/left.png" --right "$work/right.png" --disparities 100 --out-disparity "$work/x.pfm"
expect_error 1 "--out-depth needs --calib" stereo --left "$work/left.png" --right "$work/right.png" --out-disparity "$work/x.pfm" --out-depth "$work/z.pfm"
echo "image_width: 10" >"$work/calib.yaml"
expect_error 1 "calib.yaml" stereo --left "$work/left.png" --right "$work/right.png" --calib "$work/calib.yaml" --out-disparity "$work/x.pfm"
printf 'stereo:\n  window_sise: 3\n' >"$work/config.yaml"
expect_error 1 "unknown configuration key(s): stereo.window_sise" stereo --left "$work/left.png" --right "$work/right.png" --config "$work/config.yaml" --out-disparity "$work/x.pfm"

# 3. One set of defaults: no --config gives what config/default.yaml gives (left-right check and
#    truncated columns included), byte for byte.
"$cenote" stereo --left "$work/left.png" --right "$work/right.png" --disparities 16 --out-disparity "$work/plain.pfm" \
  >/dev/null 2>&1 || fail "stereo without --config failed"
"$cenote" stereo --left "$work/left.png" --right "$work/right.png" --disparities 16 --out-disparity "$work/file.pfm" \
  --config "$source_dir/config/default.yaml" >/dev/null 2>&1 || fail "stereo with config/default.yaml failed"
cmp -s "$work/plain.pfm" "$work/file.pfm" || fail "stereo without --config differs from --config config/default.yaml"

# 4. Every calibration layout the runner reads, from the file alone, written from the formats' docs:
#    the 120x80 pair above, f = 100 px, baseline 0.1 m, so depth = 100 * 0.1 / 7 m at the centre.
depth_at_centre() {
  /usr/bin/python3 - "$1" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
lines = data.split(b"\n", 3)
w, h = map(int, lines[1].split())
print(struct.unpack_from("<f", lines[3], ((h - 1 - 40) * w + 60) * 4)[0])
PY
}
#    KITTI odometry calib.txt: rectified 3x4 projection rows P0..P3 (P1 = K [I | (-b, 0, 0)]).
mkdir -p "$work/kitti"
{
  echo "P0: 1.000000e+02 0.000000e+00 6.000000e+01 0.000000e+00 0.000000e+00 1.000000e+02 4.000000e+01 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00"
  echo "P1: 1.000000e+02 0.000000e+00 6.000000e+01 -1.000000e+01 0.000000e+00 1.000000e+02 4.000000e+01 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00"
  echo "P2: 1.000000e+02 0.000000e+00 6.000000e+01 0.000000e+00 0.000000e+00 1.000000e+02 4.000000e+01 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00"
  echo "P3: 1.000000e+02 0.000000e+00 6.000000e+01 -1.000000e+01 0.000000e+00 1.000000e+02 4.000000e+01 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00"
  echo "Tr: 1 0 0 0 0 1 0 0 0 0 1 0"
} >"$work/kitti/calib.txt"
"$cenote" stereo --left "$work/left.png" --right "$work/right.png" --disparities 16 --calib "$work/kitti/calib.txt" \
  --out-disparity "$work/k.pfm" --out-depth "$work/kz.pfm" >"$work/kitti.txt" 2>&1 ||
  fail "stereo --calib calib.txt (KITTI) failed: $(cat "$work/kitti.txt")"
/usr/bin/python3 -c "import sys; z = float(sys.argv[1]); sys.exit(0 if abs(z - 10.0 / 7.0) < 0.05 else 1)" \
  "$(depth_at_centre "$work/kz.pfm")" || fail "KITTI calib.txt: depth $(depth_at_centre "$work/kz.pfm") m, expected 1.43"
#    EuRoC sensor.yaml: T_BS (camera to body, 4x4 row-major), intrinsics [fu, fv, cu, cv], resolution
#    [w, h], radial-tangential distortion; the right camera 0.1 m along the left camera's x.
mkdir -p "$work/mav0/cam0" "$work/mav0/cam1"
for cam in 0 1; do
  x=$([ $cam = 0 ] && echo 0.0 || echo 0.1)
  cat >"$work/mav0/cam$cam/sensor.yaml" <<YAML
%YAML:1.0
sensor_type: camera
comment: cam$cam, written by hand
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, $x, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [120, 80]
camera_model: pinhole
intrinsics: [100.0, 100.0, 59.5, 39.5] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [0.0, 0.0, 0.0, 0.0]
YAML
done
"$cenote" stereo --left "$work/left.png" --right "$work/right.png" --disparities 16 --calib "$work/mav0/cam0/sensor.yaml" \
  --out-disparity "$work/e.pfm" --out-depth "$work/ez.pfm" >"$work/euroc.txt" 2>&1 ||
  fail "stereo --calib mav0/cam0/sensor.yaml (EuRoC) failed: $(cat "$work/euroc.txt")"
/usr/bin/python3 -c "import sys; z = float(sys.argv[1]); sys.exit(0 if abs(z - 10.0 / 7.0) < 0.05 else 1)" \
  "$(depth_at_centre "$work/ez.pfm")" || fail "EuRoC sensor.yaml: depth $(depth_at_centre "$work/ez.pfm") m, expected 1.43"
expect_error 1 "cam1/sensor.yaml: an EuRoC / Kalibr sensor.yaml describes one camera; give the left camera's" stereo --left "$work/left.png" \
  --right "$work/right.png" --calib "$work/mav0/cam1/sensor.yaml" --out-disparity "$work/x.pfm"

# 6. A pair of a dataset (`--dataset X --frame N`), opened as `cenote run` opens it: a simulated dive
#    converted to ROS 1 bags by ROS's own rosbag gives the same disparity, byte for byte, as frame 2's
#    PNG files of the folder with its calibration file; so do the folder itself and a bag of PNG
#    CompressedImages calibrated by its CameraInfo topics alone (cv2.stereoRectify's K, D, R, P).
simulate_reef 6 "$work/dive"
to_bag() { /usr/bin/python3 "$source_dir/tests/io/bag/euroc_to_bag.py" "$work/dive" "$@" || fail "euroc_to_bag.py $*"; }
to_bag "$work/raw.bag" --images raw
to_bag "$work/info.bag" --images png --camera-info
frame2=$(ls "$work/dive/mav0/cam0/data" | sort | sed -n 3p)
frame1=$(ls "$work/dive/mav0/cam0/data" | sort | sed -n 2p)
sensor="$work/dive/mav0/cam0/sensor.yaml"
stereo_of() {  # stereo_of OUT ARGS...: cenote stereo ARGS --out-disparity OUT, or fail
  local out=$1
  shift
  "$cenote" stereo "$@" --out-disparity "$out" >"$work/ds.txt" 2>&1 || fail "stereo $* failed: $(cat "$work/ds.txt")"
}
stereo_of "$work/files2.pfm" --left "$work/dive/mav0/cam0/data/$frame2" --right "$work/dive/mav0/cam1/data/$frame2" --calib "$sensor"
stereo_of "$work/files1.pfm" --left "$work/dive/mav0/cam0/data/$frame1" --right "$work/dive/mav0/cam1/data/$frame1" --calib "$sensor"
cmp -s "$work/files1.pfm" "$work/files2.pfm" && fail "frames 1 and 2 of the dive give the same disparity"
stereo_of "$work/bag2.pfm" --dataset "$work/raw.bag" --frame 2 --calib "$sensor"
cmp "$work/bag2.pfm" "$work/files2.pfm" || fail "stereo --dataset raw.bag --frame 2 differs from frame 2's files"
stereo_of "$work/topics2.pfm" --dataset "$work/raw.bag" --frame 2 --left-topic /left/image_raw \
  --right-topic /right/image_raw --calibration "$sensor"
cmp "$work/topics2.pfm" "$work/files2.pfm" || fail "stereo --dataset raw.bag --left-topic ... --frame 2 differs"
stereo_of "$work/folder2.pfm" --dataset "$work/dive" --frame 2
cmp "$work/folder2.pfm" "$work/files2.pfm" || fail "stereo --dataset <EuRoC folder> --frame 2 differs from its files"
stereo_of "$work/info2.pfm" --dataset "$work/info.bag" --frame 2
cmp "$work/info2.pfm" "$work/files2.pfm" || fail "stereo --dataset info.bag (CameraInfo) --frame 2 differs"
#    Bad input: a frame past the end names the count; options that do not go together.
expect_error 1 "--frame 6: $work/raw.bag has 6 stereo pairs (frames 0..5)" stereo --dataset "$work/raw.bag" --frame 6 \
  --calib "$sensor" --out-disparity "$work/x.pfm"
expect_error 1 "--frame 9: $work/dive has 6 stereo pairs (frames 0..5)" stereo --dataset "$work/dive" --frame 9 --out-disparity "$work/x.pfm"
expect_error 1 "has no CameraInfo topic /left/camera_info" stereo --dataset "$work/raw.bag" --frame 0 --out-disparity "$work/x.pfm"
expect_error 1 "--left-topic is for recordings (.bag, .mcap, a ROS 2 bag); $work/dive is a folder" stereo --dataset "$work/dive" \
  --frame 0 --left-topic /left/image_raw --out-disparity "$work/x.pfm"
expect_error 1 "stereo: --dataset needs --frame N" stereo --dataset "$work/dive" --out-disparity "$work/x.pfm"
expect_error 1 "stereo: give --left/--right images or --dataset, not both" stereo --dataset "$work/dive" --frame 0 \
  --left "$work/left.png" --out-disparity "$work/x.pfm"
expect_error 1 "stereo: give --left and --right images, or --dataset and --frame" stereo --left "$work/left.png" --out-disparity "$work/x.pfm"
expect_error 1 "stereo: --frame needs --dataset" stereo --left "$work/left.png" --right "$work/right.png" --frame 0 --out-disparity "$work/x.pfm"

# 5. `cenote calibrate --help` shows the board defaults.
"$cenote" calibrate --help >"$work/calibrate_help.txt" 2>&1
# (CLI11 prints a default as TYPE=VALUE: `--board TEXT=9x6`.)
for option in '--board [A-Z:]*=9x6' '--square [A-Z:]*=0.025' '--left-prefix [A-Z:]*=left' '--right-prefix [A-Z:]*=right'; do
  grep -qE -- "$option" "$work/calibrate_help.txt" || fail "calibrate --help: no $option in: $(cat "$work/calibrate_help.txt")"
done

echo "cli_stereo_test: all checks passed"
