#!/usr/bin/env python3
"""Writes the ROS 1 bags of tests/io/bag/ with ROS's own rosbag (python3-rosbag), the reference writer.

Usage: write_test_bags.py OUT_DIR. Writes:
  messages.bag          one message of each type cenote reads, with the values bag_test.cpp expects
  encodings.bag         a 16x12 scene in the image encodings beyond 8-bit grey and colour (/enc/...),
                        each made here with numpy from the scene's definition (see encoded_scenes())
  seq_{none,bz2,lz4}.bag  240 mono8 images (/cam/image, 16x8, pixel value = index) and 240 Odometry
                        (/odom) in 4 KiB chunks, so that there are many chunks
  cut_{none,bz2,lz4}.bag  the same cut in the middle of a chunk (the index gone)
  crashed_{none,bz2,lz4}.bag  cut as a killed recorder leaves them: index_pos 0 in the bag header,
                        data length and size 0 in the header of the chunk being written
  zstd.bag              seq_none.bag with its first chunk's compression renamed 'zstd'
  unindexed_connection.bag  seq_none.bag whose first chunk defines a connection (id 99, /cam/imagX) that
                        the index does not list
  expected.json         for each cut bag: its size, the cut chunk's position and the number of
                        complete messages before the cut, from rosbag's own index
"""
import json
import os
import shutil
import struct
import sys

import cv2
import numpy as np
import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from tf2_msgs.msg import TFMessage

from bag_fixtures import bayer_mosaic, killed_recorder

out = sys.argv[1]
os.makedirs(out, exist_ok=True)


def stamp(sec, nsec):
    return rospy.Time(sec, nsec)


def image(encoding, width, height, channels, data, t):
    m = Image()
    m.header.stamp = t
    m.header.frame_id = "cam0"
    m.height, m.width, m.encoding, m.is_bigendian = height, width, encoding, 0
    m.step = width * channels
    m.data = bytes(data)
    return m


def transform(parent, child, t, xyz, q):
    m = TransformStamped()
    m.header.stamp = t
    m.header.frame_id = parent
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = xyz
    r = m.transform.rotation
    r.x, r.y, r.z, r.w = q
    return m


t0 = stamp(1700000000, 123456789)
with rosbag.Bag(os.path.join(out, "messages.bag"), "w") as bag:
    # 3x2 images: mono8 0..5; bgr8 and rgb8 with pixel i = (i, 10 + i, 20 + i) in their own order.
    bag.write("/cam/mono", image("mono8", 3, 2, 1, range(6), t0), t0)
    bag.write("/cam/bgr", image("bgr8", 3, 2, 3, [v for i in range(6) for v in (i, 10 + i, 20 + i)], t0), t0)
    bag.write("/cam/rgb", image("rgb8", 3, 2, 3, [v for i in range(6) for v in (20 + i, 10 + i, i)], t0), t0)
    bag.write("/cam/float", image("32FC1", 3, 2, 4, bytes(24), t0), t0)  # an encoding cenote does not read
    grey = (np.arange(48, dtype=np.uint8).reshape(6, 8) * 5).astype(np.uint8)
    for topic, ext, fmt in (("/cam/png", ".png", "png"), ("/cam/jpeg", ".jpg", "mono8; jpeg compressed bgr8")):
        c = CompressedImage()
        c.header.stamp = t0
        c.header.frame_id = "cam0"
        c.format = fmt
        c.data = cv2.imencode(ext, grey, [cv2.IMWRITE_JPEG_QUALITY, 100] if ext == ".jpg" else [])[1].tobytes()
        bag.write(topic, c, t0)
    info = CameraInfo()
    info.header.stamp = t0
    info.header.frame_id = "cam1"
    info.height, info.width = 480, 640
    info.distortion_model = "plumb_bob"
    info.D = [-0.1, 0.01, 0.001, -0.002, 0.0]
    info.K = [400.0, 0, 320.5, 0, 401.0, 240.5, 0, 0, 1]
    info.R = [1, 0, 0, 0, 1, 0, 0, 0, 1]
    info.P = [390.0, 0, 321.0, -39.0, 0, 390.0, 241.0, 0, 0, 0, 1, 0]
    bag.write("/cam/info", info, t0)
    odom = Odometry()
    odom.header.stamp = t0
    odom.header.frame_id = "world"
    odom.child_frame_id = "cam0"
    p = odom.pose.pose
    p.position.x, p.position.y, p.position.z = 1.5, -2.25, 3.0
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = 0.0, 0.0, 0.6, 0.8
    bag.write("/odom", odom, t0)
    ps = PoseStamped()
    ps.header.stamp = t0
    ps.header.frame_id = "world"
    ps.pose = p
    bag.write("/pose", ps, t0)
    bag.write("/tfs", transform("world", "cam0", t0, (1.5, -2.25, 3.0), (0.0, 0.0, 0.6, 0.8)), t0)
    tf = TFMessage()
    tf.transforms = [transform("odom", "base", t0, (9, 9, 9), (0, 0, 0, 1)),
                     transform("/world", "/cam0", t0, (1.5, -2.25, 3.0), (0.0, 0.0, 0.6, 0.8))]
    bag.write("/tf", tf, t0)


# The scene of encodings.bag (ros1_bag_test.cpp defines it again): 16x12, the left 8 columns one
# colour, the right 8 another (B, G, R); and a grey ramp 0..191 for the 16-bit grey images.
SCENE_LEFT, SCENE_RIGHT = (20, 60, 200), (210, 120, 30)
scene = np.zeros((12, 16, 3), np.uint8)
scene[:, :8] = SCENE_LEFT
scene[:, 8:] = SCENE_RIGHT
ramp = np.arange(192, dtype=np.uint32).reshape(12, 16)


def yuv422(bgr, order):
    """YUV 4:2:2 bytes (BT.601, video range, as cameras send it): each pixel pair shares the mean U, V."""
    b, g, r = (bgr[..., k].astype(np.float64) / 255.0 for k in range(3))
    y = 16 + 65.481 * r + 128.553 * g + 24.966 * b
    u = 128 - 37.797 * r - 74.203 * g + 112.0 * b
    v = 128 + 112.0 * r - 93.786 * g - 18.214 * b
    u, v = (u[:, 0::2] + u[:, 1::2]) / 2, (v[:, 0::2] + v[:, 1::2]) / 2
    planes = {"u": u, "v": v, "y0": y[:, 0::2], "y1": y[:, 1::2]}
    out = np.stack([planes[k] for k in order], axis=2).reshape(bgr.shape[0], -1)
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def raw_image(encoding, samples, width, big_endian=False):
    """sensor_msgs/Image of `samples` (rows of uint8 or uint16 samples) in the given byte order."""
    a = np.ascontiguousarray(samples)
    if a.dtype == np.uint16:
        a = a.astype(">u2" if big_endian else "<u2")
    m = Image()
    m.header.stamp = t0
    m.header.frame_id = "cam0"
    m.height, m.width, m.encoding, m.is_bigendian = a.shape[0], width, encoding, int(big_endian)
    m.step = a[0].nbytes
    m.data = a.tobytes()
    return m


def encoded_scenes():
    """(topic, message): the scene as every encoding tested; 16-bit samples are 257 v + 100 (v / 255
    of full scale, plus less than half a step of 8 bits)."""
    wide = lambda a: a.astype(np.uint16) * 257 + 100
    for pattern in ("rggb", "bggr", "gbrg", "grbg"):
        yield "/enc/bayer_%s8" % pattern, raw_image("bayer_%s8" % pattern, bayer_mosaic(scene, pattern), 16)
    yield "/enc/bayer_rggb16", raw_image("bayer_rggb16", wide(bayer_mosaic(scene, "rggb")), 16)
    yield "/enc/bayer_gbrg16_be", raw_image("bayer_gbrg16", wide(bayer_mosaic(scene, "gbrg")), 16, big_endian=True)
    yield "/enc/mono16", raw_image("mono16", wide(ramp), 16)
    yield "/enc/mono16_be", raw_image("mono16", wide(ramp), 16, big_endian=True)
    yield "/enc/mono16_12bit", raw_image("mono16", (ramp * 16).astype(np.uint16), 16)  # 0..4095 used
    yield "/enc/bgr16", raw_image("bgr16", wide(scene), 16)
    yield "/enc/rgb16_be", raw_image("rgb16", wide(scene[..., ::-1]), 16, big_endian=True)
    yield "/enc/rgba16", raw_image("rgba16", wide(np.dstack([scene[..., ::-1], np.full((12, 16), 200, np.uint8)])), 16)
    yield "/enc/yuv422", raw_image("yuv422", yuv422(scene, ("u", "y0", "v", "y1")), 16)
    yield "/enc/yuv422_yuy2", raw_image("yuv422_yuy2", yuv422(scene, ("y0", "u", "y1", "v")), 16)
    yield "/enc/yuv422_odd", raw_image("yuv422", yuv422(scene, ("u", "y0", "v", "y1"))[:, :30], 15)


with rosbag.Bag(os.path.join(out, "encodings.bag"), "w") as bag:
    for topic, message in encoded_scenes():
        bag.write(topic, message, t0)

expected = {}
for compression in ("none", "bz2", "lz4"):
    path = os.path.join(out, "seq_%s.bag" % compression)
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=4096) as bag:
        for i in range(240):
            t = stamp(100 + i // 10, (i % 10) * 100000000)
            bag.write("/cam/image", image("mono8", 16, 8, 1, [i % 256] * 128, t), t)
            odom = Odometry()
            odom.header.stamp = t
            odom.header.frame_id = "world"
            odom.pose.pose.position.x = float(i)
            odom.pose.pose.orientation.w = 1.0
            bag.write("/odom", odom, t)
    # The cut: halfway through the data of the middle chunk.
    with rosbag.Bag(path) as bag:
        chunks = bag._chunks
        headers = bag._chunk_headers
        cut_chunk = chunks[len(chunks) // 2]
        h = headers[cut_chunk.pos]
        cut = h.data_pos + h.compressed_size // 2
        complete = 0
        with open(path, "rb") as f:
            raw = f.read()
        for conn, entries in bag._connection_indexes.items():
            for e in entries:
                ch = headers[e.chunk_pos]
                if ch.data_pos + ch.compressed_size <= cut:
                    complete += 1
                elif e.chunk_pos == cut_chunk.pos and compression == "none":
                    # An uncompressed record is whole when its data end before the cut.
                    at = ch.data_pos + e.offset
                    header_len = struct.unpack_from("<I", raw, at)[0]
                    data_len = struct.unpack_from("<I", raw, at + 4 + header_len)[0]
                    if at + 8 + header_len + data_len <= cut:
                        complete += 1
        # What the middle chunk holds, by topic: what a reader that steps over it loses.
        held = {}
        for conn, entries in bag._connection_indexes.items():
            topic = bag._connections[conn].topic
            n = sum(1 for e in entries if e.chunk_pos == cut_chunk.pos)
            if n:
                held[topic] = n
        total = sum(len(entries) for entries in bag._connection_indexes.values())
    expected["seq_%s.bag" % compression] = {"middle_chunk_pos": cut_chunk.pos, "middle_chunk_data_pos": h.data_pos,
                                            "middle_chunk_held": held, "messages": total}
    cut_path = os.path.join(out, "cut_%s.bag" % compression)
    with open(cut_path, "wb") as f:
        f.write(raw[:cut])
    expected["cut_%s.bag" % compression] = {"size": cut, "chunk_pos": cut_chunk.pos, "complete": complete,
                                            "first_chunk_pos": chunks[0].pos}
    with open(os.path.join(out, "crashed_%s.bag" % compression), "wb") as f:
        f.write(killed_recorder(raw[:cut], cut_chunk.pos))
    expected["crashed_%s.bag" % compression] = dict(expected["cut_%s.bag" % compression])
    if compression == "none":
        zstd = bytearray(raw)
        at = zstd.index(b"compression=none", chunks[0].pos)
        zstd[at:at + 16] = b"compression=zstd"
        with open(os.path.join(out, "zstd.bag"), "wb") as f:
            f.write(zstd)
        expected["zstd.bag"] = {"first_chunk_pos": chunks[0].pos}
        # The first connection record inside the first chunk given an id (99) and a topic (/cam/imagX) the
        # index does not list; the chunk's messages keep their connections.
        unindexed = bytearray(raw)
        at = headers[chunks[0].pos].data_pos
        while True:
            header_len = struct.unpack_from("<I", unindexed, at)[0]
            fields, k = {}, at + 4
            while k < at + 4 + header_len:
                n = struct.unpack_from("<I", unindexed, k)[0]
                name = bytes(unindexed[k + 4:k + 4 + n]).split(b"=", 1)[0]
                fields[name] = (k + 4 + len(name) + 1, n - len(name) - 1)  # where the value is
                k += 4 + n
            if unindexed[fields[b"op"][0]] == 0x07:
                struct.pack_into("<I", unindexed, fields[b"conn"][0], 99)
                start, n = fields[b"topic"]
                assert unindexed[start:start + n] == b"/cam/image"
                unindexed[start + n - 1:start + n] = b"X"
                break
            at += 4 + header_len + 4 + struct.unpack_from("<I", unindexed, at + 4 + header_len)[0]
        with open(os.path.join(out, "unindexed_connection.bag"), "wb") as f:
            f.write(unindexed)

with open(os.path.join(out, "expected.json"), "w") as f:
    json.dump(expected, f, indent=1)
