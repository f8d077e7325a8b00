#!/usr/bin/env bash
# End-to-end test of `cenote fuse`: a generated folder fuses, bad input fails with a clear message; a
# `cenote run --write-depth` folder of raw maps fuses into the fused run's points.
#   cli_fuse_test.sh CENOTE MAKE_FUSION_FOLDER
set -euo pipefail
cenote=$1
make_folder=$2
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

intrinsics=$("$make_folder" "$work/in")
[[ -n $intrinsics ]] || fail "no intrinsics printed"
common=(fuse --depth-dir "$work/in/depth" --color-dir "$work/in/color" --intrinsics "$intrinsics")

# A good run: 5 frames, 3 views -> 3 fused reference frames named like their inputs.
"$cenote" "${common[@]}" --trajectory "$work/in/traj.txt" --out "$work/out" --png16 --preview >"$work/stdout" \
  || fail "fuse failed: $(cat "$work/stdout")"
grep -q "fused 3 of 5 frames" "$work/stdout" || fail "unexpected summary: $(cat "$work/stdout")"
for t in 100.500000 101.000000 101.500000; do
  for f in "$t.depth.pfm" "$t.conf.pfm" "$t.depth.png" "$t.preview.png"; do
    [[ -s $work/out/$f ]] || fail "missing output $f"
  done
done
[[ ! -e $work/out/100.000000.depth.pfm ]] || fail "the first frame is never a reference with 3 views"
# Binary PLY: header + 15 bytes per point; most of 3 x 160 x 120 pixels survive.
size=$(stat -c %s "$work/out/points.ply")
((size > 15 * 30000)) || fail "points.ply too small: $size bytes"
head -c 300 "$work/out/points.ply" | grep -qa "format binary_little_endian 1.0" || fail "points.ply header"

# Five views use every frame once as the only reference.
"$cenote" "${common[@]}" --trajectory "$work/in/traj.txt" --out "$work/out5" --views 5 --eps 0.05 >"$work/stdout"
grep -q "fused 1 of 5 frames" "$work/stdout" || fail "5 views: $(cat "$work/stdout")"

# Bad poses and inputs.
sed '3s/^\([^ ]*\) [^ ]*/\1 nan/' "$work/in/traj.txt" >"$work/traj_nan.txt"
expect_error 1 "traj_nan.txt:3: non-finite value" "${common[@]}" --trajectory "$work/traj_nan.txt" --out "$work/o1"
awk 'NR == 4 { $8 = 0.5 } { print }' "$work/in/traj.txt" >"$work/traj_scaled.txt"
expect_error 1 "traj_scaled.txt:4: quaternion (qx qy qz qw) has norm" "${common[@]}" \
  --trajectory "$work/traj_scaled.txt" --out "$work/o2"
grep -v '^101.000000' "$work/in/traj.txt" >"$work/traj_gap.txt"
expect_error 1 "no pose in $work/traj_gap.txt within 0.001 s of t = 101.000000" "${common[@]}" \
  --trajectory "$work/traj_gap.txt" --out "$work/o3"
expect_error 1 "fusion.num_views = 4" "${common[@]}" --trajectory "$work/in/traj.txt" --out "$work/o4" --views 4
expect_error 1 "--intrinsics" fuse --depth-dir "$work/in/depth" --intrinsics 1,2,3 --trajectory "$work/in/traj.txt" \
  --out "$work/o5"
cp -r "$work/in" "$work/small"
{ printf 'Pf\n2 2\n-1\n'; printf '\x00\x00\x80\x3f%.0s' 1 2 3 4; } >"$work/small/depth/101.500000.conf.pfm"
expect_error 1 "101.500000.conf.pfm is 2x2 (or not single-channel) but" fuse --depth-dir "$work/small/depth" \
  --intrinsics "$intrinsics" --trajectory "$work/in/traj.txt" --out "$work/o6" --max-depth 20
rm "$work/small/color/101.000000.png"
expect_error 1 "101.000000.png: no such file" fuse --depth-dir "$work/in/depth" --color-dir "$work/small/color" \
  --intrinsics "$intrinsics" --trajectory "$work/in/traj.txt" --out "$work/o7"
# A `cenote run --write-depth` folder directly (its depth/frames.csv: names, times, intrinsics, poses):
# fusing the raw stereo maps of a run without fusion (--fusion-views 1) gives the fused run's points,
# the same positions bit for bit; the colours come from the run's JPEG images of the rectified left.
"$cenote" sim --scene reef --frames 8 --width 320 --height 240 --quiet --out "$work/dive" >/dev/null 2>&1 ||
  fail "cenote sim failed"
"$cenote" run --dataset "$work/dive" --fusion-views 1 --write-depth --out "$work/raw" >/dev/null 2>&1 || fail "run (raw) failed"
"$cenote" run --dataset "$work/dive" --out "$work/fused" >/dev/null 2>&1 || fail "run (fused) failed"
"$cenote" fuse --depth-dir "$work/raw" --out "$work/refused" >"$work/stdout" || fail "fuse on run's folder failed"
fused=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['frames_fused'])" "$work/fused/report.json")
grep -q "fused $fused of 8 frames" "$work/stdout" || fail "fuse on run's folder: $(cat "$work/stdout"), the run fused $fused"
/usr/bin/python3 - "$work/fused/points.ply" "$work/refused/points.ply" <<'PY' || fail "fuse on run's folder: other points"
import sys
import numpy as np
def read(path):  # a binary little-endian PLY's vertices
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    lines = data[:end].decode().splitlines()
    count = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
    types = {"float": "<f4", "double": "<f8", "uchar": "u1"}
    dtype = np.dtype([(l.split()[2], types[l.split()[1]]) for l in lines if l.startswith("property")])
    return np.frombuffer(data, dtype=dtype, count=count, offset=end)
run, fuse = read(sys.argv[1]), read(sys.argv[2])
assert len(run) == len(fuse) > 100000, (len(run), len(fuse))
for axis in "xyz":
    assert np.array_equal(run[axis], fuse[axis]), axis
colour = np.mean([np.abs(run[c].astype(int) - fuse[c].astype(int)).mean() for c in ("red", "green", "blue")])
assert colour < 4.0, colour  # JPEG at the run's quality
print(f"fuse on run's folder: {len(run)} points at the run's positions, colours {colour:.2f} / 255 apart")
PY
expect_error 1 "is a \`cenote run --write-depth\` output" fuse --depth-dir "$work/raw/depth" --intrinsics "$intrinsics" \
  --out "$work/o8"
expect_error 1 "give --trajectory and --intrinsics" fuse --depth-dir "$work/in/depth" --out "$work/o9"
echo "cli_fuse_test: all checks passed"
