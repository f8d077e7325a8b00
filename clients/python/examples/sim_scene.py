"""sim_scene.py: an analytic underwater scene and a simulated depth camera for the exploration example.

Scene: a box-shaped room (a flooded chamber) holding vertical pillars (cylinders from floor to
ceiling), boulders (spheres) and crates (axis-aligned boxes), all defined by numbers, so that ray
hits and the true free space are exact. DepthCamera: a pinhole depth camera with a frustum and a
maximum range, ray-cast against the scene in numpy; a scan turns it in place through several yaw
and pitch angles, as a vehicle hovering and turning would.
Units: metres, radians; frame: world, z up. Threads: plain values, no shared state.
"""

from dataclasses import dataclass, field
from typing import List, Tuple

import numpy as np


@dataclass
class Scene:
    room_min: np.ndarray
    room_max: np.ndarray
    pillars: List[Tuple[float, float, float]] = field(default_factory=list)      # (x, y, radius)
    boulders: List[Tuple[float, float, float, float]] = field(default_factory=list)  # (x, y, z, radius)
    crates: List[Tuple[np.ndarray, np.ndarray]] = field(default_factory=list)   # (min, max)

    # -- ray casting -------------------------------------------------------------------------------
    def raycast(self, origin, directions, max_range_m):
        """Distance along each unit direction from origin (inside the room) to the first surface;
        inf where nothing is within max_range_m."""
        o = np.asarray(origin, dtype=np.float64)
        d = np.asarray(directions, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            # room walls seen from inside: the nearest exit plane along each axis
            t_exit = np.where(d > 0, (self.room_max - o) / d, np.where(d < 0, (self.room_min - o) / d, np.inf))
            t = t_exit.min(axis=1)
            for x, y, r in self.pillars:
                t = np.minimum(t, _ray_circle(o[:2] - (x, y), d[:, :2], r))
            for x, y, z, r in self.boulders:
                t = np.minimum(t, _ray_sphere(o - (x, y, z), d, r))
            for lo, hi in self.crates:
                t = np.minimum(t, _ray_box(o, d, lo, hi))
        return np.where(t <= max_range_m, t, np.inf)

    # -- free space --------------------------------------------------------------------------------
    def clearance(self, points):
        """Distance from each point to the nearest surface; negative inside an obstacle or outside
        the room (exact for walls, pillars and boulders; a lower bound near crate edges)."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64))
        c = np.minimum(p - self.room_min, self.room_max - p).min(axis=1)
        for x, y, r in self.pillars:
            c = np.minimum(c, np.hypot(p[:, 0] - x, p[:, 1] - y) - r)
        for x, y, z, r in self.boulders:
            c = np.minimum(c, np.linalg.norm(p - (x, y, z), axis=1) - r)
        for lo, hi in self.crates:
            outside = np.maximum(np.maximum(lo - p, p - hi), 0.0)
            inside = np.minimum(p - lo, hi - p).min(axis=1)
            c = np.minimum(c, np.where(inside > 0, -inside, np.linalg.norm(outside, axis=1)))
        return c

    def free_samples(self, voxel_size_m, stride=2, margin_m=None):
        """Voxel centres, every `stride` voxels, whose voxel lies wholly in free space (clearance
        above the voxel's half diagonal, or margin_m): the free space that coverage counts."""
        margin = margin_m if margin_m is not None else 0.87 * voxel_size_m
        axes = []
        for lo, hi in zip(self.room_min, self.room_max):
            first, last = int(np.floor(lo / voxel_size_m)), int(np.ceil(hi / voxel_size_m))
            axes.append((np.arange(first, last, stride) + 0.5) * voxel_size_m)
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        return grid[self.clearance(grid) > margin]


def _ray_circle(o2, d2, r):
    """Nearest positive t where o2 + t d2 meets the circle of radius r about 0 (2D rays)."""
    a = (d2 * d2).sum(axis=1)
    b = 2.0 * (d2 @ o2)
    c = o2 @ o2 - r * r
    disc = b * b - 4 * a * c
    sq = np.sqrt(np.maximum(disc, 0.0))
    t0 = (-b - sq) / (2 * a)
    t1 = (-b + sq) / (2 * a)
    t = np.where(t0 > 1e-9, t0, np.where(t1 > 1e-9, t1, np.inf))
    return np.where((disc >= 0) & (a > 1e-12), t, np.inf)


def _ray_sphere(oc, d, r):
    b = d @ oc
    c = oc @ oc - r * r
    disc = b * b - c
    sq = np.sqrt(np.maximum(disc, 0.0))
    t0, t1 = -b - sq, -b + sq
    t = np.where(t0 > 1e-9, t0, np.where(t1 > 1e-9, t1, np.inf))
    return np.where(disc >= 0, t, np.inf)


def _ray_box(o, d, lo, hi):
    t1 = (lo - o) / d
    t2 = (hi - o) / d
    t_near = np.nan_to_num(np.minimum(t1, t2), nan=-np.inf).max(axis=1)
    t_far = np.nan_to_num(np.maximum(t1, t2), nan=np.inf).min(axis=1)
    return np.where((t_far >= t_near) & (t_near > 1e-9), t_near, np.inf)


@dataclass
class DepthCamera:
    width_px: int = 120
    height_px: int = 90
    hfov_rad: float = np.radians(90.0)
    max_range_m: float = 5.0
    noise_m: float = 0.0  # Gaussian range noise

    def directions(self, yaw_rad, pitch_rad):
        """(width * height, 3) unit ray directions of the camera looking along (yaw, pitch)."""
        f = 0.5 * self.width_px / np.tan(0.5 * self.hfov_rad)
        u = (np.arange(self.width_px) + 0.5 - 0.5 * self.width_px) / f
        v = (np.arange(self.height_px) + 0.5 - 0.5 * self.height_px) / f
        uu, vv = np.meshgrid(u, v)
        cy, sy, cp, sp = np.cos(yaw_rad), np.sin(yaw_rad), np.cos(pitch_rad), np.sin(pitch_rad)
        forward = np.array([cp * cy, cp * sy, sp])
        right = np.array([sy, -cy, 0.0])
        up = np.cross(right, forward)
        d = forward + uu.reshape(-1, 1) * right - vv.reshape(-1, 1) * up
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def capture(self, scene, position, yaw_rad, pitch_rad, rng=None):
        """World-frame points of the pixels that see a surface within range."""
        d = self.directions(yaw_rad, pitch_rad)
        t = scene.raycast(position, d, self.max_range_m)
        seen = np.isfinite(t)
        t = t[seen]
        if self.noise_m > 0 and rng is not None:
            t = t + rng.normal(0.0, self.noise_m, size=t.shape)
        return np.asarray(position) + d[seen] * t[:, None]

    def scan(self, scene, position, yaws=6, pitches_deg=(-60.0, 0.0, 60.0), rng=None):
        """The images of one turn in place: a list of (N, 3) point arrays, one per view."""
        views = []
        for pitch in np.radians(pitches_deg):
            for yaw in np.arange(yaws) * 2 * np.pi / yaws:
                views.append(self.capture(scene, position, yaw, pitch, rng))
        return views


def make_scene(name):
    """'room': a 10 x 8 x 3 m chamber with pillars, boulders and crates; 'small': 5 x 4 x 2 m with
    one pillar and one crate (the test's scene)."""
    if name == "room":
        return Scene(room_min=np.array([0.0, 0.0, 0.0]), room_max=np.array([10.0, 8.0, 3.0]),
                     pillars=[(3.0, 2.5, 0.4), (6.5, 5.5, 0.5), (7.5, 2.0, 0.3)],
                     boulders=[(2.0, 6.0, 0.6, 0.8), (8.5, 6.8, 0.4, 0.6)],
                     crates=[(np.array([4.5, 0.3, 0.0]), np.array([5.5, 1.5, 1.0])),
                             (np.array([4.0, 3.5, 0.0]), np.array([5.0, 4.5, 1.8]))])
    if name == "small":
        return Scene(room_min=np.array([0.0, 0.0, 0.0]), room_max=np.array([5.0, 4.0, 2.0]),
                     pillars=[(2.5, 2.0, 0.3)],
                     crates=[(np.array([3.8, 0.4, 0.0]), np.array([4.5, 1.2, 0.8]))])
    raise ValueError(f"scene: {name!r} is not one of room, small")
