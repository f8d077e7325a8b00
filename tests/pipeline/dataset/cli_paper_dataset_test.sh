#!/usr/bin/env bash
# The reference paper's layout as a `cenote run --dataset`: a simulated dive (`cenote sim`, EuRoC layout)
# rewritten in the paper's layout by euroc_to_paper.py (OpenCV's FileStorage writes intrinsics.yaml, with
# the baseline and T in millimetres, or laid out as the paper's repository has it) must give the same points and the same map, voxel for voxel, as the
# EuRoC folder it came from with the same camera poses; `cenote eval cloud --target DATASET` takes its
# colmap.ply; bad input gets a clear error.
# Usage: cli_paper_dataset_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../../support/cli_test_lib.sh"

"$cenote" sim --scene reef --frames 20 --width 320 --height 240 --k1 -0.05 --quiet --out "$work/euroc" >/dev/null 2>&1 ||
  fail "cenote sim failed"
/usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/euroc_to_paper.py" "$work/euroc" "$work/euroc/groundtruth/cam0.tum" \
  "$work/paper" || fail "euroc_to_paper.py failed"

config="$source_dir/config/default.yaml"
"$cenote" run --dataset "$work/euroc" --trajectory "$work/euroc/groundtruth/cam0.tum" --pose-frame camera \
  --config "$config" --out "$work/euroc-out" --map "$work/euroc.vdb" >"$work/euroc.txt" 2>&1 ||
  fail "cenote run on the EuRoC folder failed: $(tail -5 "$work/euroc.txt")"
"$cenote" run --dataset "$work/paper" --config "$config" --out "$work/paper-out" --map "$work/paper.vdb" \
  >"$work/paper.txt" 2>&1 || fail "cenote run on the paper layout failed: $(tail -5 "$work/paper.txt")"
grep -q "paper layout $work/paper: 20 stereo frames" "$work/paper.txt" || fail "not read as the paper layout: $(head -2 "$work/paper.txt")"
[ "$(json "$work/paper-out/report.json" 'd["frames_processed"]')" = 20 ] || fail "not every frame processed"
cmp -s "$work/euroc-out/points.ply" "$work/paper-out/points.ply" || fail "points.ply differs from the EuRoC run's"
"$cenote" eval map --estimate "$work/paper.vdb" --reference "$work/euroc.vdb" --json "$work/map.json" >/dev/null ||
  fail "cenote eval map failed"
[ "$(json "$work/map.json" 'd["known_either"] == d["known_both"] > 0')" = True ] || fail "known voxels differ"
[ "$(json "$work/map.json" 'd["occupied_estimate"] == d["occupied_reference"] > 0')" = True ] || fail "occupied voxels differ"
[ "$(json "$work/map.json" 'd["agreement"]')" = 1.0 ] || fail "maps disagree: $(cat "$work/map.json")"

# intrinsics.yaml as the paper's own repository lays it out (left/right mappings of K and D,
# size: [w, h], T in metres): the same points.
/usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/euroc_to_paper.py" "$work/euroc" "$work/euroc/groundtruth/cam0.tum" \
  "$work/published" --as-published || fail "euroc_to_paper.py --as-published failed"
grep -q "^left:" "$work/published/intrinsics.yaml" && grep -q "^size: \[" "$work/published/intrinsics.yaml" ||
  fail "not the published layout: $(head -20 "$work/published/intrinsics.yaml")"
"$cenote" run --dataset "$work/published" --config "$config" --out "$work/published-out" >"$work/published.txt" 2>&1 ||
  fail "cenote run on the published intrinsics layout failed: $(tail -5 "$work/published.txt")"
cmp -s "$work/euroc-out/points.ply" "$work/published-out/points.ply" || fail "published layout: points.ply differs"

# colmap.ply is the dataset's reference cloud: the same numbers as naming the file itself.
"$cenote" eval cloud --source "$work/paper-out/points.ply" --target "$work/paper" --voxel 0.01 --json "$work/a.json" \
  >/dev/null 2>&1 || fail "cenote eval cloud --target DATASET failed"
"$cenote" eval cloud --source "$work/paper-out/points.ply" --target "$work/paper/colmap.ply" --voxel 0.01 \
  --json "$work/b.json" >/dev/null 2>&1 || fail "cenote eval cloud --target colmap.ply failed"
for key in accuracy_m completeness_m precision recall; do
  [ "$(json "$work/a.json" "d['$key']")" = "$(json "$work/b.json" "d['$key']")" ] || fail "$key differs with --target DATASET"
done
rm "$work/paper/colmap.ply"
expect_error 1 "the dataset has no reference cloud (colmap.ply)" eval cloud --source "$work/paper-out/points.ply" \
  --target "$work/paper"

# Bad input.
printf 'ts,filename\n1700000000000000000,a.png\nnot-a-time,b.png\n' >"$work/paper/filename_mapping.csv"
expect_error 1 "filename_mapping.csv:3: 'not-a-time' is not a timestamp" run --dataset "$work/paper" --out "$work/x"
sed -i 's/^baseline: .*/baseline: 60./' "$work/paper/intrinsics.yaml"
printf 'ts,filename\n' >"$work/paper/filename_mapping.csv"
expect_error 1 "which matches baseline = 60.000000 mm neither in millimetres nor in metres" run --dataset "$work/paper" \
  --out "$work/x"
rm "$work/paper/intrinsics.yaml"
expect_error 1 "unknown layout" run --dataset "$work/paper" --out "$work/x"
echo "paper layout: same points and map as the EuRoC folder"
