#!/usr/bin/env bash
# End-to-end test of `cenote eval`: known answers on generated inputs, JSON names, plots, the HTML
# report, and exit codes with clear messages for missing or malformed input.
#   cli_eval_test.sh CENOTE SOURCE_DIR
set -euo pipefail
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

# json_value FILE KEY: a top-level number of a JSON file.
json_value() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
# near A B TOL: |A - B| <= TOL.
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t) }'; }

/usr/bin/python3 "$source_dir/tests/eval/make_eval_inputs.py" "$work/in"
have_plots=0
/usr/bin/python3 -c "import matplotlib" 2>/dev/null && have_plots=1
plot_args=()
mkdir -p "$work/run"

# Depth: every pixel 0.1 m off, the hole (5 x 5 corner) missing in both.
[[ $have_plots -eq 1 ]] && plot_args=(--plot "$work/run/plots")
"$cenote" eval depth --estimate "$work/in/est" --reference "$work/in/ref" --json "$work/run/depth.json" \
  "${plot_args[@]}" >"$work/stdout" || fail "eval depth: $(cat "$work/stdout")"
grep -q "frames matched *3" "$work/stdout" || fail "depth table: $(cat "$work/stdout")"
grep -q "MAE *0.1 m" "$work/stdout" || fail "depth table MAE: $(cat "$work/stdout")"
near "$(json_value "$work/run/depth.json" mae)" 0.1 1e-5 || fail "mae"
near "$(json_value "$work/run/depth.json" mom)" 0.1 1e-5 || fail "mom"
near "$(json_value "$work/run/depth.json" coverage)" 1 1e-12 || fail "coverage"

# Cloud: a copy shifted by 0.03 m: accuracy = completeness = 0.03, all within 0.1 m, none within 0.02.
"$cenote" eval cloud --source "$work/in/source.pcd" --target "$work/in/target.ply" --json "$work/run/cloud.json" \
  "${plot_args[@]}" >"$work/stdout" || fail "eval cloud: $(cat "$work/stdout")"
for key in accuracy completeness; do
  near "$(json_value "$work/run/cloud.json" $key)" 0.03 1e-6 || fail "$key"
done
for key in precision recall fscore; do
  near "$(json_value "$work/run/cloud.json" $key)" 1 0 || fail "$key"
done
"$cenote" eval cloud --source "$work/in/source.pcd" --target "$work/in/target.ply" --threshold 0.02 \
  --json "$work/cloud2.json" >/dev/null
near "$(json_value "$work/cloud2.json" precision)" 0 0 || fail "precision at 0.02"
# 0.5 m voxels keep one point per grid point.
"$cenote" eval cloud --source "$work/in/source.pcd" --target "$work/in/target.ply" --voxel 0.5 >"$work/stdout"
grep -q "8000 / 8000 after 0.5 m voxels" "$work/stdout" || fail "voxel: $(cat "$work/stdout")"

# Trajectory: EuRoC estimate = reference scaled by 0.5, rotated and moved.
"$cenote" eval traj --estimate "$work/in/est_traj.csv" --reference "$work/in/ref_traj.txt" \
  --json "$work/run/traj.json" "${plot_args[@]}" >"$work/stdout" || fail "eval traj: $(cat "$work/stdout")"
near "$(json_value "$work/run/traj.json" ate_rmse)" 0 1e-6 || fail "sim3 ate_rmse"
near "$(json_value "$work/run/traj.json" scale)" 2 1e-6 || fail "sim3 scale"
"$cenote" eval traj --estimate "$work/in/est_traj.csv" --reference "$work/in/ref_traj.txt" --align se3 \
  --json "$work/se3.json" >/dev/null
awk -v a="$(json_value "$work/se3.json" ate_rmse)" 'BEGIN { exit !(a > 0.5) }' || fail "se3 should not align a scaled copy"

# The JSON names the issue promises.
for pair in depth:mae depth:mom depth:coverage cloud:accuracy cloud:completeness cloud:precision cloud:recall \
  cloud:fscore traj:ate_rmse traj:ate_mean traj:ate_median traj:ate_max; do
  grep -q "\"${pair#*:}\":" "$work/run/${pair%%:*}.json" || fail "key ${pair#*:} missing from ${pair%%:*}.json"
done

if [[ $have_plots -eq 1 ]]; then
  for png in depth_error_histogram depth_error_per_frame cloud_precision_recall cloud_distance_histogram \
    trajectory_top_view trajectory_error; do
    [[ -s $work/run/plots/$png.png ]] || fail "missing plot $png.png"
  done
  ls "$work/run/plots"/depth_error_0*.png >/dev/null || fail "no depth heat map"
else
  echo "note: python3-matplotlib missing, plots not checked"
fi

# Report: a runner-style folder (report.json, depth/), metrics and plots found, images embedded.
mkdir -p "$work/run/depth"
cp "$work/in/est/0001.depth.pfm" "$work/run/depth/0001.depth.pfm"
cat >"$work/run/report.json" <<'JSON'
{"frames_in": 10, "frames_processed": 9, "fps": 12.5,
 "stages": {"stereo": {"median_ms": 30.5, "p95_ms": 41.0}, "fusion": {"median_ms": 4.1, "p95_ms": 5.0}}}
JSON
"$cenote" eval report "$work/run" >"$work/stdout" || fail "eval report: $(cat "$work/stdout")"
html=$work/run/report.html
grep -q "<td>30.5</td>" "$html" || fail "timing table missing"
grep -q "MoM" "$html" || fail "depth metrics missing"
grep -q "ATE RMSE" "$html" || fail "trajectory metrics missing"
grep -q "data:image/png;base64," "$html" || fail "no embedded image"
grep -q "src=\"[^d]" "$html" && fail "report links an external file"
# An empty folder still gives a page that says what is missing.
mkdir "$work/empty"
"$cenote" eval report "$work/empty" >/dev/null || fail "report of an empty folder"
grep -q "No report.json" "$work/empty/report.html" || fail "empty report should say report.json is missing"

# Errors: exit 1 and a message naming the file and the problem.
expect_error 1 "$work/absent: no such directory" eval depth --estimate "$work/absent" --reference "$work/in/ref"
mkdir "$work/other"
cp "$work/in/est/0000.depth.pfm" "$work/other/frame_a.depth.pfm"
expect_error 1 "no image name is in both" eval depth --estimate "$work/in/est" --reference "$work/other"
printf '4&4&1&abc' >"$work/in/ref/0009.png.geometric.bin"
cp "$work/in/est/0000.depth.pfm" "$work/in/est/0009.depth.pfm"
expect_error 1 "0009.png.geometric.bin: COLMAP array is truncated" eval depth --estimate "$work/in/est" \
  --reference "$work/in/ref"
expect_error 1 "absent.ply: no such file" eval cloud --source "$work/absent.ply" --target "$work/in/target.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n' \
  >"$work/short.ply"
expect_error 1 "short.ply: PLY vertex 1 of 2: file ends early" eval cloud --source "$work/short.ply" \
  --target "$work/in/target.ply"
expect_error 1 "threshold -1 m: must be finite and > 0" eval cloud --source "$work/in/source.pcd" \
  --target "$work/in/target.ply" --threshold -1
sed '5s/^\([^ ]*\) [^ ]*/\1 oops/' "$work/in/ref_traj.txt" >"$work/bad_traj.txt"
expect_error 1 "bad_traj.txt:5" eval traj --estimate "$work/in/est_traj.csv" --reference "$work/bad_traj.txt"
awk '{ $1 = $1 + 1000; print }' "$work/in/ref_traj.txt" >"$work/late_traj.txt"
expect_error 1 "only 0 poses associated within 0.02 s" eval traj --estimate "$work/in/est_traj.csv" \
  --reference "$work/late_traj.txt" --reference-format tum
expect_error 1 "no such directory" eval report "$work/absent"
expect_error 1 "absent.vdb" eval map --estimate "$work/absent.vdb" --reference "$work/absent.bt"
printf 'not a map' >"$work/fake.ply"
expect_error 1 "fake.ply" eval map --estimate "$work/fake.ply" --reference "$work/absent.bt"
# Usage errors come from the command-line parser (its own exit code, not 0 or 1).
status=0
"$cenote" eval cloud --source "$work/in/source.pcd" >/dev/null 2>&1 || status=$?
[[ $status -ne 0 && $status -ne 1 ]] || fail "missing --target: exit $status"
echo "cli_eval_test: all checks passed"
