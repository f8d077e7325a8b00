#!/usr/bin/env python3
"""Converts an EuRoC-layout dive (`cenote sim`) into a ROS 1 bag with ROS's own rosbag (python3-rosbag).

Usage: euroc_to_bag.py EUROC_DIR OUT.bag [--images raw|bayer|png|jpeg] [--compression none|bz2|lz4]
                       [--right-jitter-ms J] [--drop-right N,...] [--camera-info] [--poses odometry|tf]
                       [--pose-of body|camera] [--keyframe-poses N] [--decoded-folder DIR]
  raw:  sensor_msgs/Image (bgr8 or mono8, the PNGs' pixels) on /left/image_raw and /right/image_raw
  bayer: sensor_msgs/Image bayer_rggb8 on the same topics: the colour filter mosaic of the PNGs' pixels
        (numpy: R G on even rows, G B on odd rows), as a raw colour camera records
  png:  sensor_msgs/CompressedImage holding the PNG files' bytes, format "png", on
        /slave1/image_raw/compressed and /slave2/image_raw/compressed (the SVIn2 rig's topics)
  jpeg: the same topics, each image JPEG-encoded by OpenCV at quality 95, format
        "bgr8; jpeg compressed bgr8" (as ROS's compressed_image_transport writes it)
  --decoded-folder DIR (with jpeg or bayer): also a copy of the EuRoC folder whose images are the bag's
        JPEG bytes decoded by OpenCV (cv2.imdecode) or its mosaics demosaiced by OpenCV (cv2.cvtColor),
        as PNG: the pixels OpenCV's Python bindings get
  --right-jitter-ms: the right stamps moved by a seeded uniform offset in [-J, J] ms
  --drop-right: indices of right images left out
  --camera-info: sensor_msgs/CameraInfo of both cameras (<ns>/camera_info), K, D, R, P from
        cv2.stereoRectify of the rig in cam0/cam1 sensor.yaml, as ROS's stereo calibration publishes them
  --poses: the ground-truth body poses as nav_msgs/Odometry on /odom (frame world, child body), or
        as tf2_msgs/TFMessage world -> body on /tf
  --pose-of camera: the left camera's poses instead (T_world_body * T_BS of cam0, child cam0)
  --keyframe-poses N: only the left camera's poses at every Nth image (cenote sim's groundtruth/cam0.tum,
        child cam0), as a VIO's keyframe odometry (SVIn2) publishes them
Messages are written in stamp order; the log time is the header stamp.
"""
import argparse
import os
import random
import shutil

import cv2
import numpy as np
import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from tf2_msgs.msg import TFMessage

from bag_fixtures import bayer_mosaic

ap = argparse.ArgumentParser()
ap.add_argument("euroc")
ap.add_argument("out")
ap.add_argument("--images", default="raw", choices=["raw", "bayer", "png", "jpeg"])
ap.add_argument("--compression", default="none", choices=["none", "bz2", "lz4"])
ap.add_argument("--right-jitter-ms", type=float, default=0.0)
ap.add_argument("--drop-right", default="")
ap.add_argument("--camera-info", action="store_true")
ap.add_argument("--poses", default="odometry", choices=["odometry", "tf"])
ap.add_argument("--pose-of", default="body", choices=["body", "camera"])
ap.add_argument("--keyframe-poses", type=int, default=0)
ap.add_argument("--decoded-folder", default="")
a = ap.parse_args()
if a.decoded_folder and a.images not in ("jpeg", "bayer"):
    ap.error("--decoded-folder needs --images jpeg or bayer")
mav0 = os.path.join(a.euroc, "mav0") if os.path.isdir(os.path.join(a.euroc, "mav0")) else a.euroc


def time_of(ns):
    return rospy.Time(ns // 1000000000, ns % 1000000000)


def image_list(cam):
    rows = []
    for line in open(os.path.join(mav0, cam, "data.csv")):
        line = line.strip()
        if line and not line.startswith("#"):
            t, f = line.split(",")
            rows.append((int(t), os.path.join(mav0, cam, "data", f.strip())))
    return rows


def sensor(cam):
    fs = cv2.FileStorage(os.path.join(mav0, cam, "sensor.yaml"), cv2.FILE_STORAGE_READ)
    seq = lambda name: [fs.getNode(name).at(i).real() for i in range(fs.getNode(name).size())]
    T = np.array([fs.getNode("T_BS").getNode("data").at(i).real() for i in range(16)]).reshape(4, 4)
    fu, fv, cu, cv = seq("intrinsics")
    K = np.array([[fu, 0, cu], [0, fv, cv], [0, 0, 1.0]])
    size = [int(v) for v in seq("resolution")]
    return K, np.array(seq("distortion_coefficients") + [0.0]), T, size


raw = a.images in ("raw", "bayer")
names = ("/left/image_raw", "/right/image_raw") if raw else (
    "/slave1/image_raw/compressed", "/slave2/image_raw/compressed")
infos = ("/left/camera_info", "/right/camera_info") if raw else (
    "/slave1/camera_info", "/slave2/camera_info")
rng = random.Random(15)
if a.decoded_folder:
    shutil.copytree(a.euroc, a.decoded_folder)
drop = {int(i) for i in a.drop_right.split(",") if i}

camera_infos = None
if a.camera_info:
    K1, D1, T1, size = sensor("cam0")
    K2, D2, T2, _ = sensor("cam1")
    T_21 = np.linalg.inv(T2) @ T1  # left camera into the right camera
    R1, R2, P1, P2, _, _, _ = cv2.stereoRectify(K1, D1, K2, D2, tuple(size), T_21[:3, :3], T_21[:3, 3],
                                                flags=cv2.CALIB_ZERO_DISPARITY, alpha=0)
    camera_infos = []
    for K, D, R, P, frame in ((K1, D1, R1, P1, "cam0"), (K2, D2, R2, P2, "cam1")):
        m = CameraInfo()
        m.header.frame_id = frame
        m.width, m.height = size
        m.distortion_model = "plumb_bob"
        m.D = [float(v) for v in D]
        m.K = [float(v) for v in K.flatten()]
        m.R = [float(v) for v in R.flatten()]
        m.P = [float(v) for v in P.flatten()]
        camera_infos.append(m)

def save_decoded(pixels, path):
    """The pixels OpenCV gets from the bag's image, into --decoded-folder at the image's place."""
    cv2.imwrite(os.path.join(a.decoded_folder, os.path.relpath(path, a.euroc)), pixels)


def quat_to_matrix(w, x, y, z):
    n = (w * w + x * x + y * y + z * z) ** 0.5
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(R):
    # Shepperd's method: w x y z
    t = np.trace(R)
    if t > 0:
        s = 2.0 * (t + 1.0) ** 0.5
        return [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    i = int(np.argmax(np.diag(R)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * (1.0 + R[i, i] - R[j, j] - R[k, k]) ** 0.5
    q = [0.0] * 4
    q[0] = (R[k, j] - R[j, k]) / s
    q[1 + i] = 0.25 * s
    q[1 + j] = (R[j, i] + R[i, j]) / s
    q[1 + k] = (R[k, i] + R[i, k]) / s
    return q


T_body_cam0 = sensor("cam0")[2]
events = []  # (stamp ns, order, topic, message)
for side, (cam, topic) in enumerate(zip(("cam0", "cam1"), names)):
    for index, (t_ns, path) in enumerate(image_list(cam)):
        if side == 1 and index in drop:
            continue
        stamp = t_ns
        if side == 1 and a.right_jitter_ms > 0:
            stamp += int(round(rng.uniform(-a.right_jitter_ms, a.right_jitter_ms) * 1e6))
        events.append((stamp, 1 + side, topic, path))
        if camera_infos is not None:
            events.append((stamp, 3 + side, infos[side], None))
pose_topic = "/odom" if a.poses == "odometry" else "/tf"
if a.keyframe_poses:  # the left camera's poses (cenote sim's groundtruth/cam0.tum) at every Nth image
    rows = [l.split() for l in open(os.path.join(a.euroc, "groundtruth", "cam0.tum")) if not l.startswith("#")]
    for k, r in enumerate(rows):
        if k % a.keyframe_poses == 0:
            sec, frac = r[0].split(".")
            ns = int(sec) * 1000000000 + int(frac.ljust(9, "0"))
            events.append((ns, 0, pose_topic, [ns] + r[1:4] + [r[7]] + r[4:7]))  # as the CSV: p, then qw qx qy qz
else:
    for line in open(os.path.join(mav0, "state_groundtruth_estimate0", "data.csv")):
        if line.startswith("#") or not line.strip():
            continue
        v = line.strip().split(",")
        events.append((int(v[0]), 0, pose_topic, v))
events.sort(key=lambda e: (e[0], e[1]))

with rosbag.Bag(a.out, "w", compression=a.compression) as bag:
    for stamp, order, topic, payload in events:
        t = time_of(stamp)
        if order == 0:
            p = [float(x) for x in payload[1:8]]  # px py pz qw qx qy qz, as the CSV has them
            child = "cam0" if a.keyframe_poses else "body"
            if a.pose_of == "camera" and not a.keyframe_poses:
                T = np.eye(4)
                T[:3, :3] = quat_to_matrix(*p[3:7])
                T[:3, 3] = p[0:3]
                T = T @ T_body_cam0
                p = list(T[:3, 3]) + matrix_to_quat(T[:3, :3])
                child = "cam0"
            if a.poses == "odometry":
                m = Odometry()
                m.header.stamp, m.header.frame_id, m.child_frame_id = t, "world", child
                pose = m.pose.pose
                pose.position.x, pose.position.y, pose.position.z = p[0:3]
                pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z = p[3:7]
            else:
                tr = TransformStamped()
                tr.header.stamp, tr.header.frame_id, tr.child_frame_id = t, "world", child
                tr.transform.translation.x, tr.transform.translation.y, tr.transform.translation.z = p[0:3]
                r = tr.transform.rotation
                r.w, r.x, r.y, r.z = p[3:7]
                m = TFMessage(transforms=[tr])
        elif order >= 3:
            m = camera_infos[order - 3]
            m.header.stamp = t
        else:
            pixels = cv2.imread(payload, cv2.IMREAD_UNCHANGED)
            if a.images == "bayer":
                mosaic = bayer_mosaic(pixels, "rggb")
                m = Image()
                m.height, m.width = mosaic.shape
                m.encoding, m.step, m.data = "bayer_rggb8", m.width, mosaic.tobytes()
                if a.decoded_folder:
                    save_decoded(cv2.cvtColor(mosaic, cv2.COLOR_BayerRGGB2BGR), payload)
            elif a.images == "raw":
                m = Image()
                m.height, m.width = pixels.shape[:2]
                m.encoding = "bgr8" if pixels.ndim == 3 else "mono8"
                m.step = m.width * (3 if pixels.ndim == 3 else 1)
                m.data = pixels.tobytes()
            else:
                m = CompressedImage()
                if a.images == "png":
                    m.format = "png"
                    m.data = open(payload, "rb").read()
                else:
                    m.format = "bgr8; jpeg compressed bgr8"
                    m.data = cv2.imencode(".jpg", pixels, [cv2.IMWRITE_JPEG_QUALITY, 95])[1].tobytes()
                    if a.decoded_folder:
                        save_decoded(cv2.imdecode(np.frombuffer(m.data, np.uint8), cv2.IMREAD_UNCHANGED), payload)
            m.header.stamp = t
            m.header.frame_id = "cam0" if order == 1 else "cam1"
        bag.write(topic, m, t)
