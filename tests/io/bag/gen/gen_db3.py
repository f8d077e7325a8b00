#!/usr/bin/env python3
"""gen_db3.py OUT_DIR: writes the ROS 2 sqlite3 bags the .db3 tests read, with Python's own sqlite3 and
the CDR bytes Foxglove's serialiser wrote for the MCAP files (OUT_DIR/expected.json, from gen_mcap.js).

  dive_db3/            metadata.yaml + dive_db3_0.db3, dive_db3_1.db3 (split in time, as rosbag2 splits),
                       rows inserted out of time order, a topic of another serialisation format
  dive_db3_cut/        the same .db3 files without metadata.yaml (a recorder that never finished)
  dive_db3_message/    the same bag with compression_mode MESSAGE: each message's bytes zstd-compressed
  dive_db3_file/       the same bag with compression_mode FILE: dive_db3_file_0.db3.zstd, ..._1.db3.zstd
                       (the second streamed, without its content size)
  dive_db3_file_wal/   the same, its files in WAL mode (rosbag2's resilient storage preset)
  dive_db3_wal/        dive_db3 in WAL mode
  dive_db3_wal_killed/ a WAL-mode recorder killed before its first checkpoint: each .db3 with its -wal
                       file, the messages in the -wal files only, no metadata.yaml
  dive_db3_unfinished_file/     no metadata.yaml, dive_db3_0.db3.zstd and dive_db3_1.db3 (a FILE-compressing
                                recorder stopped with its second file open)
  dive_db3_unfinished_message/  dive_db3_message's files without metadata.yaml
  dive_db3_damaged/    dive_db3_message with one message's bytes not zstd (damaged.json: its file, row id, topic)
  malformed.db3        dive_db3_0.db3 with the root page of its messages table damaged
  not_a_database.db3   text
The tables are rosbag2's (Humble) and its zstd compression, written by rosbag2_db3.py.
"""
import json
import os
import random
import shutil
import sqlite3
import sys

from rosbag2_db3 import compress_file, compress_message, create_db3, metadata_yaml

out = sys.argv[1]
with open(os.path.join(out, "expected.json")) as f:
    expected = json.load(f)

messages = expected["messages"]
split = len(messages) // 2  # the first half in file 0, the rest in file 1
topics = [(t["name"], t["type"].replace("/", "/msg/", 1), "cdr", t["count"]) for t in expected["topics"]]
first = min(int(m["log_time_ns"]) for m in messages)
last = max(int(m["log_time_ns"]) for m in messages)


def fill_file(db, index, rng, compression_mode=""):
    """Writes file `index` of a bag's two (the first half of the messages, or the rest) into `db`, its row
    ids shuffled by `rng`."""
    part = messages[:split] if index == 0 else messages[split:]
    # Topic ids differ between the files (each file numbers its own topics), in another order.
    ordered = expected["topics"] if index == 0 else list(reversed(expected["topics"]))
    ids = {}
    for i, t in enumerate(ordered):
        ids[t["name"]] = i + 1 + 10 * index
        ros2type = t["type"].replace("/", "/msg/", 1)
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (ids[t["name"]], t["name"], ros2type))
    db.execute("INSERT INTO topics VALUES (99, '/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', 'json', '')")
    rows = [(ids[m["topic"]], int(m["log_time_ns"]), bytes.fromhex(m["data"])) for m in part]
    rows.append((99, int(part[0]["log_time_ns"]), b'{"level":0}'))
    if compression_mode == "MESSAGE":
        rows = [(topic, stamp, compress_message(data)) for topic, stamp, data in rows]
    order = list(range(len(rows)))
    rng.shuffle(order)  # row ids out of time order: the reader must sort by timestamp
    for row_id, k in enumerate(order):
        db.execute("INSERT INTO messages VALUES (?, ?, ?, ?)", (row_id + 1,) + rows[k])
    db.commit()


def write_bag(name, compression_mode="", wal=False):
    """The bag OUT_DIR/name in two files, compressed as rosbag2's compression_mode says; `wal`: its files
    in WAL mode, as rosbag2's resilient storage preset writes them."""
    bag = os.path.join(out, name)
    shutil.rmtree(bag, ignore_errors=True)
    os.makedirs(bag)
    files = [f"{name}_0.db3", f"{name}_1.db3"]
    rng = random.Random(15)
    for index, file in enumerate(files):
        db = create_db3(os.path.join(bag, file))
        fill_file(db, index, rng, compression_mode)
        if wal:
            db.execute("PRAGMA journal_mode = WAL")
        db.close()
        if compression_mode == "FILE":
            files[index] = compress_file(os.path.join(bag, file), streamed=index == 1)
    with open(os.path.join(bag, "metadata.yaml"), "w") as f:
        f.write(metadata_yaml(topics, len(messages), files, first, last, compression_mode))
    return bag, files


def write_killed_wal_bag(name):
    """A recorder in WAL mode killed before its first checkpoint: OUT_DIR/name holds each .db3 with its
    -wal file, the messages in the -wal files only, and no metadata.yaml."""
    bag = os.path.join(out, name)
    work = bag + ".work"
    for folder in (bag, work):
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
    rng = random.Random(15)
    for index in range(2):
        file = f"{name}_{index}.db3"
        db = create_db3(os.path.join(work, file))
        db.commit()  # the journal mode changes outside a transaction only
        assert db.execute("PRAGMA journal_mode = WAL").fetchone()[0] == "wal"
        db.execute("PRAGMA wal_autocheckpoint = 0")  # every message stays in the -wal file
        fill_file(db, index, rng)
        for suffix in ("", "-wal"):  # copied while the writer still has them open, as a kill leaves them
            shutil.copyfile(os.path.join(work, file + suffix), os.path.join(bag, file + suffix))
        db.close()
        # The .db3 alone (sqlite's immutable=1 ignores the -wal file) holds no message: the test reads
        # what only the -wal file has.
        alone = sqlite3.connect(f"file:{os.path.join(bag, file)}?immutable=1", uri=True)
        assert alone.execute("SELECT COUNT(*) FROM messages").fetchone()[0] == 0
        alone.close()
    shutil.rmtree(work)


bag, files = write_bag("dive_db3")
write_bag("dive_db3_message", "MESSAGE")
write_bag("dive_db3_file", "FILE")
write_bag("dive_db3_file_wal", "FILE", wal=True)
write_bag("dive_db3_wal", wal=True)
write_killed_wal_bag("dive_db3_wal_killed")

# One MESSAGE-compressed message's bytes replaced by bytes that are not zstd.
damaged = os.path.join(out, "dive_db3_damaged")
shutil.rmtree(damaged, ignore_errors=True)
shutil.copytree(os.path.join(out, "dive_db3_message"), damaged)
os.rename(os.path.join(damaged, "dive_db3_message_1.db3"), os.path.join(damaged, "dive_db3_damaged_1.db3"))
with open(os.path.join(damaged, "metadata.yaml")) as f:
    text = f.read().replace("dive_db3_message_1.db3", "dive_db3_damaged_1.db3")
with open(os.path.join(damaged, "metadata.yaml"), "w") as f:
    f.write(text)
db = sqlite3.connect(os.path.join(damaged, "dive_db3_damaged_1.db3"))
row_id, topic = db.execute("SELECT messages.id, topics.name FROM messages JOIN topics ON topics.id = topic_id "
                           "WHERE topics.serialization_format = 'cdr' ORDER BY timestamp, messages.id LIMIT 1 OFFSET 3"
                           ).fetchone()
db.execute("UPDATE messages SET data = ? WHERE id = ?", (b"\x00\x01\x00\x00not zstd", row_id))
db.commit()
db.close()
with open(os.path.join(damaged, "damaged.json"), "w") as f:
    json.dump({"file": "dive_db3_damaged_1.db3", "row_id": row_id, "topic": topic}, f)

cut = os.path.join(out, "dive_db3_cut")
shutil.rmtree(cut, ignore_errors=True)
os.makedirs(cut)
for name in files:
    shutil.copy(os.path.join(bag, name), cut)
# Recorders that never finished, compressing by file (the open file still plain) or by message.
unfinished = os.path.join(out, "dive_db3_unfinished_file")
shutil.rmtree(unfinished, ignore_errors=True)
os.makedirs(unfinished)
for name in files:
    shutil.copy(os.path.join(bag, name), unfinished)
compress_file(os.path.join(unfinished, files[0]))
unfinished = os.path.join(out, "dive_db3_unfinished_message")
shutil.rmtree(unfinished, ignore_errors=True)
shutil.copytree(os.path.join(out, "dive_db3_message"), unfinished)
os.remove(os.path.join(unfinished, "metadata.yaml"))

# A file damaged inside the messages table: its root page's type byte zeroed. sqlite opens it and reads
# the topics; reading the messages finds the damage.
malformed = os.path.join(out, "malformed.db3")
shutil.copy(os.path.join(bag, files[0]), malformed)
db = sqlite3.connect(malformed)
page_size = db.execute("PRAGMA page_size").fetchone()[0]
root = db.execute("SELECT rootpage FROM sqlite_master WHERE name = 'messages'").fetchone()[0]
db.close()
with open(malformed, "r+b") as f:
    f.seek((root - 1) * page_size)
    f.write(b"\0")

with open(os.path.join(out, "not_a_database.db3"), "w") as f:
    f.write("this is not a database, but it is long enough to have a header of a hundred bytes or so, "
            "which sqlite reads first and rejects\n")
