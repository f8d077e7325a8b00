"""Byte-level forms of test recordings, shared by their generators (write_test_bags.py,
euroc_to_bag.py, tests/fuzz/make_recording_corpus.py)."""
import struct

import numpy as np


def killed_recorder(raw, chunk_pos):
    """A ROS 1 bag cut inside the chunk at `chunk_pos` as a killed recorder leaves it: rosbag writes
    index_pos 0 when it opens the bag and a chunk header with data length and size 0 when it opens a
    chunk, and fills them in only on closing."""
    crashed = bytearray(raw)
    at = crashed.index(b"index_pos=") + len(b"index_pos=")
    crashed[at:at + 8] = struct.pack("<Q", 0)
    header_len = struct.unpack_from("<I", crashed, chunk_pos)[0]
    at = crashed.index(b"size=", chunk_pos, chunk_pos + 4 + header_len) + len(b"size=")
    crashed[at:at + 4] = struct.pack("<I", 0)
    struct.pack_into("<I", crashed, chunk_pos + 4 + header_len, 0)
    return bytes(crashed)


def bayer_mosaic(bgr, pattern):
    """The colour filter mosaic of a BGR image: `pattern` names the colours of (0, 0), (0, 1), (1, 0),
    (1, 1) as ROS does (rggb: R G on even rows, G B on odd rows)."""
    out = np.zeros(bgr.shape[:2], bgr.dtype)
    for i, colour in enumerate(pattern):
        out[i // 2::2, i % 2::2] = bgr[i // 2::2, i % 2::2, "bgr".index(colour)]
    return out
