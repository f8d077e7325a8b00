#!/usr/bin/env bash
# End-to-end test of `cenote run` on simulated sequences: exit codes, outputs, report.json, bad
# input, and bounded memory (a 300-frame run peaks within 10 % of a 60-frame run).
# Usage: cli_run_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

# Small frames keep the test short; the memory claim does not depend on the image size.
simulate_reef 300 "$work/long"
simulate_reef 60 "$work/short"

for run in short long; do
  if ! "$cenote" run --dataset "$work/$run" --config "$source_dir/config/default.yaml" --out "$work/$run-out" \
      >"$work/$run.txt" 2>&1; then
    fail "cenote run on the $run sequence failed: $(tail -5 "$work/$run.txt")"
  fi
done
[ -s "$work/long-out/points.ply" ] || fail "no points.ply"
[ -s "$work/long-out/report.json" ] || fail "no report.json"
if [ -s "$work/long-out/report.json" ] && [ -s "$work/short-out/report.json" ]; then
  [ "$(json "$work/long-out/report.json" 'd["frames_processed"]')" = 300 ] || fail "300 frames not all processed"
  [ "$(json "$work/short-out/report.json" 'd["frames_in"]')" = 60 ] || fail "frames_in of the short run is not 60"
  for key in fps stages peak_memory_mb; do
    [ "$(json "$work/long-out/report.json" "'$key' in d")" = True ] || fail "report.json lacks $key"
  done
  short_mb=$(json "$work/short-out/report.json" 'd["peak_memory_mb"]')
  long_mb=$(json "$work/long-out/report.json" 'd["peak_memory_mb"]')
  echo "peak memory: 60 frames $short_mb MiB, 300 frames $long_mb MiB"
  if [ -n "${CENOTE_SANITIZED:-}" ]; then
    echo "bounded memory not judged: AddressSanitizer's quarantine holds freed memory"
  else
    /usr/bin/python3 -c "import sys; sys.exit(0 if $long_mb <= 1.1 * $short_mb else 1)" ||
      fail "memory grows with the sequence: $short_mb MiB for 60 frames, $long_mb MiB for 300"
  fi
fi
grep -q "stereo" "$work/long.txt" || fail "no timing table printed"

# Bad input: a clear message and a non-zero exit, nothing half-written.
expect_error 1 "no such folder" run --dataset "$work/absent" --out "$work/x"
mkdir -p "$work/empty"
expect_error 1 "unknown layout" run --dataset "$work/empty" --out "$work/x"
printf '0 0 0 0 0 0 0 1\nbroken line\n' >"$work/bad.tum"
expect_error 1 "bad.tum:2:" run --dataset "$work/short" --trajectory "$work/bad.tum" --out "$work/x"
printf 'run:\n  queue_dept: 2\n' >"$work/typo.yaml"
expect_error 1 "run.queue_dept" run --dataset "$work/short" --config "$work/typo.yaml" --out "$work/x"
# Poses that miss every frame: all skipped and counted, none guessed.
printf '1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n' >"$work/elsewhere.tum"
if "$cenote" run --dataset "$work/short" --trajectory "$work/elsewhere.tum" --out "$work/none" >/dev/null 2>&1; then
  [ "$(json "$work/none/report.json" 'd["frames_skipped"]["no_pose"]')" = 60 ] || fail "frames without pose not counted"
else
  fail "a run whose poses miss every frame should still finish"
fi

# Poses on real-like KITTI: a sequence written by hand from the odometry devkit's format (calib.txt
# rows of sequence 00, times.txt about 0.1036 s apart with jitter, poses/00.txt of camera 0), 20
# colour frames. The poses file named explicitly must give what the default layout gives: every
# frame posed, the same points (raw stereo points, --fusion-views 1: each placed by its frame's pose).
/usr/bin/python3 - "$work/kitti" <<'PY'
import math, os, random, shutil, struct, sys, zlib
root = sys.argv[1]
seq = os.path.join(root, "sequences", "00")
for d in ("image_2", "image_3"):
    os.makedirs(os.path.join(seq, d), exist_ok=True)
os.makedirs(os.path.join(root, "poses"), exist_ok=True)
def png(path, w, h, rows):
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                           + chunk(b"IDAT", zlib.compress(b"".join(b"\x00" + r for r in rows), 1)) + chunk(b"IEND", b""))
random.seed(5)
w, h, shift = 1241, 376, 100  # disparity 100 px: 3.8 m, inside fusion.max_depth_m
base = [random.randbytes(3 * (w + shift)) for _ in range(h)]
png(os.path.join(seq, "image_2", "000000.png"), w, h, [r[3 * shift:] for r in base])
png(os.path.join(seq, "image_3", "000000.png"), w, h, [r[:3 * w] for r in base])
with open(os.path.join(seq, "calib.txt"), "w") as f:
    f.write("P0: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 0.000000000000e+00 0.000000000000e+00 7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n")
    f.write("P1: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.861448000000e+02 0.000000000000e+00 7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n")
    f.write("P2: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 4.538225000000e+01 0.000000000000e+00 7.188560000000e+02 1.852157000000e+02 -1.130887000000e-01 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 3.779761000000e-03\n")
    f.write("P3: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.372877000000e+02 0.000000000000e+00 7.188560000000e+02 1.852157000000e+02 2.369057000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 4.915215000000e-03\n")
with open(os.path.join(seq, "times.txt"), "w") as times, open(os.path.join(root, "poses", "00.txt"), "w") as poses:
    for i in range(20):
        t = 0.0 if i == 0 else 0.1036 * i + 0.0004 * math.sin(1.7 * i)
        times.write("%.6e\n" % t)
        a = 0.2 * t  # turning about y, driving 8.5 m/s along z
        poses.write(" ".join("%.9e" % v for v in (math.cos(a), 0, math.sin(a), 0.3 * t * t,
                                                   0, 1, 0, 0, -math.sin(a), 0, math.cos(a), 8.5 * t)) + "\n")
for i in range(1, 20):
    for d in ("image_2", "image_3"):
        shutil.copy(os.path.join(seq, d, "000000.png"), os.path.join(seq, d, "%06d.png" % i))
PY
kitti_seq="$work/kitti/sequences/00"
"$cenote" run --dataset "$kitti_seq" --fusion-views 1 --out "$work/kitti-default" >"$work/kitti-default.txt" 2>&1 ||
  fail "cenote run on the KITTI-like sequence failed: $(tail -3 "$work/kitti-default.txt")"
"$cenote" run --dataset "$kitti_seq" --fusion-views 1 --format kitti --trajectory "$work/kitti/poses/00.txt" --out "$work/kitti-explicit" \
  >"$work/kitti-explicit.txt" 2>&1 || fail "cenote run --trajectory poses/00.txt failed: $(tail -3 "$work/kitti-explicit.txt")"
for run in default explicit; do
  skipped=$(json "$work/kitti-$run/report.json" 'd["frames_skipped"]["no_pose"]')
  [ "$skipped" = 0 ] || fail "KITTI-like sequence, $run poses: $skipped of 20 frames skipped without pose"
  [ "$(json "$work/kitti-$run/report.json" 'd["frames_processed"]')" = 20 ] || fail "KITTI-like, $run: not 20 frames processed"
  [ "$(json "$work/kitti-$run/report.json" 'd["pose_frame"]')" = body ] || fail "KITTI-like, $run: poses not taken as camera 0's"
done
[ "$(json "$work/kitti-default/report.json" 'd["points_written"] > 1000')" = True ] || fail "KITTI-like: no points"
cmp -s "$work/kitti-default/points.ply" "$work/kitti-explicit/points.ply" ||
  fail "KITTI-like: the explicit poses file gives other points than the default layout"
# Times of another clock for the same poses: --trajectory-times replaces times.txt (every frame missed).
awk '{ printf "%.6f\n", $1 + 100.0 }' "$kitti_seq/times.txt" >"$work/kitti/times_later.txt"
"$cenote" run --dataset "$kitti_seq" --trajectory "$work/kitti/poses/00.txt" --trajectory-times "$work/kitti/times_later.txt" \
  --out "$work/kitti-later" >/dev/null 2>&1 || fail "cenote run --trajectory-times failed"
[ "$(json "$work/kitti-later/report.json" 'd["frames_skipped"]["no_pose"]')" = 20 ] || fail "--trajectory-times not used"
expect_error 1 "KITTI poses carry no timestamps and this dataset has no times.txt; give them with --trajectory-times FILE" \
  run --dataset "$work/short" --trajectory "$work/kitti/poses/00.txt" --out "$work/x"

# A TUM file on a dataset with extrinsics: which frame was assumed is said in the first lines and
# in report.json; --pose-frame body says it, and nothing is assumed.
"$cenote" run --dataset "$work/short" --trajectory "$work/elsewhere.tum" --out "$work/tum-auto" >"$work/tum-auto.txt" 2>&1 ||
  fail "cenote run with a TUM file failed"
head -3 "$work/tum-auto.txt" | grep -qF "note: poses of $work/elsewhere.tum taken as camera poses: a tum file does not say which frame it describes" ||
  fail "no note on the pose frame assumed in the first lines: $(head -3 "$work/tum-auto.txt")"
grep -qF "pass --pose-frame body if they are body (IMU) poses" "$work/tum-auto.txt" || fail "no --pose-frame hint"
[ "$(json "$work/tum-auto/report.json" 'd["pose_frame"]')" = camera ] || fail "report.json: pose_frame is not camera"
[ "$(json "$work/tum-auto/report.json" 'd["pose_frame_assumed"]')" = True ] || fail "report.json: pose_frame_assumed is not true"
"$cenote" run --dataset "$work/short" --trajectory "$work/elsewhere.tum" --pose-frame body --out "$work/tum-body" \
  >"$work/tum-body.txt" 2>&1 || fail "cenote run --pose-frame body failed"
! grep -q "^note:" "$work/tum-body.txt" || fail "a note although --pose-frame body was given"
[ "$(json "$work/tum-body/report.json" 'd["pose_frame_assumed"]')" = False ] || fail "report.json: assumed with --pose-frame body"

echo "cli_run_test: all checks passed"
