# cli_test_lib.sh: what the command-line end-to-end tests share. Source it after setting $cenote;
# it makes $work, a temporary folder removed on exit. Checks stop at the first failure.

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# json FILE EXPR: EXPR evaluated on the JSON document in FILE, bound to d (e.g. "d['frames_processed']").
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2], {}, {'d': d}))" "$@"; }

# simulate_reef FRAMES OUT: a simulated reef dive of FRAMES small (320 x 240) frames, written to OUT.
simulate_reef() {
  "$cenote" sim --scene reef --frames "$1" --width 320 --height 240 --quiet --out "$2" >/dev/null 2>&1 ||
    fail "cenote sim ($1 frames) failed"
}

# expect_error CODE PATTERN ARGS...: `cenote ARGS` must exit CODE and print PATTERN on stderr.
expect_error() {
  local want=$1 pattern=$2
  shift 2
  local status=0
  "$cenote" "$@" >"$work/stdout" 2>"$work/stderr" || status=$?
  [[ $status -eq $want ]] || fail "expected exit $want, got $status for: $* ($(cat "$work/stderr"))"
  grep -qF -- "$pattern" "$work/stderr" || fail "expected '$pattern' in: $(cat "$work/stderr")"
}
