#!/usr/bin/python3
"""explore.py: frontier-based exploration of a simulated underwater room through cenote-server.

A simulated vehicle with a depth camera (sim_scene.py: an analytic room with pillars, boulders and
crates) turns in place, sending each depth image's points with Ingest/IntegratePoints. Then the
planner repeatedly:
  1. asks the server for frontier clusters (Query/GetFrontiers, sorted by distance);
  2. for each, nearest first, proposes goals stood off from the centroid back into known space (or
     towards the vehicle) and keeps the first goal that is known free (GetVoxels), clear of known
     obstacles by more than the vehicle's radius (GetDistances), and reachable along a straight
     capsule that hits nothing occupied (CheckSegments with a radius, stop_at_unknown off); a
     frontier still there after a visit is given up (it cannot be seen from where we can go);
     when no goal is straight ahead, straight legs through a small roadmap (the trail's viewpoints
     and random known-free points, joined by clear capsules) reach one;
  3. "moves" the vehicle there in the simulator and scans again;
until no frontier is left (or none is reachable, or the last scans made almost nothing new known,
or the step limit). After each step it prints the coverage: the fraction of the scene's free space
(voxel centres clear of every surface) that the map knows. At the end it saves a plot of coverage
over steps and the path seen from above (matplotlib, Agg).

    explore.py --server-binary <build>/server/cenote-server --stubs <build>/clients/python/gen
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

from cenote_client import LocalServer, MapClient, VoxelState, use_stubs  # noqa: E402


@dataclass
class PlannerConfig:
    vehicle_radius_m: float = 0.25  # capsule radius of the path check
    goal_margin_m: float = 0.1      # goals keep vehicle_radius_m + this from known obstacles, so that
                                    # the next path's capsule does not touch them at its start
    standoff_m: List[float] = field(default_factory=lambda: [0.6, 0.4, 0.2])  # goal: centroid - d * direction
    approach_m: List[float] = field(default_factory=lambda: [0.3, 0.6, 1.0])  # or: centroid + d towards us
    region_margin_m: float = 0.15   # frontiers only inside the room shrunk by this: a floor or wall seen
                                    # at a grazing angle leaves free voxels next to the unknown behind it
    revisit_radius_m: float = 0.4   # a frontier within this of a visited goal's frontier counts as the same
    min_move_m: float = 0.3         # a goal nearer than this sees nothing the last scan did not
    max_attempts: int = 1           # a frontier still there after this many visits is given up
    # Converged: the last stall_steps scans together made fewer than stall_fraction of the known
    # voxels known. Free voxels carved by grazing rays on curved surfaces (pillars, boulders) lie next
    # to the never-seen inside of the obstacle: frontiers that no viewpoint resolves.
    stall_steps: int = 6
    stall_fraction: float = 0.002
    max_steps: int = 60
    # when no goal is straight ahead: a roadmap of the trail's last viewpoints and random points
    max_backtrack: int = 30
    roadmap_samples: int = 150
    max_roadmap_goals: int = 40     # goals (nearest frontiers first) joined to the roadmap
    coverage_stride: int = 2        # coverage samples every this many voxels


@dataclass
class ExploreResult:
    coverage: List[float]  # after the first scan, then after each step
    steps: int
    reason: str            # why it stopped
    path_length_m: float
    collisions: int        # moves whose straight path passed through the true scene's obstacles
    positions: List[np.ndarray]  # every point the vehicle flew through, in order


class Explorer:
    def __init__(self, client, scene, camera, start, config=PlannerConfig(), log=print, seed=1):
        self.client = client
        self.scene = scene
        self.camera = camera
        self.position = np.asarray(start, dtype=np.float64)
        self.config = config
        self.log = log
        self.rng = np.random.default_rng(seed)
        self.region = (scene.room_min + config.region_margin_m, scene.room_max - config.region_margin_m)
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

    def known_voxels(self):
        info = self.client.info()
        return info.free + info.occupied

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
        """Nearest frontier with a reachable goal: (frontier, route) or None; the route is the list of
        straight legs' end points, its last the goal. Goals straight from here come first; failing
        those, a route of straight legs through the trail's viewpoints and random known-free points. All candidates go in batched queries."""
        cfg = self.config
        cands, owners = [], []
        for i, f in enumerate(frontiers):
            if self._given_up(f.centroid):
                continue
            # back from the frontier into known space, looking into the unknown; when the cluster's
            # direction is undefined (unknown on both sides) or that point is not free, towards us
            towards_us = self.position - f.centroid
            towards_us /= max(np.linalg.norm(towards_us), 1e-9)
            for goal in ([f.centroid - d * f.direction for d in cfg.standoff_m]
                         + [f.centroid + d * towards_us for d in cfg.approach_m]):
                cands.append(goal)
                owners.append(i)
        if not cands:
            return None
        cands = np.array(cands)
        inside = np.all((cands > self.scene.room_min) & (cands < self.scene.room_max), axis=1)
        states, _ = self.client.voxels(cands)
        dist, _ = self.client.distances(cands)
        moved = np.linalg.norm(cands - self.position, axis=1) >= cfg.min_move_m
        usable = np.flatnonzero(inside & moved & (states == VoxelState.FREE)
                                & (dist >= cfg.vehicle_radius_m + cfg.goal_margin_m))
        if len(usable) == 0:
            return None
        goals = cands[usable]  # in frontier order: nearest first
        direct = self.client.capsules(np.repeat(self.position[None], len(goals), axis=0), goals,
                                      cfg.vehicle_radius_m, stop_at_unknown=False)
        if not np.all(direct.hit):
            k = int(np.argmin(direct.hit))
            return frontiers[owners[usable[k]]], [goals[k]]
        return self._roadmap_route(frontiers, owners, usable, goals)

    def _roadmap_route(self, frontiers, owners, usable, goals):
        """No goal straight from here: a small roadmap (the trail's viewpoints and random known-free
        points, joined where a capsule is clear), searched with Dijkstra from here to the goals."""
        cfg = self.config
        lo, hi = self.region
        samples = lo + self.rng.random((cfg.roadmap_samples, 3)) * (hi - lo)
        states, _ = self.client.voxels(samples)
        dist, _ = self.client.distances(samples)
        samples = samples[(states == VoxelState.FREE) & (dist >= cfg.vehicle_radius_m + cfg.goal_margin_m)]
        goals = goals[:cfg.max_roadmap_goals]
        ways = np.concatenate([self.position[None], np.array(self.trail[-2::-1][:cfg.max_backtrack]).reshape(-1, 3),
                               samples])
        nodes = np.concatenate([ways, goals])
        n, w = len(nodes), len(ways)
        i, j = np.triu_indices(n, 1)
        keep = i < w  # no edges between two goals
        i, j = i[keep], j[keep]
        clear = ~self.client.capsules(nodes[i], nodes[j], cfg.vehicle_radius_m, stop_at_unknown=False).hit
        cost = np.full((n, n), np.inf)
        lengths = np.linalg.norm(nodes[i] - nodes[j], axis=1)
        cost[i[clear], j[clear]] = lengths[clear]
        cost[j[clear], i[clear]] = lengths[clear]
        best, previous, done = np.full(n, np.inf), np.full(n, -1), np.zeros(n, bool)
        best[0] = 0.0
        for _ in range(n):  # Dijkstra on a dense graph of a few hundred nodes
            u = int(np.argmin(np.where(done, np.inf, best)))
            if not np.isfinite(best[u]):
                break
            done[u] = True
            if u >= w:
                continue  # goals end routes
            via = best[u] + cost[u]
            better = via < best
            best[better], previous[better] = via[better], u
        for g in range(len(goals)):  # nearest frontier first
            if np.isfinite(best[w + g]):
                route, u = [], w + g
                while u > 0:
                    route.append(nodes[u])
                    u = previous[u]
                return frontiers[owners[usable[g]]], route[::-1]
        return None

    def move(self, route):
        """Flies the simulated vehicle along the route's straight legs; counts the legs that cross
        an obstacle of the true scene (the map did not know it). Returns (length, collisions)."""
        length, collisions = 0.0, 0
        for goal in route:
            t = np.linspace(0.0, 1.0, max(2, int(np.linalg.norm(goal - self.position) / 0.02)))
            path = self.position + t[:, None] * (goal - self.position)
            collisions += bool(np.any(self.scene.clearance(path) < 0.0))
            length += float(np.linalg.norm(goal - self.position))
            self.position = np.asarray(goal, dtype=np.float64)
            self.path.append(self.position.copy())
        return length, collisions

    def run(self):
        cfg = self.config
        self.sense()
        coverage = [self.coverage()]
        self.path = [self.position.copy()]
        self.trail = [self.position.copy()]
        known = [self.known_voxels()]
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
            frontier, route = choice
            self._count_visit(frontier.centroid)
            length, collided = self.move(route)
            self.trail.append(self.position.copy())
            path_m += length
            collisions += collided
            self.sense()
            coverage.append(self.coverage())
            known.append(self.known_voxels())
            via = f", back {len(route) - 1} viewpoints" if len(route) > 1 else ""
            self.log(f"step {step}: {len(frontiers)} frontiers, goal {np.round(route[-1], 2)} "
                     f"({length:.2f} m{via}, frontier of {frontier.num_voxels} voxels), coverage {coverage[-1]:.3f}")
            if len(known) > cfg.stall_steps:
                gained = known[-1] - known[-1 - cfg.stall_steps]
                if gained < cfg.stall_fraction * known[-1]:
                    reason = (f"converged (the last {cfg.stall_steps} scans made {gained} voxels known, "
                              f"{len(frontiers)} frontiers left)")
                    break
        return ExploreResult(coverage, step, reason, path_m, collisions, self.path)


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
    ax0.set_title(f"coverage {result.coverage[-1]:.3f} after {result.steps} steps")
    fig.text(0.01, 0.01, f"stopped: {result.reason}", fontsize=8)
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
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--server", help="address of a running cenote-server (host:port)")
    ap.add_argument("--token", help="bearer token of the server (given with --server-binary: the one it starts with)")
    ap.add_argument("--server-binary", help="start this cenote-server on a free loopback port instead")
    ap.add_argument("--server-config", help="--config for the started server")
    ap.add_argument("--stubs", help="generated stubs folder, <build>/clients/python/gen (else CENOTE_PYTHON_STUBS)")
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
    if args.stubs:
        use_stubs(args.stubs)
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
