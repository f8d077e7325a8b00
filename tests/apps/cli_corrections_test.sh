#!/usr/bin/env bash
# End-to-end test of loop-closure corrections: `cenote sim --drift` writes a dive with a drifting
# VIO and its loop closures; `cenote run` maps it three times: with the true trajectory (the
# reference), with the VIO's live poses, and with them and --corrections. The corrected map must
# agree with the reference in at least 99 % of the voxels known in either; the drifted map's
# agreement is printed beside it and must be lower; the map corrected with map.correction_move:
# resample is printed too and must beat the drifted one. Fusion off (--fusion-views 1): the stereo
# points are then the same in all three runs, and the maps differ by their poses only.
#   cli_corrections_test.sh CENOTE
set -euo pipefail
cenote=$1
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

cat >"$work/sim.yaml" <<'YAML'
sim:
  drift_position_m_per_sqrt_s: 0.1
  drift_yaw_deg_per_sqrt_s: 1.0
  loop_closure_period_s: 1.5
  loop_closure_residual: 0.005
YAML
dive=$work/dive
"$cenote" sim --scene cave --frames 46 --width 320 --height 240 --drift --config "$work/sim.yaml" --out "$dive" \
  --quiet >/dev/null || fail "sim --drift failed"
# 46 frames at 15 Hz: loop closures at the first frames at or after 1.5 s and 3 s (frames 23 and 45, the
# last: every frame is corrected in the end).
[[ $(grep -vc '^#' "$dive/vio_trajectory.tum") -eq 46 ]] || fail "vio_trajectory.tum rows"
[[ $(ls "$dive/loop_closures" | tr '\n' ' ') == "1700000001.533333.tum 1700000003.000000.tum " ]] \
  || fail "loop closures: $(ls "$dive/loop_closures")"
[[ $(grep -vc '^#' "$dive/loop_closures/1700000003.000000.tum") -eq 46 ]] || fail "loop closure rows"

run() {
  "$cenote" run --dataset "$dive" --fusion-views 1 "$@" >"$work/run.out" 2>"$work/run.err" \
    || fail "run $*: $(cat "$work/run.err")"
}
run --out "$work/truth" --map "$work/truth.vdb"
run --out "$work/drifted" --trajectory "$dive/vio_trajectory.tum" --pose-frame camera --map "$work/drifted.vdb"
run --out "$work/corrected" --trajectory "$dive/vio_trajectory.tum" --pose-frame camera \
  --corrections "$dive/loop_closures" --map "$work/corrected.vdb"
grep -q "corrections: 2 of 2 events applied" "$work/run.out" || fail "corrections line: $(cat "$work/run.out")"

agreement() {
  "$cenote" eval map --estimate "$1" --reference "$work/truth.vdb" --json "$work/agreement.json" >/dev/null \
    || fail "eval map $1"
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["agreement"])' "$work/agreement.json"
}
drifted=$(agreement "$work/drifted.vdb")
corrected=$(agreement "$work/corrected.vdb")
echo "agreement with the map from the true poses: drifted $drifted, corrected $corrected"
python3 -c 'import sys; d, c = map(float, sys.argv[1:]); sys.exit(0 if c >= 0.99 and d < c else 1)' "$drifted" \
  "$corrected" || fail "corrected agreement $corrected (must be >= 0.99), drifted $drifted (must be lower)"

# map.correction_move: resample (the frames' stored updates moved rigidly, docs/CORRECTIONS.md): this
# dive's 320x240 stereo leaves ragged free space, which the resampling gets wrong at its every edge:
# printed beside the march's, and better than the drifted map.
printf 'map:\n  correction_move: resample\n' >"$work/resample.yaml"
run --out "$work/resampled" --config "$work/resample.yaml" --trajectory "$dive/vio_trajectory.tum" --pose-frame camera \
  --corrections "$dive/loop_closures" --map "$work/resampled.vdb"
resampled=$(agreement "$work/resampled.vdb")
echo "agreement with the map from the true poses, resampled: $resampled"
python3 -c 'import sys; d, r = map(float, sys.argv[1:]); sys.exit(0 if d < r else 1)' "$drifted" "$resampled" \
  || fail "resampled agreement $resampled (must be above the drifted map's $drifted)"

# SVIn2's pose-graph file (tests/support/write_svin_loop_path.py writes it from the last event, the IMU's
# poses): one event at its last keyframe, the same corrected poses as the folder's last event, which
# gives every frame its pose: the same map as the folder's two events.
python3 "$(dirname "${BASH_SOURCE[0]}")/../support/write_svin_loop_path.py" "$dive/loop_closures/1700000003.000000.tum" \
  "$dive" "$work/svin_loop.txt" || fail "write_svin_loop_path.py"
run --out "$work/svin" --trajectory "$dive/vio_trajectory.tum" --pose-frame camera \
  --corrections "$work/svin_loop.txt" --map "$work/svin.vdb"
grep -q "corrections: 1 of 1 events applied" "$work/run.out" || fail "SVIn2 corrections line: $(cat "$work/run.out")"
"$cenote" eval map --estimate "$work/svin.vdb" --reference "$work/corrected.vdb" --json "$work/svin.json" >/dev/null \
  || fail "eval map svin"
svin=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["agreement"])' "$work/svin.json")
echo "agreement of the SVIn2-corrected map with the folder-corrected map: $svin"
python3 -c 'import sys; sys.exit(0 if float(sys.argv[1]) == 1.0 else 1)' "$svin" \
  || fail "SVIn2-corrected map agrees with the folder-corrected one in $svin (must be 1: the same map)"
: >"$work/empty_svin.txt"
expect_error 1 "corrections $work/empty_svin.txt: no keyframe in SVIn2's pose-graph file" run --dataset "$dive" --out "$work/bad" \
  --map "$work/bad.vdb" --corrections "$work/empty_svin.txt"

expect_error 1 "corrections $work/nowhere: no such folder or file" run --dataset "$dive" --out "$work/bad" --map "$work/bad.vdb" \
  --corrections "$work/nowhere"
expect_error 1 "--corrections $dive/loop_closures needs --map" run --dataset "$dive" --out "$work/bad" \
  --corrections "$dive/loop_closures"
echo "cli_corrections_test: ok"
