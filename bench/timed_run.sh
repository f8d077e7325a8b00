# timed_run.sh: sourced by the `cenote run` throughput benchmarks (run_throughput.sh,
# recording_throughput.sh) for the one thing they measure alike.
#
# timed_cenote_run CENOTE OUT ARGS...: runs `CENOTE run ARGS --out OUT` (its output discarded) and
# prints the CPU time of the whole run per processed frame in milliseconds (user + system, all
# threads, start-up included; OUT/report.json's frames_processed, at least 1). Fails as the run does.
timed_cenote_run() {
  local cenote=$1 out=$2
  shift 2
  local TIMEFORMAT='%U %S'
  { time "$cenote" run "$@" --out "$out" >/dev/null 2>&1; } 2>"$out.cpu" || return
  /usr/bin/python3 - "$out/report.json" "$out.cpu" <<'PY'
import json, sys
frames = max(json.load(open(sys.argv[1]))["frames_processed"], 1)
user, system = map(float, open(sys.argv[2]).read().split())
print((user + system) * 1000.0 / frames)
PY
}
