#!/usr/bin/python3
"""explore.py: frontier-based exploration of a simulated underwater room through cenote-server.

A simulated vehicle with a depth camera (sim_scene.py: an analytic room with pillars, boulders and
crates) turns in place, sending each depth image's points with Ingest/IntegratePoints. Then the
planner repeatedly:
  1. asks the server for frontier clusters (Query/GetFrontiers, sorted by distance);
  2. for each, nearest first, proposes a goal stood off from the centroid back into known space and
     keeps the first goal that is known free (GetVoxels), clear of known obstacles by the vehicle's
     radius (GetDistances), and reachable along a straight capsule that hits nothing occupied
     (CheckSegments with a radius, stop_at_unknown off);
  3. "moves" the vehicle there in the simulator and scans again;
until no frontier is left (or none is reachable, or the step limit). After each step it prints the
coverage: the fraction of the scene's free space (voxel centres clear of every surface) that the map
knows. At the end it saves a plot of coverage over steps (matplotlib, Agg).

    explore.py --server-binary <build>/server/cenote-server          # starts its own server
    explore.py --server 127.0.0.1:50051 --token secret --plot cov.png

Units: metres; frame: the scene's world frame, z up.
"""

import argparse
import os
import sys
import time
from dataclasses import dataclass, field
from typing import List

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from sim_scene import DepthCamera, make_scene  # noqa: E402

from cenote_client import LocalServer, MapClient, VoxelState  # noqa: E402


@dataclass
class PlannerConfig:
    vehicle_radius_m: float = 0.25  # capsule radius of the path check and clearance of goals
    standoff_m: List[float] = field(default_factory=lambda: [0.6, 0.4, 0.2])  # goal: centroid - d * direction
    revisit_radius_m: float = 0.4   # a frontier within this of a visited goal's frontier counts as the same
    max_attempts: int = 2           # a frontier still there after this many visits is given up
    max_steps: int = 60
    coverage_stride: int = 2        # coverage samples every this many voxels


@dataclass
class ExploreResult:
    coverage: List[float]  # after the first scan, then after each step
    steps: int
    reason: str            # why it stopped
    path_length_m: float
    collisions: int        # moves whose straight path passed through the true scene's obstacles
    positions: List[np.ndarray]


class Explorer:
    def __init__(self, client, scene, camera, start, config=PlannerConfig(), log=print, seed=1):
        self.client = client
        self.scene = scene
        self.camera = camera
        self.position = np.asarray(start, dtype=np.float64)
        self.config = config
        self.log = log
        self.rng = np.random.default_rng(seed)
        self.region = (scene.room_min, scene.room_max)
        info = client.info()
        self.voxel_size_m = info.voxel_size_m
        self.samples = scene.free_samples(self.voxel_size_m, stride=config.coverage_stride)
        self.attempts = []  # (frontier centroid, visits)
        self.time_s = 0.0

    def sense(self):
        for points in self.camera.scan(self.scene, self.position, rng=self.rng):
            if len(points):
                self.time_s += 0.1
                self.client.integrate_points(self.position, points, timestamp_s=self.time_s)

    def coverage(self):
        states, _ = self.client.voxels(self.samples)
        return float(np.count_nonzero(states != VoxelState.UNKNOWN)) / len(self.samples)

    def _given_up(self, centroid):
        for c, visits in self.attempts:
            if np.linalg.norm(c - centroid) < self.config.revisit_radius_m and visits >= self.config.max_attempts:
                return True
        return False

    def _count_visit(self, centroid):
        for i, (c, visits) in enumerate(self.attempts):
            if np.linalg.norm(c - centroid) < self.config.revisit_radius_m:
                self.attempts[i] = (c, visits + 1)
                return
        self.attempts.append((centroid, 1))

    def choose(self, frontiers):
        """Nearest frontier with a reachable goal: (frontier, goal) or None. Every candidate of every
        frontier is checked in three batched queries."""
        cfg = self.config
        cands, owners = [], []
        for i, f in enumerate(frontiers):
            if self._given_up(f.centroid):
                continue
            for d in cfg.standoff_m:
                cands.append(f.centroid - d * f.direction)
                owners.append(i)
        if not cands:
            return None
        cands = np.array(cands)
        inside = np.all((cands > self.scene.room_min) & (cands < self.scene.room_max), axis=1)
        states, _ = self.client.voxels(cands)
        dist, _ = self.client.distances(cands)
        paths = self.client.capsules(np.repeat(self.position[None], len(cands), axis=0), cands,
                                     cfg.vehicle_radius_m, stop_at_unknown=False)
        ok = inside & (states == VoxelState.FREE) & (dist >= cfg.vehicle_radius_m) & ~paths.hit
        moved = np.linalg.norm(cands - self.position, axis=1) > 0.5 * self.voxel_size_m
        for k in np.flatnonzero(ok & moved):  # candidates are in frontier order: nearest first
            return frontiers[owners[k]], cands[k]
        return None

    def move(self, goal):
        """Moves the simulated vehicle; counts a collision when the straight path crosses an obstacle
        of the true scene (the map did not know it)."""
        t = np.linspace(0.0, 1.0, max(2, int(np.linalg.norm(goal - self.position) / 0.02)))
        path = self.position + t[:, None] * (goal - self.position)
        collided = bool(np.any(self.scene.clearance(path) < 0.0))
        length = float(np.linalg.norm(goal - self.position))
        self.position = goal
        return length, collided

    def run(self):
        cfg = self.config
        self.sense()
        coverage = [self.coverage()]
        positions = [self.position.copy()]
        self.log(f"step 0: position {np.round(self.position, 2)}, coverage {coverage[-1]:.3f}")
        path_m, collisions, reason, step = 0.0, 0, f"step limit ({cfg.max_steps})", 0
        for step in range(1, cfg.max_steps + 1):
            frontiers = self.client.frontiers(self.position, region=self.region)
            if not frontiers:
                reason, step = "no frontier left", step - 1
                break
            choice = self.choose(frontiers)
            if choice is None:
                reason, step = f"no reachable frontier ({len(frontiers)} left)", step - 1
                break
            frontier, goal = choice
            self._count_visit(frontier.centroid)
            length, collided = self.move(goal)
            path_m += length
            collisions += collided
            self.sense()
            coverage.append(self.coverage())
            positions.append(self.position.copy())
            self.log(f"step {step}: {len(frontiers)} frontiers, goal {np.round(goal, 2)} "
                     f"({length:.2f} m, frontier of {frontier.num_voxels} voxels), coverage {coverage[-1]:.3f}")
        return ExploreResult(coverage, step, reason, path_m, collisions, positions)


def save_plot(result, scene, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Rectangle

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
    ax0.plot(range(len(result.coverage)), result.coverage, marker="o")
    ax0.set_xlabel("step")
    ax0.set_ylabel("coverage (known fraction of free space)")
    ax0.set_ylim(0, 1.02)
    ax0.grid(True, alpha=0.3)
    ax0.set_title(f"coverage over steps: {result.coverage[-1]:.3f} ({result.reason})")
    lo, hi = scene.room_min, scene.room_max
    ax1.add_patch(Rectangle(lo[:2], *(hi - lo)[:2], fill=False, lw=2))
    for x, y, r in scene.pillars:
        ax1.add_patch(Circle((x, y), r, color="grey"))
    for x, y, z, r in scene.boulders:
        ax1.add_patch(Circle((x, y), r, color="tan"))
    for cmin, cmax in scene.crates:
        ax1.add_patch(Rectangle(cmin[:2], *(cmax - cmin)[:2], color="saddlebrown"))
    p = np.array(result.positions)
    ax1.plot(p[:, 0], p[:, 1], "-o", ms=3, color="tab:blue")
    ax1.plot(p[0, 0], p[0, 1], "g^", ms=9, label="start")
    ax1.set_aspect("equal")
    ax1.set_xlim(lo[0] - 0.3, hi[0] + 0.3)
    ax1.set_ylim(lo[1] - 0.3, hi[1] + 0.3)
    ax1.set_title(f"top view: path {result.path_length_m:.1f} m")
    ax1.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--server", help="address of a running cenote-server (host:port)")
    ap.add_argument("--token", help="bearer token of the server (given with --server-binary: the one it starts with)")
    ap.add_argument("--server-binary", help="start this cenote-server on a free loopback port instead")
    ap.add_argument("--server-config", help="--config for the started server")
    ap.add_argument("--scene", default="room", choices=["room", "small"])
    ap.add_argument("--start", default=None, help="start position x,y,z (default: near a corner, mid-height)")
    ap.add_argument("--max-steps", type=int, default=PlannerConfig.max_steps)
    ap.add_argument("--range", type=float, default=5.0, help="depth camera's maximum range, m")
    ap.add_argument("--noise", type=float, default=0.0, help="depth camera's range noise (sigma), m")
    ap.add_argument("--plot", default="explore_coverage.png", help="where to save the coverage plot ('' for none)")
    ap.add_argument("--keep-map", action="store_true", help="do not reset the server's map first")
    return ap.parse_args(argv)


def explore(args, log=print):
    """Runs the whole example with parsed arguments; returns the ExploreResult."""
    scene = make_scene(args.scene)
    start = (np.array([float(v) for v in args.start.split(",")]) if args.start
             else scene.room_min + np.array([1.0, 1.0, 0.5 * (scene.room_max[2] - scene.room_min[2])]))
    if scene.clearance(start)[0] <= 0:
        raise SystemExit(f"explore: start {start} is not in the scene's free space")
    camera = DepthCamera(max_range_m=args.range, noise_m=args.noise)
    config = PlannerConfig(max_steps=args.max_steps)
    server = None
    if args.server_binary:
        server = LocalServer(args.server_binary, token=args.token, config=args.server_config)
        target = server.target
    elif args.server:
        target = args.server
    else:
        raise SystemExit("explore: give --server HOST:PORT or --server-binary PATH")
    try:
        with MapClient(target, token=args.token, timeout_s=30.0) as client:
            if not args.keep_map:
                client.reset()
            t0 = time.monotonic()
            result = Explorer(client, scene, camera, start, config, log=log).run()
            log(f"explore: {result.steps} steps, stopped: {result.reason}; coverage {result.coverage[-1]:.3f}, "
                f"path {result.path_length_m:.1f} m, collisions {result.collisions}, "
                f"{time.monotonic() - t0:.1f} s")
    finally:
        if server is not None:
            server.close()
            server.remove()
    if args.plot:
        save_plot(result, scene, args.plot)
        log(f"explore: plot saved to {args.plot}")
    return result


if __name__ == "__main__":
    from cenote_client import CenoteError
    try:
        explore(parse_args(sys.argv[1:]))
    except CenoteError as e:
        sys.exit(f"explore: {e}")
