#!/usr/bin/env python3
"""gen_db3.py OUT_DIR: writes the ROS 2 sqlite3 bags the .db3 tests read, with Python's own sqlite3 and
the CDR bytes Foxglove's serialiser wrote for the MCAP files (OUT_DIR/expected.json, from gen_mcap.js).

  dive_db3/            metadata.yaml + dive_db3_0.db3, dive_db3_1.db3 (split in time, as rosbag2 splits),
                       rows inserted out of time order, a topic of another serialisation format
  dive_db3_cut/        the same .db3 files without metadata.yaml (a recorder that never finished)
  not_a_database.db3   text
The tables are rosbag2's (Humble), written by rosbag2_db3.py.
"""
import json
import os
import random
import shutil
import sys

from rosbag2_db3 import create_db3, metadata_yaml

out = sys.argv[1]
with open(os.path.join(out, "expected.json")) as f:
    expected = json.load(f)

bag = os.path.join(out, "dive_db3")
shutil.rmtree(bag, ignore_errors=True)
os.makedirs(bag)
messages = expected["messages"]
split = len(messages) // 2  # the first half in file 0, the rest in file 1
files = ["dive_db3_0.db3", "dive_db3_1.db3"]
rng = random.Random(15)
for index, name in enumerate(files):
    part = messages[:split] if index == 0 else messages[split:]
    db = create_db3(os.path.join(bag, name))
    # Topic ids differ between the files (each file numbers its own topics), in another order.
    topics = expected["topics"] if index == 0 else list(reversed(expected["topics"]))
    ids = {}
    for i, t in enumerate(topics):
        ids[t["name"]] = i + 1 + 10 * index
        ros2type = t["type"].replace("/", "/msg/", 1)
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (ids[t["name"]], t["name"], ros2type))
    db.execute("INSERT INTO topics VALUES (99, '/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', 'json', '')")
    rows = [(ids[m["topic"]], int(m["log_time_ns"]), bytes.fromhex(m["data"])) for m in part]
    rows.append((99, int(part[0]["log_time_ns"]), b'{"level":0}'))
    order = list(range(len(rows)))
    rng.shuffle(order)  # row ids out of time order: the reader must sort by timestamp
    for row_id, k in enumerate(order):
        db.execute("INSERT INTO messages VALUES (?, ?, ?, ?)", (row_id + 1,) + rows[k])
    db.commit()
    db.close()

topics = [(t["name"], t["type"].replace("/", "/msg/", 1), "cdr", t["count"]) for t in expected["topics"]]
first = min(int(m["log_time_ns"]) for m in messages)
last = max(int(m["log_time_ns"]) for m in messages)
with open(os.path.join(bag, "metadata.yaml"), "w") as f:
    f.write(metadata_yaml(topics, len(messages), files, first, last))

cut = os.path.join(out, "dive_db3_cut")
shutil.rmtree(cut, ignore_errors=True)
os.makedirs(cut)
for name in files:
    shutil.copy(os.path.join(bag, name), cut)
with open(os.path.join(out, "not_a_database.db3"), "w") as f:
    f.write("this is not a database, but it is long enough to have a header of a hundred bytes or so, "
            "which sqlite reads first and rejects\n")
