"""rosbag2_db3.py: what the two .db3 writers (gen_db3.py, mcap_to_db3.py) share: a ROS 2 sqlite3 bag file
in rosbag2's tables (Humble), written by Python's own sqlite3, and its metadata.yaml; rosbag2's zstd
compression (rosbag2_compression) through Debian's python3-zstandard.
The tables: topics(id, name, type, serialization_format, offered_qos_profiles), messages(id, topic_id,
timestamp, data) with its timestamp index.
Compression as rosbag2 writes it: compression_mode MESSAGE compresses each message's serialized bytes
(one zstd frame, level 1, content size stored: ZSTD_compress); FILE compresses each closed .db3 file
whole into <name>.zstd and lists that name in relative_file_paths; metadata.yaml then says
compression_format: zstd and compression_mode: MESSAGE or FILE ("" and "" uncompressed)."""
import os
import sqlite3

import zstandard

SCHEMA = """
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                    serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,
                      data BLOB NOT NULL);
CREATE INDEX timestamp_idx ON messages (timestamp ASC);
"""


def create_db3(path):
    """A new .db3 file at `path` with rosbag2's (empty) tables; the caller inserts topics and messages."""
    db = sqlite3.connect(path)
    db.executescript(SCHEMA)
    db.execute("INSERT INTO schema VALUES (3, 'humble')")
    return db


def compress_message(data):
    """A message's bytes as compression_mode MESSAGE stores them."""
    return zstandard.ZstdCompressor(level=1).compress(data)


def compress_file(path, streamed=False):
    """Replaces the .db3 file `path` by path + ".zstd", as compression_mode FILE does once a file is
    closed; `streamed`: without the content size in the frame header (a streaming compressor's
    output) instead of ZSTD_compress's one frame with it. Returns the new file's name."""
    cctx = zstandard.ZstdCompressor(level=1)
    with open(path, "rb") as src, open(path + ".zstd", "wb") as dst:
        if streamed:
            cctx.copy_stream(src, dst)
        else:
            dst.write(cctx.compress(src.read()))
    os.remove(path)
    return os.path.basename(path) + ".zstd"


def metadata_yaml(topics, message_count, files, first_ns=None, last_ns=None, compression_mode=""):
    """metadata.yaml of a bag: `topics` as (name, ROS 2 type, serialization format, message count), the
    bag's .db3 `files`; the time span when `first_ns` and `last_ns` are given; compression_mode
    "MESSAGE" or "FILE" with compression_format zstd, as rosbag2 writes them."""
    counts = "\n".join(
        f"    - topic_metadata:\n        name: {name}\n        type: {type_name}\n"
        f"        serialization_format: {encoding}\n        offered_qos_profiles: \"\"\n      message_count: {count}"
        for name, type_name, encoding, count in topics)
    span = "" if first_ns is None else (f"  duration:\n    nanoseconds: {last_ns - first_ns}\n"
                                        f"  starting_time:\n    nanoseconds_since_epoch: {first_ns}\n")
    paths = "".join(f"    - {name}\n" for name in files)
    compression_format = "zstd" if compression_mode else '""'
    return (f"rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n{span}"
            f"  message_count: {message_count}\n  topics_with_message_count:\n{counts}\n"
            f"  compression_format: {compression_format}\n"
            f"  compression_mode: {compression_mode or compression_format}\n  relative_file_paths:\n{paths}")
