#!/usr/bin/env bash
# End-to-end test of `cenote stereo`: real image files in, PFM/PNG files out, exit codes and error
# messages for bad input. Usage: cli_stereo_test.sh <cenote binary> <source dir>
set -u
cenote=$1
source_dir=$2
source "$(dirname "${BASH_SOURCE[0]}")/../support/cli_test_lib.sh"

# A textured pair written by the test itself: disparity 7 px everywhere.
python_png() {
  /usr/bin/python3 - "$@" <<'PY'
import sys, zlib, struct, random
def png(path, w, h, shift):
    random.seed(3)
    base = [[random.randrange(256) for _ in range(w + 16)] for _ in range(h)]
    rows = b"".join(b"\x00" + bytes(base[y][x + shift] for x in range(w)) for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) \
        + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    open(path, "wb").write(data)
png(sys.argv[1], 120, 80, 0)   # left: pixel x shows base[x]
png(sys.argv[2], 120, 80, 7)   # right: pixel x - 7 shows base[x] too
png(sys.argv[3], 120, 79, 7)   # a right image one row short
PY
}
python_png "$work/left.png" "$work/right.png" "$work/short.png"

# 1. A pair in, every output written, timing printed.
if "$cenote" stereo --left "$work/left.png" --right "$work/right.png" --disparities 16 \
    --out-disparity "$work/d.pfm" --out-confidence "$work/c.pfm" --out-preview "$work/p.png" \
    --out-depth "$work/z.pfm" --focal-px 100 --baseline-m 0.1 --repeat 3 >"$work/run.txt" 2>&1; then
  grep -q '^stereo_ms_median=[0-9.]*$' "$work/run.txt" || fail "no stereo_ms_median line: $(cat "$work/run.txt")"
  for f in d.pfm c.pfm p.png z.pfm; do [ -s "$work/$f" ] || fail "missing output $f"; done
  head -c 3 "$work/d.pfm" | grep -q "Pf" || fail "disparity is not a PFM file"
  # The disparity at the image centre is 7 and the depth f b / d = 100 * 0.1 / 7.
  /usr/bin/python3 - "$work/d.pfm" "$work/z.pfm" <<'PY' || fail "disparity or depth value wrong"
import struct, sys
def value(path, x, y):
    data = open(path, "rb").read()
    lines = data.split(b"\n", 3)
    w, h = map(int, lines[1].split())
    row = h - 1 - y
    return struct.unpack_from("<f", lines[3], (row * w + x) * 4)[0]
d, z = value(sys.argv[1], 60, 40), value(sys.argv[2], 60, 40)
assert abs(d - 7.0) < 0.25, d
assert abs(z - 10.0 / d) < 1e-4, (z, d)
PY
else
  fail "cenote stereo on a valid pair failed: $(cat "$work/run.txt")"
fi

# 2. Bad input: clear messages, non-zero exit.
expect_error 1 "no such file" stereo --left "$work/missing.png" --right "$work/right.png" --out-disparity "$work/x.pfm"
expect_error 1 "is 120x79 but left image" stereo --left "$work/left.png" --right "$work/short.png" --out-disparity "$work/x.pfm"
echo "not an image" >"$work/text.png"
expect_error 1 "not a readable image" stereo --left "$work/text.png" --right "$work/right.png" --out-disparity "$work/x.pfm"
expect_error 1 "stereo.num_disparities = 100" stereo --left "$work/left.png" --right "$work/right.png" --disparities 100 --out-disparity "$work/x.pfm"
expect_error 1 "--out-depth needs --calib" stereo --left "$work/left.png" --right "$work/right.png" --out-disparity "$work/x.pfm" --out-depth "$work/z.pfm"
echo "image_width: 10" >"$work/calib.yaml"
expect_error 1 "calib.yaml" stereo --left "$work/left.png" --right "$work/right.png" --calib "$work/calib.yaml" --out-disparity "$work/x.pfm"
printf 'stereo:\n  window_sise: 3\n' >"$work/config.yaml"
expect_error 1 "unknown configuration key(s): stereo.window_sise" stereo --left "$work/left.png" --right "$work/right.png" --config "$work/config.yaml" --out-disparity "$work/x.pfm"

echo "cli_stereo_test: all checks passed"
