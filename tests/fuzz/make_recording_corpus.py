#!/usr/bin/env python3
"""Writes the seed corpus of the recording harness (recording_fuzz.cpp), each file made by an
independent writer, with the harness's first byte in front (0: one file; 1: a ROS 2 bag folder,
metadata.yaml NUL file name NUL file bytes):

  ros1_{images,poses,encodings}_{none,bz2,lz4}.bag  ROS's own rosbag (python3-rosbag): mono8 and bgr8
                       images, a PNG (OpenCV) and a JPEG CompressedImage, a CameraInfo; Odometry,
                       PoseStamped, TransformStamped and a TFMessage; Bayer, 16-bit, RGBA and YUV 4:2:2
                       images; small chunks, so that there are several
  ros1_cut_lz4.bag     ros1_images_lz4.bag cut inside its last chunk (no index); ros1_crashed_lz4.bag the
                       same as a killed recorder leaves it (index_pos 0, the open chunk's sizes 0)
  mcap_*.mcap          the MCAP team's writer (@mcap/core) and Foxglove's CDR serialiser, as the io/bag
                       tests generate them (tests/io/bag/gen/gen_mcap.js): none, zstd, lz4, unchunked,
                       no summary
  db3_file.db3         a .db3 file of Python's sqlite3 (tests/io/bag/gen/gen_db3.py) on its own
  db3_{plain,message,file}_folder  the same bags as folders, their metadata.yaml listing the one file
  db3_unfinished_folder  a .db3.zstd file without metadata.yaml (a recorder that did not finish)

Usage (the ROS 2 recordings come from a build tree: cmake --build build --target ros2_bag_data):
  /usr/bin/python3 tests/fuzz/make_recording_corpus.py tests/fuzz/corpus/recording build/tests/io/bag/ros2_data
Run once and commit the files. Every file stays under the 64 KiB `make fuzz` gives an input.
"""
import os
import re
import sys

import cv2
import numpy as np
import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from tf2_msgs.msg import TFMessage

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "io", "bag"))
from bag_fixtures import killed_recorder  # noqa: E402

out, ros2_data = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
MAX_BYTES = 65536


def write(name, layout, payload):
    data = bytes([layout]) + payload
    assert len(data) <= MAX_BYTES, "%s: %d bytes" % (name, len(data))
    with open(os.path.join(out, name), "wb") as f:
        f.write(data)
    print("%s: %d bytes" % (name, len(data)))


def read(path):
    with open(path, "rb") as f:
        return f.read()


def folder(metadata, file_name, file_bytes):
    return metadata + b"\0" + file_name.encode() + b"\0" + file_bytes


def t(i):
    return rospy.Time(1700000000 + i, 250000000)


def image(encoding, width, height, channels, i):
    m = Image()
    m.header.stamp, m.header.frame_id = t(i), "cam0"
    m.height, m.width, m.encoding, m.is_bigendian = height, width, encoding, 0
    m.step = width * channels
    m.data = bytes((k * 7 + i) % 256 for k in range(width * height * channels))
    return m


def compressed(ext, fmt, i):
    grey = (np.arange(48, dtype=np.uint8).reshape(6, 8) * 5 + i).astype(np.uint8)
    m = CompressedImage()
    m.header.stamp, m.header.frame_id = t(i), "cam0"
    m.format = fmt
    m.data = cv2.imencode(ext, grey)[1].tobytes()
    return m


def camera_info(i):
    m = CameraInfo()
    m.header.stamp, m.header.frame_id = t(i), "cam0"
    m.height, m.width, m.distortion_model = 6, 8, "plumb_bob"
    m.D = [-0.1, 0.01, 0.001, -0.002, 0.0]
    m.K = [400.0, 0, 4.0, 0, 401.0, 3.0, 0, 0, 1]
    m.R = [1, 0, 0, 0, 1, 0, 0, 0, 1]
    m.P = [390.0, 0, 4.0, -39.0, 0, 390.0, 3.0, 0, 0, 0, 1, 0]
    return m


def transform(parent, child, i):
    m = TransformStamped()
    m.header.stamp, m.header.frame_id, m.child_frame_id = t(i), parent, child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = 0.5 * i, -0.25, 1.0
    m.transform.rotation.z, m.transform.rotation.w = 0.6, 0.8
    return m


def images_bag(path, compression):
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=1024) as bag:
        for i in range(3):
            bag.write("/cam0/image_raw", image("mono8", 8, 6, 1, i), t(i))
            bag.write("/cam1/image_raw", image("bgr8", 4, 3, 3, i), t(i))
            bag.write("/cam0/image_raw/compressed", compressed(".png", "png", i), t(i))
            if i == 0:
                bag.write("/cam0/camera_info", camera_info(i), t(i))
                bag.write("/cam1/image_raw/compressed", compressed(".jpg", "mono8; jpeg compressed bgr8", i), t(i))


def encodings_bag(path, compression):
    """One small image in each kind of encoding sensor_msgs/Image has beyond 8-bit grey and colour."""
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=1024) as bag:
        for i, (encoding, channels, sample_bytes, bigendian) in enumerate(
                (("bayer_rggb8", 1, 1, 0), ("bayer_grbg16", 1, 2, 1), ("mono16", 1, 2, 0), ("rgb16", 3, 2, 1),
                 ("rgba8", 4, 1, 0), ("yuv422", 2, 1, 0), ("yuyv", 2, 1, 0))):
            m = image(encoding, 4, 4, channels * sample_bytes, i)
            m.is_bigendian = bigendian
            bag.write("/cam%d/image_raw" % i, m, t(i))


def poses_bag(path, compression):
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=1024) as bag:
        for i in range(3):
            odom = Odometry()
            odom.header.stamp, odom.header.frame_id, odom.child_frame_id = t(i), "world", "cam0"
            odom.pose.pose.position.x = float(i)
            odom.pose.pose.orientation.w = 1.0
            bag.write("/odom", odom, t(i))
            pose = PoseStamped()
            pose.header.stamp, pose.header.frame_id = t(i), "world"
            pose.pose.orientation.z, pose.pose.orientation.w = 0.6, 0.8
            bag.write("/pose", pose, t(i))
            bag.write("/transform", transform("world", "cam0", i), t(i))
            tf = TFMessage()
            tf.transforms = [transform("odom", "base", i), transform("/world", "/cam0", i)]
            bag.write("/tf", tf, t(i))


for compression in ("none", "bz2", "lz4"):
    for kind, writer in (("images", images_bag), ("poses", poses_bag), ("encodings", encodings_bag)):
        path = os.path.join(out, "ros1_%s_%s.bag" % (kind, compression))
        writer(path, compression)
        data = read(path)
        os.remove(path)
        write("ros1_%s_%s.bag" % (kind, compression), 0, data)

# Cut inside the last chunk, its index gone; and the same as a killed recorder leaves it.
path = os.path.join(out, "images_lz4.tmp")
images_bag(path, "lz4")
with rosbag.Bag(path) as bag:
    last = bag._chunks[-1]
    header = bag._chunk_headers[last.pos]
    cut = header.data_pos + header.compressed_size // 2
raw = read(path)[:cut]
os.remove(path)
write("ros1_cut_lz4.bag", 0, raw)
write("ros1_crashed_lz4.bag", 0, killed_recorder(raw, last.pos))

for name in ("none", "zstd", "lz4", "unchunked", "nosummary"):
    write("mcap_%s.mcap" % name, 0, read(os.path.join(ros2_data, "dive_%s.mcap" % name)))


def one_file_metadata(bag, file_name):
    """The bag's metadata.yaml with relative_file_paths listing `file_name` alone."""
    text = read(os.path.join(ros2_data, bag, "metadata.yaml"))
    head, paths = text.split(b"relative_file_paths:")
    rest = re.sub(rb"^(\s*- [^\n]*\n?)+", b"", paths.lstrip(b"\n"))
    return head + b"relative_file_paths:\n    - " + file_name.encode() + b"\n" + rest


write("db3_file.db3", 0, read(os.path.join(ros2_data, "dive_db3", "dive_db3_0.db3")))
for kind, bag, file_name in (("plain", "dive_db3", "dive_db3_0.db3"),
                             ("message", "dive_db3_message", "dive_db3_message_0.db3"),
                             ("file", "dive_db3_file", "dive_db3_file_0.db3.zstd")):
    file_bytes = read(os.path.join(ros2_data, bag, file_name))
    write("db3_%s_folder" % kind, 1, folder(one_file_metadata(bag, file_name), file_name, file_bytes))
write("db3_unfinished_folder", 1,
      folder(b"", "dive_db3_0.db3.zstd", read(os.path.join(ros2_data, "dive_db3_unfinished_file", "dive_db3_0.db3.zstd"))))
