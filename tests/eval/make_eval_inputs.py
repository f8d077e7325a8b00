#!/usr/bin/env python3
"""make_eval_inputs.py OUT: small inputs with known answers for cli_eval_test.sh (numpy only).

OUT/est, OUT/ref        depth maps: est = ref + 0.1 m on every pixel, 3 frames; ref as COLMAP
                        .geometric.bin (0 = hole in one corner), est as PFM
OUT/target.ply          a 20 x 20 x 20 grid of 1 m spacing, ASCII PLY
OUT/source.pcd          the same grid shifted by 0.03 m along x, binary PCD
OUT/ref_traj.txt        TUM helix, 100 poses at 10 Hz
OUT/est_traj.csv        the same, scaled by 0.5, rotated and translated, as EuRoC CSV (ns)
"""
import os
import struct
import sys

import numpy as np


def write_pfm(path, image):
    with open(path, "wb") as f:
        f.write(b"Pf\n%d %d\n-1\n" % (image.shape[1], image.shape[0]))
        f.write(np.flipud(image).astype("<f4").tobytes())


def write_colmap(path, image):
    with open(path, "wb") as f:
        f.write(b"%d&%d&1&" % (image.shape[1], image.shape[0]))
        f.write(image.astype("<f4").tobytes())  # x fastest: row-major for one channel


def main():
    out = sys.argv[1]
    os.makedirs(os.path.join(out, "est"), exist_ok=True)
    os.makedirs(os.path.join(out, "ref"), exist_ok=True)
    y, x = np.mgrid[0:30, 0:40]
    for i in range(3):
        ref = (2.0 + 0.01 * x + 0.02 * y + i).astype(np.float32)
        ref[:5, :5] = 0.0
        write_colmap(os.path.join(out, "ref", f"{i:04d}.png.geometric.bin"), ref)
        est = ref + 0.1
        est[:5, :5] = np.inf
        write_pfm(os.path.join(out, "est", f"{i:04d}.depth.pfm"), est)

    g = np.stack(np.meshgrid(np.arange(20), np.arange(20), np.arange(20), indexing="ij"), -1).reshape(-1, 3)
    g = g.astype(np.float32)
    with open(os.path.join(out, "target.ply"), "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "end_header\n" % len(g))
        np.savetxt(f, g, fmt="%.6f")
    shifted = g + np.array([0.03, 0, 0], np.float32)
    with open(os.path.join(out, "source.pcd"), "wb") as f:
        f.write(("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH %d\nHEIGHT 1\n"
                 "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS %d\nDATA binary\n" % (len(g), len(g))).encode())
        f.write(shifted.astype("<f4").tobytes())

    t = 100.0 + 0.1 * np.arange(100)
    a = 0.1 * np.arange(100)
    p = np.stack([3 * np.cos(a), 2 * np.sin(a), 0.05 * np.arange(100)], -1)
    with open(os.path.join(out, "ref_traj.txt"), "w") as f:
        for ti, pi in zip(t, p):
            f.write("%.6f %.9f %.9f %.9f 0 0 0 1\n" % (ti, *pi))
    c, s = np.cos(0.8), np.sin(0.8)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    q = (np.cos(0.4), 0.0, 0.0, np.sin(0.4))  # w x y z of R
    pe = 0.5 * p @ R.T + np.array([10.0, -4.0, 2.0])
    with open(os.path.join(out, "est_traj.csv"), "w") as f:
        f.write("#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n")
        for ti, pi in zip(t, pe):
            f.write("%d,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n" % (round(ti * 1e9), *pi, *q))


if __name__ == "__main__":
    main()
