#!/usr/bin/env python3
"""mcap_to_db3.py IN.mcap OUT_DIR [MESSAGE|FILE]: an MCAP recording with uncompressed chunks (as
euroc_to_mcap.js writes it with compression none) rewritten as a ROS 2 sqlite3 bag: OUT_DIR/metadata.yaml
and OUT_DIR/<name>_0.db3 in rosbag2's tables (Humble), written by Python's own sqlite3, the CDR message
bytes unchanged; with MESSAGE each message's bytes zstd-compressed, with FILE the file compressed whole
(<name>_0.db3.zstd, streamed), as rosbag2's compression_mode does (rosbag2_db3.py). The MCAP records are
read as the specification lays them out (mcap.dev/spec): opcode u8, length u64, fields."""
import os
import struct
import sys

from rosbag2_db3 import compress_file, compress_message, create_db3, metadata_yaml

src, out = sys.argv[1:3]
mode = sys.argv[3] if len(sys.argv) > 3 else ""
assert mode in ("", "MESSAGE", "FILE"), "compression mode: MESSAGE or FILE"
data = open(src, "rb").read()
assert data[:8] == b"\x89MCAP0\r\n", "not an MCAP file"

schemas, channels, messages = {}, {}, []


def string(buf, pos):
    n = struct.unpack_from("<I", buf, pos)[0]
    return buf[pos + 4:pos + 4 + n].decode(), pos + 4 + n


def records(buf, pos, end):
    while pos + 9 <= end:
        op, length = struct.unpack_from("<BQ", buf, pos)
        yield op, buf[pos + 9:pos + 9 + length]
        pos += 9 + length


def read(buf, start, end):
    for op, body in records(buf, start, end):
        if op == 0x03:  # Schema: id u16, name, encoding, data
            sid = struct.unpack_from("<H", body, 0)[0]
            schemas[sid], _ = string(body, 2)
        elif op == 0x04:  # Channel: id u16, schema u16, topic, message encoding, metadata
            cid, sid = struct.unpack_from("<HH", body, 0)
            topic, pos = string(body, 4)
            encoding, _ = string(body, pos)
            channels[cid] = (topic, schemas[sid], encoding)
        elif op == 0x05:  # Message: channel u16, sequence u32, log time u64, publish time u64, data
            cid, _, log_time = struct.unpack_from("<HIQ", body, 0)
            messages.append((cid, log_time, body[22:]))
        elif op == 0x06:  # Chunk: start, end, uncompressed size, crc, compression, records (u64 length)
            compression, pos = string(body, 28)
            assert compression == "", "uncompressed chunks only"
            n = struct.unpack_from("<Q", body, pos)[0]
            read(body, pos + 8, pos + 8 + n)
        elif op == 0x0F:  # DataEnd
            return


read(data, 8, len(data))
os.makedirs(out, exist_ok=True)
name = os.path.basename(os.path.normpath(out)) + "_0.db3"
db = create_db3(os.path.join(out, name))
for cid, (topic, type_name, encoding) in channels.items():
    db.execute("INSERT INTO topics VALUES (?, ?, ?, ?, '')", (cid, topic, type_name, encoding))
rows = [(cid, t, compress_message(data) if mode == "MESSAGE" else data) for cid, t, data in messages]
db.executemany("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", rows)
db.commit()
db.close()
if mode == "FILE":
    name = compress_file(os.path.join(out, name), streamed=True)
topics = [(topic, type_name, encoding, sum(1 for m in messages if m[0] == cid))
          for cid, (topic, type_name, encoding) in channels.items()]
with open(os.path.join(out, "metadata.yaml"), "w") as f:
    f.write(metadata_yaml(topics, len(messages), [name], min(m[1] for m in messages), max(m[1] for m in messages),
                          compression_mode=mode))
