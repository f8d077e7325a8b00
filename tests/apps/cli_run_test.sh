#!/usr/bin/env bash
# End-to-end test of `cenote run` on simulated sequences: exit codes, outputs, report.json, bad
# input, and bounded memory (a 300-frame run peaks within 10 % of a 60-frame run).
# Usage: cli_run_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2], {}, {'d': d}))" "$@"; }

# Small frames keep the test short; the memory claim does not depend on the image size.
"$cenote" sim --scene reef --frames 300 --width 320 --height 240 --quiet --out "$work/long" >/dev/null 2>&1 ||
  fail "cenote sim (300 frames) failed"
"$cenote" sim --scene reef --frames 60 --width 320 --height 240 --quiet --out "$work/short" >/dev/null 2>&1 ||
  fail "cenote sim (60 frames) failed"

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
  /usr/bin/python3 -c "import sys; sys.exit(0 if $long_mb <= 1.1 * $short_mb else 1)" ||
    fail "memory grows with the sequence: $short_mb MiB for 60 frames, $long_mb MiB for 300"
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

echo "cli_run_test: all checks passed"
