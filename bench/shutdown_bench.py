#!/usr/bin/python3
"""How long cenote-server takes from SIGTERM to exit (snapshot written), with an update subscriber,
a pose stream and a point stream open, beside the same server with no client at all (the floor:
the snapshot and gRPC's own shutdown), in the same run. Median and max of --runs starts each.

Usage: bench/shutdown_bench.py build/server/cenote-server [--runs 5]
"""
import argparse
import os
import queue
import signal
import statistics
import subprocess
import tempfile
import time

import grpc


def identity(x):
    return x


def start(binary, workdir):
    port_file = os.path.join(workdir, "port")
    process = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--port-file", port_file,
                                "--snapshot-dir", os.path.join(workdir, "snapshots")],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not os.path.exists(port_file):
        if process.poll() is not None:
            raise RuntimeError("cenote-server exited at start")
        time.sleep(0.02)
    with open(port_file) as f:
        return process, "127.0.0.1:" + f.read().strip()


def open_streams(channel):
    """A subscriber with its snapshot, and pose and point streams that send nothing."""
    subscription = channel.unary_stream("/cenote.v1.Updates/Subscribe", request_serializer=identity,
                                        response_deserializer=identity)(b"", timeout=120)
    next(subscription)
    idle = queue.Queue()

    def nothing():
        while idle.get() is not None:
            pass
        return
        yield

    streams = [channel.stream_stream(m, request_serializer=identity, response_deserializer=identity)(nothing(),
                                                                                                     timeout=120)
               for m in ("/cenote.v1.Ingest/StreamPoses", "/cenote.v1.Ingest/StreamPoints")]
    time.sleep(0.3)  # the server has taken both calls
    return [subscription, *streams], idle


def sigterm_to_exit(binary, with_streams):
    with tempfile.TemporaryDirectory(prefix="cenote-shutdown-") as workdir:
        process, target = start(binary, workdir)
        channel = grpc.insecure_channel(target)
        calls, idle = open_streams(channel) if with_streams else ([], None)
        t0 = time.monotonic()
        process.send_signal(signal.SIGTERM)
        code = process.wait(timeout=60)
        elapsed = time.monotonic() - t0
        if code != 0:
            raise RuntimeError(f"cenote-server exited {code}")
        if idle:
            idle.put(None)
        for call in calls:
            call.cancel()
        channel.close()
        return elapsed


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("binary")
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    print(f"{'SIGTERM to exit':<44} {'median ms':>10} {'max ms':>8}")
    for label, with_streams in (("no client (floor)", False), ("subscriber + pose + point streams open", True)):
        times = [1000 * sigterm_to_exit(args.binary, with_streams) for _ in range(args.runs)]
        print(f"{label:<44} {statistics.median(times):>10.1f} {max(times):>8.1f}")


if __name__ == "__main__":
    main()
