#!/usr/bin/env python3
"""Writes SVIn2's pose-graph output from a correction event of `cenote sim --drift`.

SVIn2's pose_graph node (LoopClosing::updatePath) rewrites svin_results/svin_<date>.txt after each
pose-graph optimisation: a row per keyframe, `t x y z qx qy qz qw`, std::fixed with 9 decimals,
space-separated, t in seconds, the pose T_WS of the keyframe's IMU (S there). The sim's event holds
camera poses T_WC (TUM); the camera's pose in the body (IMU) frame, T_BC (EuRoC's T_BS of
mav0/cam0/sensor.yaml), gives the IMU's pose T_WB = T_WC * inverse(T_BC). Written without cenote's code (plain python, no numpy), so the reader
under test is checked against an independent writer.

  write_svin_loop_path.py EVENT.tum DATASET OUT.txt
"""
import math
import re
import sys


def read_t_bs(dataset):
    text = open(f"{dataset}/mav0/cam0/sensor.yaml").read()
    data = re.search(r"T_BS:.*?data:\s*\[([^\]]*)\]", text, re.S).group(1)
    m = [float(v) for v in data.replace("\n", " ").split(",")]
    return [m[0:4], m[4:8], m[8:12], m[12:16]]


def quat_to_matrix(x, y, z, w):
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def matrix_to_quat(r):
    # Shepperd's method: the largest of the four candidates keeps the division well conditioned.
    trace = r[0][0] + r[1][1] + r[2][2]
    if trace > 0:
        s = 2 * math.sqrt(1 + trace)
        return ((r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s, s / 4)
    i = max(range(3), key=lambda k: r[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2 * math.sqrt(1 + r[i][i] - r[j][j] - r[k][k])
    q = [0.0, 0.0, 0.0, (r[k][j] - r[j][k]) / s]
    q[i] = s / 4
    q[j] = (r[j][i] + r[i][j]) / s
    q[k] = (r[k][i] + r[i][k]) / s
    return tuple(q)


def compose(ra, ta, rb, tb):
    r = [[sum(ra[i][k] * rb[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    t = [sum(ra[i][k] * tb[k] for k in range(3)) + ta[i] for i in range(3)]
    return r, t


def main():
    event, dataset, out = sys.argv[1:4]
    t_bs = read_t_bs(dataset)
    r_bs = [row[:3] for row in t_bs[:3]]
    r_sb = [[r_bs[j][i] for j in range(3)] for i in range(3)]
    t_sb = [-sum(r_sb[i][k] * t_bs[k][3] for k in range(3)) for i in range(3)]
    with open(out, "w") as f:
        for line in open(event):
            if line.startswith("#") or not line.strip():
                continue
            t, x, y, z, qx, qy, qz, qw = (float(v) for v in line.split())
            r, p = compose(quat_to_matrix(qx, qy, qz, qw), [x, y, z], r_sb, t_sb)
            q = matrix_to_quat(r)
            f.write(f"{t:.9f} " + " ".join(f"{v:.9f}" for v in (*p, *q)) + "\n")


if __name__ == "__main__":
    main()
