#!/usr/bin/env bash
# VIO outputs as pose sources of `cenote run`, on files write_vio_outputs.py writes in the systems'
# documented layouts from a simulated dive's ground truth:
# - OKVIS / SVIn2 CSV (IMU poses, detected by its header): T_SC applies, the same points as the EuRoC
#   ground truth it was written from;
# - OpenVINS (TUM rows of the IMU) named with --trajectory-format openvins: the map of the EuRoC ground
#   truth within 1e-4 (its timestamps in seconds are doubles 0.24 us apart near 1.7e9 s, so the
#   interpolation weights differ in the last bits); read as plain TUM the poses are taken as the
#   camera's and the run says so;
# - ORB-SLAM3 TUM rows in nanoseconds: the same points as the same poses in seconds;
# - ORB-SLAM3 keyframes (every 4th frame): keyframe-only processing, said in the report.
# Usage: cli_vio_poses_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../../support/cli_test_lib.sh"
simulate_reef 20 "$work/dive"
/usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/write_vio_outputs.py" "$work/dive" "$work/vio" ||
  fail "write_vio_outputs.py failed"
config="$source_dir/config/default.yaml"
run() {  # run NAME ARGS...: cenote run on the dive into $work/NAME, its stderr in $work/NAME.txt
  local name=$1
  shift
  "$cenote" run --dataset "$work/dive" --config "$config" --out "$work/$name" --map "$work/$name.vdb" "$@" \
    >"$work/$name.txt" 2>&1 || fail "cenote run $name failed: $(tail -5 "$work/$name.txt")"
}
same_map() {  # same_map A B: the maps of runs A and B agree voxel for voxel
  "$cenote" eval map --estimate "$work/$1.vdb" --reference "$work/$2.vdb" --json "$work/$1-$2.json" >/dev/null ||
    fail "cenote eval map $1 $2 failed"
  [ "$(json "$work/$1-$2.json" 'd["agreement"] == 1.0 and d["known_either"] == d["known_both"] > 0')" = True ] ||
    fail "maps of $1 and $2 differ: $(head -c 600 "$work/$1-$2.json")"
}
near_map() {  # near_map A B: the maps of runs A and B agree on all but 1e-4 of the voxels known in either
  "$cenote" eval map --estimate "$work/$1.vdb" --reference "$work/$2.vdb" --json "$work/$1-$2.json" >/dev/null ||
    fail "cenote eval map $1 $2 failed"
  [ "$(json "$work/$1-$2.json" 'd["agreement"] >= 0.9999 and d["known_either"] > 0')" = True ] ||
    fail "maps of $1 and $2 differ: $(head -c 600 "$work/$1-$2.json")"
}

run truth
run okvis --trajectory "$work/vio/okvis.csv"
grep -q "okvis.csv (.* poses, body poses)" "$work/okvis.txt" || fail "OKVIS CSV not read as body poses: $(head -3 "$work/okvis.txt")"
cmp -s "$work/truth/points.ply" "$work/okvis/points.ply" || fail "OKVIS CSV gives other points than the EuRoC ground truth"
same_map okvis truth

run openvins --trajectory "$work/vio/openvins.txt" --trajectory-format openvins
[ "$(json "$work/openvins/report.json" 'd["pose_frame"]')" = body ] || fail "OpenVINS poses not taken as the IMU's"
[ "$(json "$work/openvins/report.json" 'd["frames_processed"]')" = 20 ] || fail "OpenVINS: not every frame processed"
near_map openvins truth
run openvins-as-tum --trajectory "$work/vio/openvins.txt"
grep -q "taken as camera poses" "$work/openvins-as-tum.txt" || fail "plain TUM rows: the assumed frame is not said"

run orbslam3-s --trajectory "$work/dive/groundtruth/cam0.tum" --pose-frame camera
run orbslam3-ns --trajectory "$work/vio/orbslam3_ns.txt" --pose-frame camera
[ "$(json "$work/orbslam3-ns/report.json" 'd["frames_processed"]')" = 20 ] || fail "ns timestamps: not every frame posed"
cmp -s "$work/orbslam3-s/points.ply" "$work/orbslam3-ns/points.ply" || fail "ns timestamps give other points than seconds"

run keyframes --trajectory "$work/vio/orbslam3_keyframes.txt" --pose-frame camera
[ "$(json "$work/keyframes/report.json" 'd["pose_keyframes_only"]')" = 5 ] || fail "keyframe-only source not reported"
[ "$(json "$work/keyframes/report.json" 'd["frames_processed"]')" = 5 ] || fail "not the 5 keyframes processed"
[ "$(json "$work/keyframes/report.json" 'd["frames_skipped"]["no_pose"]')" = 15 ] || fail "15 frames without pose expected"
grep -q "poses: keyframes only (5)" "$work/keyframes.txt" || fail "the run's table does not say keyframes only"
[ "$(json "$work/orbslam3-s/report.json" "'pose_keyframes_only' in d")" = False ] || fail "every-frame poses taken as keyframes"

# Bad input: a CSV without a pose column names it.
sed '1s/q_WS_w/q_WS_W/' "$work/vio/okvis.csv" >"$work/bad.csv"
expect_error 1 "bad.csv:1: the header has no column q_WS_w" run --dataset "$work/dive" --trajectory "$work/bad.csv" \
  --out "$work/x"
echo "VIO pose formats: OKVIS, OpenVINS, ORB-SLAM3 (s, ns, keyframes)"
