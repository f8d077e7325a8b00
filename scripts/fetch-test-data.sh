#!/usr/bin/env bash
# fetch-test-data.sh: unpacks real test data from Debian packages, without installing them.
#   data/motorcycle/   Middlebury 2014 Motorcycle, quarter size, float ground truth (python3-skimage)
#   data/aloe/         Middlebury Aloe pair and ground truth (opencv-doc)
#   data/chessboard/   14 stereo chessboard pairs left01..14 / right01..14 (opencv-doc)
# Idempotent: does nothing when the files are there. When the packages cannot be downloaded it
# says so and exits 0: the tests that need the data skip.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${CENOTE_DATA:-data}
PY=/usr/bin/python3

have_all() { for f in "$@"; do [ -f "$f" ] || return 1; done; }

if have_all "$DATA/motorcycle/motorcycle_disp.pfm" "$DATA/aloe/aloeGT.png" "$DATA/chessboard/right14.jpg"; then
  echo "fetch-test-data: data present in $DATA/"
  exit 0
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
chmod 755 "$work"  # apt's download user must be able to write here
if ! (cd "$work" && apt-get download -qq python3-skimage opencv-doc >/dev/null 2>&1); then
  # The package lists may be missing on a fresh machine.
  apt-get update -qq >/dev/null 2>&1 || true
  if ! (cd "$work" && apt-get download -qq python3-skimage opencv-doc >/dev/null 2>&1); then
    echo "fetch-test-data: cannot download python3-skimage / opencv-doc; tests needing them will skip"
    exit 0
  fi
fi
for deb in "$work"/*.deb; do dpkg -x "$deb" "$work/root"; done

mkdir -p "$DATA/motorcycle" "$DATA/aloe" "$DATA/chessboard"
sk="$work/root/usr/lib/python3/dist-packages/skimage/data"
cp "$sk/motorcycle_left.png" "$sk/motorcycle_right.png" "$DATA/motorcycle/"
# Ground truth: float32 disparity in an .npz (+inf = unknown) -> PFM (Middlebury's own format).
"$PY" - "$sk/motorcycle_disp.npz" "$DATA/motorcycle/motorcycle_disp.pfm" <<'PYEOF'
import sys
import numpy as np
disparity = np.load(sys.argv[1])["arr_0"].astype("<f4")
with open(sys.argv[2], "wb") as out:
    out.write(b"Pf\n%d %d\n-1\n" % (disparity.shape[1], disparity.shape[0]))
    out.write(np.ascontiguousarray(disparity[::-1]).tobytes())
PYEOF
docdata="$work/root/usr/share/doc/opencv-doc/examples/data"
cp "$docdata"/aloeL.jpg "$docdata"/aloeR.jpg "$docdata"/aloeGT.png "$DATA/aloe/"
cp "$docdata"/left0[1-9].jpg "$docdata"/left1[0-4].jpg "$docdata"/right0[1-9].jpg "$docdata"/right1[0-4].jpg \
   "$DATA/chessboard/"
echo "fetch-test-data: unpacked Motorcycle, Aloe and the chessboard set into $DATA/"
