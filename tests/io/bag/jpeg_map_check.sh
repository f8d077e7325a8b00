# jpeg_map_check.sh: the map check of a JPEG recording, shared by cli_bag_test.sh and cli_mcap_test.sh.
# Source it after cli_test_lib.sh.

# expect_jpeg_map LABEL JPEG.vdb DECODED.vdb FOLDER.vdb MIN_STRICT MIN_BOTH: the map of the JPEG images is
# that of OpenCV's decoding of the same bytes (DECODED.vdb, voxel for voxel) and agrees with the PNG
# folder's within one voxel for >= 99 % of the voxels known in either. The strict agreement (same
# state voxel for voxel) is printed and must stay >= MIN_STRICT (>= MIN_BOTH among voxels known in both):
# at this rig's depth noise (a voxel) any change of the pixels re-draws a surface's shell.
expect_jpeg_map() {
  local label=$1 jpeg=$2 decoded=$3 folder=$4 min_strict=$5 min_both=$6
  "$cenote" eval map --estimate "$jpeg" --reference "$decoded" --json "$work/$label-decoded.json" >/dev/null 2>&1 ||
    fail "cenote eval map ($label against OpenCV's decoding) failed"
  [ "$(json "$work/$label-decoded.json" 'd["agreement"] == 1.0 and d["known_either"] == d["known_both"] > 0')" = True ] ||
    fail "$label: the voxels differ from those of OpenCV's decoding of the same JPEG bytes"
  "$cenote" eval map --estimate "$jpeg" --reference "$folder" --json "$work/$label-folder.json" >/dev/null 2>&1 ||
    fail "cenote eval map ($label against the folder) failed"
  local within strict both
  within=$(json "$work/$label-folder.json" 'd["agreement_within_voxel"]')
  strict=$(json "$work/$label-folder.json" 'd["agreement"]')
  both=$(json "$work/$label-folder.json" 'd["known_agreement"]')
  echo "$label: OpenCV's decoding's voxels; voxel agreement within one voxel $within (strict $strict, known in both $both)"
  /usr/bin/python3 -c "import sys; sys.exit(0 if $within >= 0.99 and $strict >= $min_strict and $both >= $min_both else 1)" ||
    fail "$label: voxel agreement within one voxel $within, expected >= 0.99 (strict $strict >= $min_strict, known in both $both >= $min_both)"
}
