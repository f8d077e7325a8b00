#!/usr/bin/python3
"""viewer_bench.py CENOTE CENOTE_SERVER SOURCE_DIR [FRAMES]: what the live viewer costs and sends.

A simulated 800x600 cave dive (cenote sim, FRAMES frames, default 60 as in `make demo`) is streamed
into cenote-server at 15 Hz (poses first, then stereo frames, over gRPC), three times: without the
viewer, with the viewer and no client, with the viewer and one client (web/test/protocol_client.mjs,
@foxglove/ws-protocol on Node, subscribed to every channel, run until it holds the whole map at full
detail). For each: the server's CPU time (user + system, all threads, from /proc) per frame; beside
it, `cenote run`'s CPU time per frame on the same dive, and the viewer's extra CPU per frame as a
share of it: once as the difference of whole-server CPU between runs (noisy on a shared machine:
the runs are separate processes), once as the CPU of the viewer's own threads (viewer-feed,
viewer-net, from /proc/PID/task; what ingest does for the viewer, the cloud's thinning and the
camera images' encoding, runs on ingest threads and is not in it: a profile puts it under 0.2 %
of the server's samples). The client's bytes are what it received (WebSocket payloads) during the dive and until
it held the whole map; the byte budget is server.viewer.budget_bytes_per_s (1 MB/s by default).
"""

import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

CENOTE, SERVER, SOURCE = (os.path.abspath(a) for a in sys.argv[1:4])
FRAMES = int(sys.argv[4]) if len(sys.argv) > 4 else 60
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
from cenote_client import LocalServer, MapClient, paced, read_dive  # noqa: E402

WEB = os.path.join(SOURCE, "web")
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def cpu_s(pid, task=None):
    """CPU seconds (user + system) of a process, all its threads, or of one of its threads."""
    with open(f"/proc/{pid}/stat" if task is None else f"/proc/{pid}/task/{task}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS  # utime, stime


def viewer_threads_cpu_s(pid):
    """CPU seconds of the viewer's own threads (named viewer-feed and viewer-net by the server)."""
    total = 0.0
    for task in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{task}/comm") as f:
            if f.read().strip() in ("viewer-feed", "viewer-net"):
                total += cpu_s(pid, task)
    return total


def stream(server, dive):
    """Poses first, then the stereo frames at 15 Hz, as the camera records; (processed, occupied)."""
    client = MapClient(server.target, timeout_s=600)
    frames = read_dive(dive)
    client.stream_poses([f[0] for f in frames], [f[3][0] for f in frames], [f[3][1] for f in frames])
    acks = client.stream_frames(paced([f[:3] for f in frames], 15.0))
    occupied = client.info().occupied
    client.close()
    return sum(a.outcome == "PROCESSED" for a in acks), occupied


def run(dive, tmp, viewer, watch):
    args = ["--calibration", dive] + (["--viewer-listen", "127.0.0.1:0"] if viewer else [])
    server = LocalServer(SERVER, extra_args=args)
    try:
        watcher = None
        if watch:
            port = None
            while port is None:
                m = re.search(r"viewer on http://127\.0\.0\.1:(\d+)/", server.log())
                port = int(m.group(1)) if m else time.sleep(0.1)
            watcher = subprocess.Popen(["node", os.path.join(WEB, "test", "protocol_client.mjs"),
                                        f"ws://127.0.0.1:{port}/"], cwd=WEB, stdin=subprocess.PIPE,
                                       stdout=subprocess.PIPE, text=True, env=dict(os.environ, TIMEOUT_S="600"))
            time.sleep(1.0)
        before = cpu_s(server.process.pid)
        start = time.monotonic()
        processed, occupied = stream(server, dive)
        report = None
        if watcher:
            out, _ = watcher.communicate(f"occupied {occupied}\n", timeout=900)
            report = json.loads(out.strip().splitlines()[-1])
        elapsed = time.monotonic() - start
        used = cpu_s(server.process.pid) - before
        viewer_ms = 1000.0 * viewer_threads_cpu_s(server.process.pid) / max(processed, 1)
        return {"cpu_ms_per_frame": 1000.0 * used / max(processed, 1), "processed": processed, "occupied": occupied,
                "viewer_ms_per_frame": viewer_ms, "report": report, "elapsed_s": elapsed}
    finally:
        server.close()
        server.remove()


def main():
    with tempfile.TemporaryDirectory(prefix="cenote-viewer-bench-") as tmp:
        dive = os.path.join(tmp, "cave")
        subprocess.run([CENOTE, "sim", "--scene", "cave", "--frames", str(FRAMES), "--quiet", "--out", dive],
                       check=True, stdout=subprocess.DEVNULL)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([CENOTE, "run", "--dataset", dive, "--config", os.path.join(SOURCE, "config", "default.yaml"),
                        "--out", os.path.join(tmp, "run"), "--map", os.path.join(tmp, "run", "map.vdb")],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        run_ms = 1000.0 * ((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)) / FRAMES
        rows = [("no viewer", run(dive, tmp, False, False)), ("viewer, no client", run(dive, tmp, True, False)),
                ("viewer, one client", run(dive, tmp, True, True))]
        base = rows[0][1]["cpu_ms_per_frame"]
        print(f"cave dive, {FRAMES} frames 800x600 at 15 Hz; cenote run: {run_ms:.1f} CPU ms/frame")
        print("| server | CPU ms/frame | extra vs no viewer | extra / cenote run | viewer threads ms/frame "
              "| viewer threads / cenote run | client bytes | bytes/frame | client MB/s |")
        print("|---|---|---|---|---|---|---|---|---|")
        for name, r in rows:
            extra = r["cpu_ms_per_frame"] - base
            rep = r["report"]
            bytes_text = f"{rep['bytes']:,}" if rep else "-"
            per_frame = f"{rep['bytes'] / FRAMES:,.0f}" if rep else "-"
            rate = f"{rep['bytes'] / r['elapsed_s'] / 1e6:.2f}" if rep else "-"
            viewer = r["viewer_ms_per_frame"]
            print(f"| {name} | {r['cpu_ms_per_frame']:.1f} | {extra:+.1f} ms | {100.0 * extra / run_ms:+.1f} % | "
                  f"{viewer:.2f} | {100.0 * viewer / run_ms:.1f} % | {bytes_text} | {per_frame} | {rate} |")
        rep = rows[2][1]["report"]
        print(f"client: {rep['fullVoxels']:,} voxels at full detail (server: {rows[2][1]['occupied']:,}), "
              f"{rep['blocks']} blocks, coarse seen: {rep['sawCoarse']}, messages {rep['messages']}")


if __name__ == "__main__":
    main()
