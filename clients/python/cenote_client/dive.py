"""dive.py: the frames of a recorded dive in the EuRoC layout, with their camera poses, ready for
MapClient.stream_frames: what `cenote sim` writes (mav0/cam0, mav0/cam1, groundtruth/cam0.tum).

    frames = read_dive("out/demo/cave")   # [(t_s, left PNG bytes, right PNG bytes, (position, quaternion_xyzw))]
    client.stream_frames(paced(frames, rate_hz=15.0))

Units: seconds, metres; poses are the left camera's in the world (TUM order x y z, qx qy qz qw).
"""

import os
import time


def read_tum(path):
    """{t_s rounded to the microsecond: (position [3], quaternion xyzw [4])} of a TUM trajectory."""
    poses = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            poses[round(v[0], 6)] = (v[1:4], v[4:8])
    return poses


def read_dive(dive, poses_file=os.path.join("groundtruth", "cam0.tum")):
    """Every frame of the dive in time order: (t_s, left bytes, right bytes, pose); the pose from
    poses_file (relative to the dive) at the frame's time, None where it has none."""
    poses = read_tum(os.path.join(dive, poses_file))
    frames = []
    with open(os.path.join(dive, "mav0", "cam0", "data.csv")) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            stamp, name = line.strip().split(",")
            t_s = int(stamp) * 1e-9
            with open(os.path.join(dive, "mav0", "cam0", "data", name), "rb") as left, \
                    open(os.path.join(dive, "mav0", "cam1", "data", name), "rb") as right:
                frames.append((t_s, left.read(), right.read(), poses.get(round(t_s, 6))))
    return frames


def paced(frames, rate_hz):
    """Yields the frames no faster than rate_hz, as a camera delivers them."""
    next_at = time.monotonic()
    for frame in frames:
        time.sleep(max(0.0, next_at - time.monotonic()))
        next_at += 1.0 / rate_hz
        yield frame
