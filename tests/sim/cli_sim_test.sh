#!/usr/bin/env bash
# End-to-end test of `cenote sim`: a short sequence of each scene writes the EuRoC layout and the
# ground truth with matching counts; bad options fail with a clear message.
#   cli_sim_test.sh CENOTE
set -euo pipefail
cenote=$1
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

for scene in cave reef wreck; do
  out=$work/$scene
  "$cenote" sim --scene "$scene" --frames 4 --width 200 --height 150 --seed 3 --out "$out" --quiet >"$work/stdout" \
    || fail "sim $scene failed"
  grep -q "simulated 4 frames of the $scene scene (200x150" "$work/stdout" || fail "summary: $(cat "$work/stdout")"
  for cam in cam0 cam1; do
    [[ $(ls "$out/mav0/$cam/data" | grep -c '\.png$') -eq 4 ]] || fail "$scene: $cam images"
    [[ $(wc -l <"$out/mav0/$cam/data.csv") -eq 5 ]] || fail "$scene: $cam/data.csv rows"
    head -1 "$out/mav0/$cam/data.csv" | grep -qx '#timestamp \[ns\],filename' || fail "$scene: $cam/data.csv header"
    head -1 "$out/mav0/$cam/sensor.yaml" | grep -qx '%YAML:1.0' || fail "$scene: $cam/sensor.yaml first line"
    grep -q '^resolution: \[200, 150\]' "$out/mav0/$cam/sensor.yaml" || fail "$scene: $cam resolution"
  done
  # Every listed image exists.
  tail -n +2 "$out/mav0/cam0/data.csv" | while IFS=, read -r stamp file; do
    [[ -s $out/mav0/cam0/data/$file && -s $out/mav0/cam1/data/$file ]] || fail "$scene: missing $file"
    [[ -s $out/groundtruth/depth/$stamp.pfm ]] || fail "$scene: missing depth $stamp.pfm"
  done
  [[ $(grep -vc '^#' "$out/groundtruth/cam0.tum") -eq 4 ]] || fail "$scene: cam0.tum rows"
  # Ground truth at 200 Hz over 3/15 s plus 0.1 s either side.
  rows=$(grep -vc '^#' "$out/mav0/state_groundtruth_estimate0/data.csv")
  ((rows == 81)) || fail "$scene: $rows ground-truth rows, expected 81"
  [[ $(grep -vc '^#' "$out/groundtruth/body.tum") -eq $rows ]] || fail "$scene: body.tum rows"
  head -c 300 "$out/groundtruth/surface.ply" | grep -qa "format binary_little_endian 1.0" || fail "$scene: surface.ply"
  grep -q "^K1:" "$out/groundtruth/calibration.yaml" || fail "$scene: calibration.yaml"
done

# Same seed, same bytes; the thread count does not matter.
OMP_NUM_THREADS=1 "$cenote" sim --scene reef --frames 2 --width 200 --height 150 --seed 3 --out "$work/one" --quiet >/dev/null
OMP_NUM_THREADS=2 "$cenote" sim --scene reef --frames 2 --width 200 --height 150 --seed 3 --out "$work/two" --quiet >/dev/null
# (two empty folders would be the same too: the images must be there)
[[ $(ls "$work/one/mav0/cam0/data" | grep -c '\.png$') -eq 2 ]] || fail "1 thread: no images to compare"
diff -r "$work/one" "$work/two" >/dev/null || fail "1 and 2 threads wrote different files"

# A config file's sim: section, overridden by options.
printf 'sim:\n  scene: wreck\n  num_frames: 2\n  width_px: 128\n  height_px: 96\n' >"$work/sim.yaml"
"$cenote" sim --config "$work/sim.yaml" --frames 3 --out "$work/cfg" --quiet >"$work/stdout"
grep -q "simulated 3 frames of the wreck scene (128x96" "$work/stdout" || fail "config: $(cat "$work/stdout")"

# Bad options.
expect_error 1 "--scene ocean: must be cave, reef or wreck" sim --scene ocean --frames 2 --out "$work/bad"
expect_error 1 "sim.num_frames = 0: must be in [1, 100000]" sim --scene cave --frames 0 --out "$work/bad"
expect_error 1 "sim.baseline_m = -1: must be in (0, 2]" sim --scene cave --frames 2 --baseline -1 --out "$work/bad"
expect_error 1 "sim.exposure_ratio = 20: must be in [0.1, 10]" sim --frames 2 --exposure-ratio 20 --out "$work/bad"
expect_error 1 "sim.width_px = 10: must be in [64, 4096]" sim --frames 2 --width 10 --out "$work/bad"
printf 'sim:\n  num_frame: 2\n' >"$work/typo.yaml"
expect_error 1 "unknown configuration key(s): sim.num_frame" sim --config "$work/typo.yaml" --out "$work/bad"
expect_error 104 "Could not convert: --frames = many" sim --frames many --out "$work/bad"
expect_error 106 "--out is required" sim --frames 2
echo "cli_sim_test: all checks passed"
