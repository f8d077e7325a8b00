#!/usr/bin/env python3
"""euroc_to_paper.py EUROC_DIR POSES_TUM OUT_DIR [--as-published]: rewrites a simulated dive (`cenote sim`, EuRoC layout) in
the reference paper's layout, independently of cenote's own readers:
  left/, right/             the PNG images, named by their timestamp in nanoseconds
  filename_mapping.csv      "ts,ts.png" rows under a header row
  poses.txt                 POSES_TUM (TUM rows of the left camera) copied
  intrinsics.yaml           written by OpenCV's FileStorage: K1 D1 K2 D2, image size, baseline in
                            millimetres, R and T (T in millimetres) from the two sensor.yaml files' T_BS
  colmap.ply                the dive's ground-truth surface (groundtruth/surface.ply), as the reference cloud
With --as-published, intrinsics.yaml is laid out as the paper's own repository documents and reads it
(github.com/ApdowJN/RTDense3DMapping, README and src/util.cpp): `left:` and `right:` mappings holding K
and D, `size: [w, h]`, the baseline in millimetres and T in metres.
"""
import os
import shutil
import sys

import cv2
import numpy as np
import yaml

euroc, poses, out = sys.argv[1:4]
as_published = "--as-published" in sys.argv[4:]
mav0 = os.path.join(euroc, "mav0")


def sensor(cam):
    with open(os.path.join(mav0, cam, "sensor.yaml")) as f:
        text = "".join(line for line in f if not line.startswith("%YAML"))
    s = yaml.safe_load(text)
    fu, fv, cu, cv = s["intrinsics"]
    K = np.array([[fu, 0, cu], [0, fv, cv], [0, 0, 1]], dtype=np.float64)
    D = np.array(s["distortion_coefficients"], dtype=np.float64).reshape(1, -1)
    T_BS = np.array(s["T_BS"]["data"], dtype=np.float64).reshape(4, 4)
    return K, D, T_BS, s["resolution"]


def images(cam):
    rows = []
    with open(os.path.join(mav0, cam, "data.csv")) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                stamp, name = line.split(",")
                rows.append((int(stamp), name.strip()))
    return rows


os.makedirs(os.path.join(out, "left"), exist_ok=True)
os.makedirs(os.path.join(out, "right"), exist_ok=True)
left, right = images("cam0"), images("cam1")
assert [s for s, _ in left] == [s for s, _ in right], "the simulator writes both cameras at the same stamps"
with open(os.path.join(out, "filename_mapping.csv"), "w") as f:
    f.write("ts,filename\n")
    for (stamp, l_name), (_, r_name) in zip(left, right):
        name = f"{stamp}.png"
        shutil.copy(os.path.join(mav0, "cam0", "data", l_name), os.path.join(out, "left", name))
        shutil.copy(os.path.join(mav0, "cam1", "data", r_name), os.path.join(out, "right", name))
        f.write(f"{stamp},{name}\n")
shutil.copy(poses, os.path.join(out, "poses.txt"))
shutil.copy(os.path.join(euroc, "groundtruth", "surface.ply"), os.path.join(out, "colmap.ply"))

K1, D1, T_B0, size = sensor("cam0")
K2, D2, T_B1, _ = sensor("cam1")
T_right_left = np.linalg.inv(T_B1) @ T_B0  # p_right = R p_left + T
R = T_right_left[:3, :3]
T_mm = T_right_left[:3, 3:4] * 1000.0
fs = cv2.FileStorage(os.path.join(out, "intrinsics.yaml"), cv2.FILE_STORAGE_WRITE)
if as_published:
    for side, K, D in (("left", K1, D1), ("right", K2, D2)):
        fs.startWriteStruct(side, cv2.FileNode_MAP)
        fs.write("K", K)
        fs.write("D", D)
        fs.endWriteStruct()
    fs.startWriteStruct("size", cv2.FileNode_SEQ | cv2.FileNode_FLOW)
    fs.write("", int(size[0]))
    fs.write("", int(size[1]))
    fs.endWriteStruct()
    fs.write("baseline", float(np.linalg.norm(T_mm)))
    fs.write("R", R)
    fs.write("T", (T_mm / 1000.0).reshape(1, 3))
else:
    fs.write("image_width", int(size[0]))
    fs.write("image_height", int(size[1]))
    fs.write("K1", K1)
    fs.write("D1", D1)
    fs.write("K2", K2)
    fs.write("D2", D2)
    fs.write("baseline", float(np.linalg.norm(T_mm)))
    fs.write("R", R)
    fs.write("T", T_mm)
fs.release()
