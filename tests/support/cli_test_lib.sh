# cli_test_lib.sh: what the command-line end-to-end tests share. Source it after setting $cenote;
# it makes $work, a temporary folder removed on exit. Checks stop at the first failure.

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*" >&2
  exit 1
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
