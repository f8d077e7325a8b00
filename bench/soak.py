#!/usr/bin/python3
"""Soak: a long simulated dive against a real cenote-server, as a vehicle runs it (`make soak`,
outside CI). Bounded in time by --minutes (20 by default).

- a simulated cave dive (`cenote sim`) is streamed at camera rate (--rate-hz, 15) with each frame's
  own pose, lap after lap (each lap a new StreamFrames call, its timestamps after the last lap's):
  the same poses see the same space, so the map stops growing after the first lap;
- every --bad-every'th frame (50) is a PNG cut in half, which the server must reject in its ack;
- a planner checks 64 segments at a time through the map, 20 times a second;
- an update subscriber connects every few seconds, reads for a while and drops; every fourth one
  reads nothing at all (a stalled viewer, resynced by the server) before it drops.

Every 30 s it prints the server's resident set (RSS), the frames processed / rejected, the map's
occupied voxels and the planner's query latency (p50 / p99) over the interval. At the end: the
RSS after the first lap against the highest after it, p50 / p99 over the whole run, and every
error that was not a bad frame's rejection. Exits 1 on such an error or a bad frame accepted.

Usage: bench/soak.py BUILD_DIR [--minutes 20] [--rate-hz 15] [--frames 150] [--width 400 --height 300]
"""
import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time

import grpc
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "clients", "python"))
from cenote_client.dive import read_dive  # noqa: E402


def log(*args):
    print(time.strftime("%H:%M:%S"), *args, flush=True)


class Errors:
    def __init__(self):
        self.lock = threading.Lock()
        self.items = []

    def add(self, where, what):
        with self.lock:
            self.items.append(f"{where}: {what}")
            if len(self.items) <= 20:
                log("ERROR", where, what)


def rss_bytes(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


class Soak:
    def __init__(self, args, pb, target, errors):
        self.args, self.pb, self.errors = args, pb, errors
        self.channel = grpc.insecure_channel(target)
        self.ingest = pb["ingest_grpc"].IngestStub(self.channel)
        self.query = pb["query_grpc"].QueryStub(self.channel)
        self.updates = pb["updates_grpc"].UpdatesStub(self.channel)
        self.admin = pb["admin_grpc"].AdminStub(self.channel)
        self.stop = threading.Event()
        self.lock = threading.Lock()
        self.latencies_ms = []  # of the current interval
        self.all_latencies_ms = []
        self.bad_sent = 0
        self.bad_rejected = 0
        self.laps = 0
        self.subscriptions = 0

    def frame(self, t, left, right, position, quaternion, bad):
        msg = self.pb["ingest"].StereoFrame(timestamp_s=t)
        msg.left.encoded = left[:len(left) // 2] if bad else left
        msg.right.encoded = right
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = position
        q = msg.pose.orientation
        q.x, q.y, q.z, q.w = quaternion
        return msg

    def stream_frames(self, frames):
        ingest = self.pb["ingest"]
        span = frames[-1][0] - frames[0][0] + 1.0
        period = 1.0 / self.args.rate_hz
        n = 0
        while not self.stop.is_set():
            offset = self.laps * span
            bad_in_lap = []

            def requests():
                nonlocal n
                next_at = time.monotonic()
                for t, left, right, position, quaternion in frames:
                    if self.stop.is_set():
                        return
                    n += 1
                    bad = n % self.args.bad_every == 0
                    bad_in_lap.append(bad)
                    if bad:
                        self.bad_sent += 1
                    next_at += period
                    time.sleep(max(0.0, next_at - time.monotonic()))
                    yield self.frame(t + offset, left, right, position, quaternion, bad)

            try:
                for ack in self.ingest.StreamFrames(requests(), timeout=3600):
                    bad = bad_in_lap[ack.sequence]
                    rejected = ack.outcome == ingest.FRAME_OUTCOME_REJECTED
                    if bad and rejected:
                        self.bad_rejected += 1
                    elif bad:
                        self.errors.add("StreamFrames", f"bad frame {ack.sequence} of lap {self.laps} was not rejected")
                    elif rejected or ack.outcome == ingest.FRAME_OUTCOME_SKIPPED_NO_POSE:
                        self.errors.add("StreamFrames", f"frame {ack.sequence} of lap {self.laps}: {ack.message}")
            except grpc.RpcError as e:
                if not self.stop.is_set():
                    self.errors.add("StreamFrames", f"{e.code()} {e.details()}")
            self.laps += 1

    def plan(self, lo, hi):
        query = self.pb["query"]
        rng = np.random.default_rng(1)
        while not self.stop.is_set():
            request = query.SegmentsRequest()
            for _ in range(64):
                s = request.segments.add()
                a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
                s.start.x, s.start.y, s.start.z = a
                s.end.x, s.end.y, s.end.z = b
            t0 = time.perf_counter()
            try:
                self.query.CheckSegments(request, timeout=10)
                ms = 1000 * (time.perf_counter() - t0)
                with self.lock:
                    self.latencies_ms.append(ms)
                    self.all_latencies_ms.append(ms)
            except grpc.RpcError as e:
                self.errors.add("CheckSegments", f"{e.code()} {e.details()}")
            time.sleep(0.05)

    def churn_subscribers(self):
        updates = self.pb["updates"]
        rng = random.Random(2)
        while not self.stop.is_set():
            stalled = self.subscriptions % 4 == 3
            self.subscriptions += 1
            call = self.updates.Subscribe(updates.SubscribeRequest(), timeout=120)
            until = time.monotonic() + rng.uniform(1.0, 8.0)
            try:
                if stalled:
                    self.stop.wait(until - time.monotonic())
                else:
                    for _ in call:
                        if time.monotonic() > until or self.stop.is_set():
                            break
            except grpc.RpcError as e:
                if e.code() != grpc.StatusCode.CANCELLED and not self.stop.is_set():
                    self.errors.add("Subscribe", f"{e.code()} {e.details()}")
            call.cancel()
            self.stop.wait(rng.uniform(0.5, 3.0))

    def stats(self):
        return self.admin.GetStats(self.pb["admin"].StatsRequest(), timeout=10)

    def interval_latencies(self):
        with self.lock:
            out, self.latencies_ms = self.latencies_ms, []
        return out


def percentile(values, p):
    return float(np.percentile(values, p)) if values else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build")
    parser.add_argument("--minutes", type=float, default=20.0)
    parser.add_argument("--rate-hz", type=float, default=15.0)
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--width", type=int, default=400)
    parser.add_argument("--height", type=int, default=300)
    parser.add_argument("--bad-every", type=int, default=50)
    parser.add_argument("--report-s", type=float, default=30.0)
    args = parser.parse_args()

    sys.path.insert(0, os.path.join(args.build, "clients", "python", "gen"))
    from cenote.v1 import (admin_pb2, admin_pb2_grpc, ingest_pb2, ingest_pb2_grpc, query_pb2, query_pb2_grpc,
                           updates_pb2, updates_pb2_grpc)
    pb = {"admin": admin_pb2, "admin_grpc": admin_pb2_grpc, "ingest": ingest_pb2, "ingest_grpc": ingest_pb2_grpc,
          "query": query_pb2, "query_grpc": query_pb2_grpc, "updates": updates_pb2, "updates_grpc": updates_pb2_grpc}

    work = tempfile.mkdtemp(prefix="cenote-soak-")
    dive = os.path.join(work, "dive")
    log(f"simulating a {args.frames}-frame cave dive ({args.width}x{args.height}) in {work}")
    subprocess.run([os.path.join(args.build, "apps", "cenote"), "sim", "--scene", "cave", "--frames", str(args.frames),
                    "--width", str(args.width), "--height", str(args.height), "--quiet", "--out", dive],
                   check=True, stdout=subprocess.DEVNULL)
    frames = [(t, left, right, *pose) for t, left, right, pose in read_dive(dive)]
    positions = np.array([f[3] for f in frames])
    lo, hi = positions.min(axis=0) - 2.0, positions.max(axis=0) + 2.0

    port_file = os.path.join(work, "port")
    server = subprocess.Popen([os.path.join(args.build, "server", "cenote-server"), "--listen", "127.0.0.1:0",
                               "--port-file", port_file, "--snapshot-dir", os.path.join(work, "snapshots"),
                               "--calibration", dive], stdout=open(os.path.join(work, "server.log"), "w"),
                              stderr=subprocess.STDOUT)
    while not os.path.exists(port_file):
        if server.poll() is not None:
            sys.exit("cenote-server did not start: " + open(os.path.join(work, "server.log")).read())
        time.sleep(0.05)
    with open(port_file) as f:
        target = "127.0.0.1:" + f.read().strip()

    errors = Errors()
    soak = Soak(args, pb, target, errors)
    threads = [threading.Thread(target=soak.stream_frames, args=(frames,)),
               threading.Thread(target=soak.plan, args=(lo, hi)), threading.Thread(target=soak.churn_subscribers)]
    for t in threads:
        t.start()
    start = time.monotonic()
    end = start + 60.0 * args.minutes
    rss_after_first_lap, rss_max_after = None, 0
    log(f"{'t_s':>6} {'rss_MiB':>8} {'processed':>9} {'rejected':>8} {'occupied':>9} {'lap':>4} "
        f"{'q_p50_ms':>9} {'q_p99_ms':>9} {'subs':>5}")
    while time.monotonic() < end and server.poll() is None:
        time.sleep(max(0.0, min(args.report_s, end - time.monotonic())))
        rss = rss_bytes(server.pid)
        if soak.laps >= 1:
            if rss_after_first_lap is None:
                rss_after_first_lap = rss
            rss_max_after = max(rss_max_after, rss)
        lat = soak.interval_latencies()
        try:
            s = soak.stats()
            counts = (s.frames_processed, s.frames_rejected, s.occupied, s.subscribers)
        except grpc.RpcError as e:
            errors.add("GetStats", f"{e.code()} {e.details()}")
            counts = (-1, -1, -1, -1)
        log(f"{time.monotonic() - start:6.0f} {rss / 2**20:8.1f} {counts[0]:9d} {counts[1]:8d} {counts[2]:9d} "
            f"{soak.laps:4d} {percentile(lat, 50):9.2f} {percentile(lat, 99):9.2f} {counts[3]:5d}")
    soak.stop.set()
    for t in threads:
        t.join(timeout=60)
    crashed = server.poll() is not None
    if not crashed:
        server.send_signal(signal.SIGTERM)
        code = server.wait(timeout=60)
        if code != 0:
            errors.add("cenote-server", f"exit {code}")
    else:
        errors.add("cenote-server", f"died with {server.returncode} during the soak")

    lat = soak.all_latencies_ms
    log(f"done: {soak.laps} laps, {len(lat)} planner queries, {soak.subscriptions} subscriptions, "
        f"{soak.bad_rejected} of {soak.bad_sent} bad frames rejected")
    log(f"planner CheckSegments (64 segments): p50 {percentile(lat, 50):.2f} ms, p99 {percentile(lat, 99):.2f} ms")
    if rss_after_first_lap is not None:
        log(f"RSS after the first lap {rss_after_first_lap / 2**20:.1f} MiB, highest after it "
            f"{rss_max_after / 2**20:.1f} MiB")
    log(f"errors other than the bad frames': {len(errors.items)}")
    print(f"server log and dive: {work}")
    sys.exit(1 if errors.items else 0)


if __name__ == "__main__":
    main()
