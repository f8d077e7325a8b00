#!/usr/bin/env bash
# cli_map_test.sh CENOTE MAKE_SCAN_GRAPH: `cenote map` end to end, and against OctoMap's graph2tree
# on the same ScanGraph when octomap-tools is installed.
set -euo pipefail
cenote=$1
make_graph=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

"$make_graph" "$dir/scans.graph" 4
"$cenote" map integrate --graph "$dir/scans.graph" --resolution 0.05 --max-range 8 --out "$dir/ours.vdb"
"$cenote" map export "$dir/ours.vdb" --bt "$dir/ours.bt" --mesh "$dir/mesh.ply" --points "$dir/points.ply" --ot "$dir/ours.ot"
for f in ours.bt ours.ot mesh.ply points.ply; do test -s "$dir/$f" || { echo "missing $f"; exit 1; }; done
info=$("$cenote" map info "$dir/ours.vdb")
echo "$info"
grep -q "resolution: 0.05 m" <<<"$info"
occupied=$(sed -n 's/.*voxels: \([0-9]*\) occupied.*/\1/p' <<<"$info")
test "$occupied" -gt 1000

# PCD through PCL (io/cloud/pcd_io.h): the occupied voxel centres, as many as `map info` counts,
# read back by `cenote eval` (PCL's reader) as the same points as the PLY's.
out=$("$cenote" map export "$dir/ours.vdb" --points "$dir/points.pcd")
grep -qF "wrote $dir/points.pcd: $occupied occupied voxel centres" <<<"$out" || { echo "$out"; exit 1; }
grep -aqx "POINTS $occupied" "$dir/points.pcd" || { echo "points.pcd: no POINTS $occupied"; exit 1; }
grep -aqx "DATA binary" "$dir/points.pcd"
ev=$("$cenote" eval cloud --source "$dir/points.pcd" --target "$dir/points.ply" --voxel 0.001)
grep -Eq "points \(source / target\) +$occupied / $occupied\b" <<<"$ev" || { echo "$ev"; exit 1; }
grep -Eq "precision .*100\.00 %" <<<"$ev" || { echo "$ev"; exit 1; }
# The option names the format and the extension must agree (mapping/io/map_file_format.h): an error
# naming option and file, nothing written.
for bad in "--points $dir/p.vdb" "--bt $dir/x.vdb" "--mesh $dir/m.points.ply" "--vdb $dir/x.ply" "--points $dir/p.xyz"; do
  # shellcheck disable=SC2086
  if "$cenote" map export "$dir/ours.vdb" $bad 2>"$dir/err"; then echo "map export $bad: accepted"; exit 1; fi
  grep -qF -- "$bad: " "$dir/err" || { echo "map export $bad printed: $(cat "$dir/err")"; exit 1; }
  test ! -e "${bad#* }" || { echo "map export $bad wrote ${bad#* }"; exit 1; }
done

# .bt written and read back: the same number of occupied voxels.
bt_occupied=$("$cenote" map info "$dir/ours.bt" | sed -n 's/.*voxels: \([0-9]*\) occupied.*/\1/p')
test "$bt_occupied" -eq "$occupied" || { echo ".bt has $bt_occupied occupied voxels, .vdb $occupied"; exit 1; }

# Queries: on the first camera's central ray (direction 3,0.2,-1.5) 1.1 m out is free, far away
# is unknown, the ray continued hits the floor.
q=$("$cenote" map query "$dir/ours.vdb" --state 1.0,0.07,-0.5 --state 50,50,50 --segment 1.0,0.07,-0.5,6.0,0.4,-3.0)
echo "$q"
grep -q "state 1.0,0.07,-0.5: free" <<<"$q"
grep -q "state 50,50,50: unknown" <<<"$q"
grep -q "segment 1.0,0.07,-0.5,6.0,0.4,-3.0: hit" <<<"$q"

# Distances (the floor is within the 2 m default of the free point; far away there is nothing)
# and frontiers (the survey leaves unknown space around what it saw).
q=$("$cenote" map query "$dir/ours.vdb" --distance 1.0,0.07,-0.5 --distance 50,50,50 --frontiers --position 1,0,-0.5)
head -5 <<<"$q"  # not echo | head: with pipefail, echo killed by SIGPIPE once head exits failed the test
grep -Eq "^distance 1.0,0.07,-0.5: [01]\.[0-9]+ m, gradient " <<<"$q"
grep -q "^distance 50,50,50: beyond 2.000 m" <<<"$q"
clusters=$(sed -n 's/^frontiers: \([0-9]*\) clusters.*/\1/p' <<<"$q")
test "$clusters" -ge 1 || { echo "no frontier clusters"; exit 1; }
test "$(grep -c '^frontier [0-9]*: ' <<<"$q")" -eq "$clusters"
if "$cenote" map query "$dir/ours.vdb" --distance 1,0,0 --max-distance -1 2>"$dir/err"; then exit 1; fi
grep -q "map.max_distance_m" "$dir/err"

# Bad input: a clear error, non-zero exit.
if "$cenote" map integrate --graph "$dir/missing.graph" --out "$dir/x.bt" 2>"$dir/err"; then exit 1; fi
grep -q "missing.graph" "$dir/err"
if "$cenote" map integrate --graph "$dir/scans.graph" --resolution 0 --out "$dir/x.bt" 2>"$dir/err"; then exit 1; fi
grep -q "map.voxel_size_m" "$dir/err"

# The same job as graph2tree, same options: occupied voxel counts within 1 %.
if command -v graph2tree >/dev/null; then
  graph2tree -i "$dir/scans.graph" -o "$dir/octomap.bt" -res 0.05 -m 8 -discretize -sensor 0.4 0.7 -clamping 0.12 0.97 >/dev/null
  "$cenote" map integrate --graph "$dir/scans.graph" --resolution 0.05 --max-range 8 --sensor-model 0.7 0.4 \
    --clamping 0.12 0.97 --out "$dir/ours2.bt"
  theirs=$("$cenote" map info "$dir/octomap.bt" | sed -n 's/.*voxels: \([0-9]*\) occupied.*/\1/p')
  ours=$("$cenote" map info "$dir/ours2.bt" | sed -n 's/.*voxels: \([0-9]*\) occupied.*/\1/p')
  echo "occupied voxels: graph2tree $theirs, cenote $ours"
  awk -v a="$theirs" -v b="$ours" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 0.01 * a) }'
fi
echo "cli_map_test: ok"
