#!/usr/bin/env python3
"""Damages one chunk of a ROS 1 bag or an MCAP file, and trims the EuRoC dive it came from to the
frames and poses that survive, so that a run on the damaged recording can be compared with a run on
the trimmed folder.

Usage: damage_chunk.py IN OUT --mode record|data [--euroc DIVE --euroc-out TRIMMED]
  Chunk: the middle one of the file (the first holds the connection / channel definitions).
  record: ROS 1 (an uncompressed chunk): the header length of its middle message record becomes
          0xfffffff0, so that record runs past the chunk's end; the messages before it survive.
          MCAP (an uncompressed chunk): 64 bytes in the middle of its records are inverted, so the
          chunk's CRC no longer matches.
  data:   64 bytes in the middle of the chunk's stored (compressed) data are inverted.
Prints JSON: offset (the chunk record's byte offset), size (uncompressed), inner (ROS 1 record mode:
the damaged record's offset in the chunk), stored_crc / actual_crc (MCAP record mode), held (topic ->
log times in ns of the chunk's messages, as the index records after it list them; held_order: their
topics in that order; held_text: "of its N messages: n on /topic, ..."), lost (the same for the
messages that no longer read).
--euroc: copies DIVE to TRIMMED without the frames of which an image is lost and without the lost
ground-truth poses (images symlinked). Topics: /left, /cam0 -> cam0; /right, /cam1 -> cam1; /odom.
"""
import argparse
import json
import os
import shutil
import struct
import zlib

ap = argparse.ArgumentParser()
ap.add_argument("inp")
ap.add_argument("out")
ap.add_argument("--mode", required=True, choices=["record", "data"])
ap.add_argument("--euroc")
ap.add_argument("--euroc-out")
a = ap.parse_args()
buf = bytearray(open(a.inp, "rb").read())


held = []  # (offset, topic, ns) of every message the chunk holds, in the index records' order


def invert(start, n=64):
    for i in range(start, start + n):
        buf[i] ^= 0xFF


def ros1_fields(data):
    fields, i = {}, 0
    while i < len(data):
        (n,) = struct.unpack_from("<I", data, i)
        name, value = bytes(data[i + 4 : i + 4 + n]).split(b"=", 1)
        fields[name.decode()] = value
        i += 4 + n
    return fields


def ros1():
    records, pos = [], 13  # "#ROSBAG V2.0\n"
    while pos + 8 <= len(buf):
        (hl,) = struct.unpack_from("<I", buf, pos)
        fields = ros1_fields(buf[pos + 4 : pos + 4 + hl])
        (dl,) = struct.unpack_from("<I", buf, pos + 4 + hl)
        records.append((pos, fields, pos + 8 + hl, dl))
        pos += 8 + hl + dl
    topic_of = {struct.unpack("<I", f["conn"])[0]: f["topic"].decode() for _, f, _, _ in records if f["op"] == b"\x07"}
    chunks = [i for i, r in enumerate(records) if r[1]["op"] == b"\x05"]
    k = chunks[len(chunks) // 2]
    offset, fields, data_pos, data_len = records[k]
    entries = []  # (offset in the chunk, topic, ns)
    for _, f, dp, dl in records[k + 1 :]:
        if f["op"] != b"\x04":
            break
        topic = topic_of[struct.unpack("<I", f["conn"])[0]]
        for j in range(0, dl, 12):
            sec, nsec, off = struct.unpack_from("<III", buf, dp + j)
            entries.append((off, topic, sec * 1000000000 + nsec))
    held.extend(entries)
    result = {"offset": offset, "size": struct.unpack("<I", fields["size"])[0]}
    if a.mode == "record":
        assert fields["compression"] == b"none"
        entries.sort()
        inner = entries[len(entries) // 2][0]
        struct.pack_into("<I", buf, data_pos + inner, 0xFFFFFFF0)
        result["inner"] = inner
        entries = [e for e in entries if e[0] >= inner]
    else:
        invert(data_pos + data_len // 2)
    return result, entries


def mcap_records(start, end):
    pos = start
    while pos + 9 <= end:
        op = buf[pos]
        (n,) = struct.unpack_from("<Q", buf, pos + 1)
        yield pos, op, pos + 9, n
        pos += 9 + n


def mcap():
    topic_of, chunks, all_records = {}, [], list(mcap_records(8, len(buf) - 8))
    for i, (pos, op, c, n) in enumerate(all_records):
        if op == 0x04:  # channel: id u16, schema u16, topic string
            (tl,) = struct.unpack_from("<I", buf, c + 4)
            topic_of[struct.unpack_from("<H", buf, c)[0]] = bytes(buf[c + 8 : c + 8 + tl]).decode()
        elif op == 0x06:
            chunks.append(i)
    k = chunks[len(chunks) // 2]
    offset, _, c, n = all_records[k]
    size, crc, cl = struct.unpack_from("<QII", buf, c + 16)
    compression = bytes(buf[c + 32 : c + 32 + cl]).decode()
    (rl,) = struct.unpack_from("<Q", buf, c + 32 + cl)
    records = c + 40 + cl
    entries = []
    for _, op, mc, mn in all_records[k + 1 :]:
        if op != 0x07:
            break
        (channel,) = struct.unpack_from("<H", buf, mc)
        for j in range(mc + 6, mc + mn, 16):
            (ns,) = struct.unpack_from("<Q", buf, j)
            entries.append((0, topic_of[channel], ns))
    held.extend(entries)
    invert(records + rl // 2)
    result = {"offset": offset, "size": size}
    if a.mode == "record":
        assert compression == "" and crc != 0
        result["stored_crc"] = "0x%08x" % crc
        result["actual_crc"] = "0x%08x" % zlib.crc32(bytes(buf[records : records + rl]))
    return result, entries


result, lost = ros1() if buf.startswith(b"#ROSBAG") else mcap()
open(a.out, "wb").write(buf)
result["lost"], result["held"], result["held_order"] = {}, {}, []
for _, topic, ns in held:
    if topic not in result["held"]:
        result["held_order"].append(topic)
    result["held"].setdefault(topic, []).append(ns)
result["held_text"] = "of its %d messages: " % len(held) + ", ".join(
    "%d on %s" % (len(result["held"][t]), t) for t in result["held_order"])
for _, topic, ns in lost:
    result["lost"].setdefault(topic, []).append(ns)
print(json.dumps(result))

if a.euroc:
    gone = {ns for t, stamps in result["lost"].items() if t != "/odom" for ns in stamps}
    gone_poses = set(result["lost"].get("/odom", []))
    shutil.rmtree(a.euroc_out, ignore_errors=True)
    for root, dirs, files in os.walk(a.euroc):
        rel = os.path.relpath(root, a.euroc)
        os.makedirs(os.path.join(a.euroc_out, rel), exist_ok=True)
        for f in files:
            src, dst = os.path.join(root, f), os.path.join(a.euroc_out, rel, f)
            if f != "data.csv":
                os.symlink(os.path.abspath(src), dst)
                continue
            drop = gone_poses if "groundtruth" in rel else gone if rel.split(os.sep)[-1] in ("cam0", "cam1") else set()
            with open(src) as i, open(dst, "w") as o:
                for line in i:
                    head = line.split(",", 1)[0].strip()
                    if not (head.isdigit() and int(head) in drop):
                        o.write(line)
