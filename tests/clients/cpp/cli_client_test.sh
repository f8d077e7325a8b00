#!/usr/bin/env bash
# cli_client_test.sh CENOTE_SERVER CENOTE_CLI: cenote-cli against a real cenote-server on loopback
# (port 0, token file): the `state` lines of a known wall scene, the other commands' output, and a
# failed call (wrong token, bad input) printing the status name and exiting non-zero.
set -euo pipefail
server_bin=$1
cenote=$2
source "$(dirname "$0")/../../support/cli_test_lib.sh"

echo "e2e-cli-token" >"$work/token"
mkdir -p "$work/snapshots"
"$server_bin" --listen 127.0.0.1:0 --port-file "$work/port" --token-file "$work/token" \
  --snapshot-dir "$work/snapshots" >"$work/server.log" 2>&1 &
server_pid=$!
trap 'kill $server_pid 2>/dev/null; wait $server_pid 2>/dev/null; rm -rf "$work"' EXIT
for _ in $(seq 600); do
  [[ -s "$work/port" ]] && break
  kill -0 $server_pid 2>/dev/null || fail "cenote-server exited: $(cat "$work/server.log")"
  sleep 0.1
done
[[ -s "$work/port" ]] || fail "cenote-server wrote no port file: $(cat "$work/server.log")"
sleep 0.1
server="127.0.0.1:$(tr -d '[:space:]' <"$work/port")"
cli() { "$cenote" --server "$server" --token-file "$work/token" "$@"; }
# expect_output GREP_ARGS -- CLI_ARGS...: the command succeeds and its output matches.
expect_output() {
  local -a pattern=()
  while [[ $1 != -- ]]; do pattern+=("$1"); shift; done
  shift
  cli "$@" >"$work/out" 2>"$work/err" || fail "cenote-cli $* failed: $(cat "$work/err")"
  grep -q "${pattern[@]}" "$work/out" || fail "cenote-cli $* printed: $(cat "$work/out")"
}

# The wall: one point at each voxel centre x = 2.025, y and z in -0.975 .. 0.975 (40 x 40), seen
# from the centre of voxel (0, 0, 0).
awk 'BEGIN { for (j = -20; j < 20; j++) for (k = -20; k < 20; k++) printf "2.025 %.3f %.3f\n", (j + 0.5) * 0.05, (k + 0.5) * 0.05 }' \
  >"$work/wall.txt"
expect_output "integrated 1600 points" -- integrate --points-file "$work/wall.txt" --origin 0.025,0.025,0.025

# state: one line per point, `x y z state probability`, in order.
out=$(cli state 2.025,0.025,0.025 1.025,0.025,0.025 3.025,0.025,0.025 -1,0,0)
echo "$out"
expected=$'2.025 0.025 0.025 occupied 0.7000\n1.025 0.025 0.025 free 0.4000\n3.025 0.025 0.025 unknown 0.5000\n-1 0 0 unknown 0.5000'
[[ "$out" == "$expected" ]] || fail "state printed:"$'\n'"$out"$'\n'"expected:"$'\n'"$expected"
printf '2.025 0.525 -0.475\n\n# a comment\n1.525 0.025 0.025\n' >"$work/points.txt"
out=$(cli state --points-file "$work/points.txt")
[[ "$out" == $'2.025 0.525 -0.475 occupied 0.7000\n1.525 0.025 0.025 free 0.4000' ]] || fail "state --points-file printed: $out"

# The other queries.
expect_output -x "occupied 1600 free 0 unknown 0" -- box 2.01,-1,-1 2.04,1,1
expect_output "^hit at 1.500 m, voxel 40,0,0" -- segment 0.525,0.025,0.025 3.025,0.025,0.025
expect_output "^hit at 2.000 m" -- raycast 0.025,0.025,0.025 1,0,0 --max-range 5
dist=$(cli distance 1.525,0.025,0.025)
awk '{ exit !($4 > 0.449 && $4 < 0.551 && $5 < -0.9) }' <<<"$dist" || fail "distance: $dist"
expect_output "frontier clusters" -- frontiers --max 3
expect_output -x "occupied: 1600" -- info
expect_output -x "batches_integrated: 1" -- stats
expect_output "^update [0-9]* snapshot" -- watch --count 1
expect_output "^wrote .*wall.vdb" -- snapshot wall.vdb
[[ -s "$work/snapshots/wall.vdb" ]] || fail "snapshot: no $work/snapshots/wall.vdb"
expect_output "^downloaded" -- snapshot --download "$work/local.vdb"
[[ -s "$work/local.vdb" ]] || fail "snapshot --download wrote nothing"
# The format follows the extension (mapping/io/map_file_format.h; issue 14): a download named .bt is
# an OctoMap tree, mesh.ply says which PLY it is, and a --format the extension disagrees with is refused.
expect_output "^downloaded" -- snapshot --download "$work/local.bt"
[[ "$(head -n 1 "$work/local.bt")" == "# Octomap OcTree binary file" ]] || fail "snapshot --download local.bt: $(head -c 40 "$work/local.bt")"
expect_output "^wrote .*wall.mesh.ply" -- snapshot wall.mesh.ply
grep -aq "^element face " "$work/snapshots/wall.mesh.ply" || fail "wall.mesh.ply has no faces"
for refused in "mesh.ply" "wall.vdb --format points-ply" "wall.xyz"; do
  status=0
  # shellcheck disable=SC2086
  cli snapshot $refused >"$work/stdout" 2>"$work/stderr" || status=$?
  [[ $status -ne 0 ]] && grep -q "^error: INVALID_ARGUMENT: ${refused%% *}: " "$work/stderr" ||
    fail "snapshot $refused: exit $status, $(cat "$work/stderr")"
done
[[ ! -e "$work/snapshots/mesh.ply" && ! -e "$work/snapshots/wall.xyz" ]] || fail "a refused snapshot was written"

# Failed calls: the status name and message on stderr, a non-zero exit, and the map unchanged.
cenote_wrong() { "$cenote" --server "$server" --token wrong-token "$@"; }
status=0
cenote_wrong state 1,1,1 >"$work/stdout" 2>"$work/stderr" || status=$?
[[ $status -eq 2 ]] || fail "wrong token: exit $status, expected 2"
grep -q "^error: UNAUTHENTICATED: " "$work/stderr" || fail "wrong token printed: $(cat "$work/stderr")"
status=0
"$cenote" --server "$server" reset >"$work/stdout" 2>"$work/stderr" || status=$?
[[ $status -eq 2 ]] && grep -q "UNAUTHENTICATED" "$work/stderr" || fail "no token: exit $status, $(cat "$work/stderr")"
status=0
cli state nan,0,0 >"$work/stdout" 2>"$work/stderr" || status=$?
[[ $status -eq 2 ]] && grep -q "^error: INVALID_ARGUMENT: " "$work/stderr" || fail "NaN point: exit $status, $(cat "$work/stderr")"
expect_output -x "occupied: 1600" -- info  # the map is unchanged after the refused calls
# TLS: a second server with a self-signed certificate for 127.0.0.1; --tls-ca connects, plaintext does not.
if command -v openssl >/dev/null; then
  openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=cenote -addext subjectAltName=IP:127.0.0.1 \
    -keyout "$work/tls.key" -out "$work/tls.pem" >/dev/null 2>&1 || fail "openssl could not make a certificate"
  "$server_bin" --listen 127.0.0.1:0 --port-file "$work/tls_port" --tls-cert "$work/tls.pem" --tls-key "$work/tls.key" \
    --snapshot-dir "$work/snapshots" >"$work/tls_server.log" 2>&1 &
  tls_pid=$!
  trap 'kill $server_pid $tls_pid 2>/dev/null; wait $server_pid $tls_pid 2>/dev/null; rm -rf "$work"' EXIT
  for _ in $(seq 600); do [[ -s "$work/tls_port" ]] && break; sleep 0.1; done
  tls_server="127.0.0.1:$(tr -d '[:space:]' <"$work/tls_port")"
  "$cenote" --server "$tls_server" --tls-ca "$work/tls.pem" info >"$work/out" 2>"$work/err" \
    || fail "TLS info failed: $(cat "$work/err")"
  grep -qx "voxel_size_m: 0.05" "$work/out" || fail "TLS info printed: $(cat "$work/out")"
  status=0
  "$cenote" --server "$tls_server" --deadline 3 info >"$work/out" 2>"$work/err" || status=$?
  [[ $status -eq 2 ]] && grep -q "^error: UNAVAILABLE: " "$work/err" || fail "plaintext to TLS: exit $status, $(cat "$work/err")"
fi

# Bad command line: exit 1 naming the argument; no server needed.
expect_error 1 "expected X,Y,Z" state 1,2
echo "cli_client_test: ok"
