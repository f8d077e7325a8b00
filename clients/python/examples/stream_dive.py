#!/usr/bin/python3
"""stream_dive.py: streams a recorded dive (EuRoC layout with camera poses, as `cenote sim` writes
it) into cenote-server at camera rate, as a vehicle does: each stereo frame with its left camera's
pose, through the server's whole pipeline (rectify, stereo, fusion, map). Prints what the server
answered (frames processed, skipped, rejected) and the map's voxel counts once the stream is done.
A viewer open on the server (--viewer-listen, docs/VIEWER.md) shows the map grow meanwhile.

    stream_dive.py --server 127.0.0.1:50051 --stubs <build>/clients/python/gen out/demo/cave
    stream_dive.py --server HOST:PORT --token-file token.txt --rate-hz 15 DIVE

Exits 1 when a frame is rejected.
"""

import argparse
import collections
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from cenote_client import MapClient, paced, read_dive, use_stubs  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dive", help="the dive's folder (mav0/cam0, mav0/cam1, groundtruth/cam0.tum)")
    parser.add_argument("--server", required=True, help="HOST:PORT of cenote-server")
    parser.add_argument("--stubs", help="the generated stubs (<build>/clients/python/gen)")
    parser.add_argument("--token-file", help="the bearer token, first line of the file")
    parser.add_argument("--rate-hz", type=float, default=15.0, help="frames a second (the camera's rate)")
    args = parser.parse_args()
    if args.stubs:
        use_stubs(args.stubs)
    token = None
    if args.token_file:
        with open(args.token_file) as f:
            token = f.readline().strip()

    frames = read_dive(args.dive)
    with MapClient(args.server, token=token, timeout_s=600) as client:
        acks = client.stream_frames(paced(frames, args.rate_hz))
        info = client.info()
    outcomes = collections.Counter(a.outcome for a in acks)
    print(f"{len(frames)} frames at {args.rate_hz:g} Hz: " +
          ", ".join(f"{n} {outcome.lower()}" for outcome, n in sorted(outcomes.items())) +
          f"; the map holds {info.occupied} occupied and {info.free} free voxels")
    for a in acks:
        if a.outcome == "REJECTED":
            print(f"frame at t = {a.timestamp_s:.3f} s rejected: {a.message}", file=sys.stderr)
    return 1 if outcomes.get("REJECTED") else 0


if __name__ == "__main__":
    sys.exit(main())
