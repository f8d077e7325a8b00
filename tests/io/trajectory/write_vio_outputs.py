#!/usr/bin/env python3
"""write_vio_outputs.py EUROC_DIR OUT_DIR: the pose files of visual-inertial odometry systems, in their
documented layouts, written from a simulated dive's ground truth (`cenote sim`, EuRoC layout):
  okvis.csv                OKVIS / SVIn2 CSV (okvis_ros): "timestamp, p_WS_W_x, p_WS_W_y, p_WS_W_z, q_WS_x, q_WS_y,
                           q_WS_z, q_WS_w, v_WS_W_x, ..., b_a_z", timestamps in ns, the IMU (body) poses
                           of state_groundtruth_estimate0 with the quaternion reordered x y z w
  openvins.txt             OpenVINS (ov_eval's pose_to_file): "# timestamp(s) tx ty tz qx qy qz qw", seconds,
                           the IMU poses
  orbslam3_ns.txt          ORB-SLAM3 SaveTrajectoryEuRoC: TUM rows with nanoseconds printed fixed with 6
                           decimals, here of the left camera (groundtruth/cam0.tum)
  orbslam3_keyframes.txt   ORB-SLAM3 SaveKeyFrameTrajectoryTUM: TUM rows in seconds of every 4th frame's camera
"""
import os
import sys

euroc, out = sys.argv[1:3]
os.makedirs(out, exist_ok=True)

body = []
with open(os.path.join(euroc, "mav0", "state_groundtruth_estimate0", "data.csv")) as f:
    for line in f:
        if line.startswith("#") or not line.strip():
            continue
        c = [x.strip() for x in line.split(",")]
        body.append(c)  # t_ns, px, py, pz, qw, qx, qy, qz, v..., biases...

with open(os.path.join(out, "okvis.csv"), "w") as f:
    f.write("timestamp, p_WS_W_x, p_WS_W_y, p_WS_W_z, q_WS_x, q_WS_y, q_WS_z, q_WS_w, v_WS_W_x, v_WS_W_y, v_WS_W_z, "
            "b_g_x, b_g_y, b_g_z, b_a_x, b_a_y, b_a_z\n")
    for c in body:
        f.write(", ".join([c[0], c[1], c[2], c[3], c[5], c[6], c[7], c[4], c[8], c[9], c[10]] + ["0"] * 6) + "\n")

with open(os.path.join(out, "openvins.txt"), "w") as f:
    f.write("# timestamp(s) tx ty tz qx qy qz qw\n")
    for c in body:
        t_ns = int(c[0])
        f.write(f"{t_ns // 10**9}.{t_ns % 10**9:09d} {c[1]} {c[2]} {c[3]} {c[5]} {c[6]} {c[7]} {c[4]}\n")

camera = []
with open(os.path.join(euroc, "groundtruth", "cam0.tum")) as f:
    for line in f:
        if line.startswith("#") or not line.strip():
            continue
        camera.append(line.split())
with open(os.path.join(out, "orbslam3_ns.txt"), "w") as f:
    for w in camera:
        seconds, fraction = w[0].split(".")
        t_ns = int(seconds) * 10**9 + int(fraction.ljust(9, "0")[:9])
        f.write(f"{t_ns}.000000 " + " ".join(w[1:]) + "\n")
with open(os.path.join(out, "orbslam3_keyframes.txt"), "w") as f:
    for w in camera[::4]:
        f.write(" ".join(w) + "\n")
