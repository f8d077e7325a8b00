"""types.py: the values MapClient returns: numpy arrays in dataclasses.

Units: metres, seconds; frame: the map's world frame. Point arrays are (N, 3) float64, voxel
indices (N, 3) int32 (voxel i covers [i * s, (i + 1) * s) for voxel size s), states uint8 with the
values of VoxelState below. Plain values: share them freely between threads.
"""

from dataclasses import dataclass, field
from typing import List, Optional

import numpy as np


class VoxelState:
    UNKNOWN = 0  # never observed (or cleared): never free
    FREE = 1
    OCCUPIED = 2
    NAMES = ("unknown", "free", "occupied")


@dataclass
class BoxCounts:
    """Voxel counts of N boxes (a voxel belongs to a box when its centre does)."""
    unknown: np.ndarray       # (N,) uint64
    free: np.ndarray
    occupied: np.ndarray
    any_occupied: np.ndarray  # (N,) bool
    map_version: int = 0


@dataclass
class Collisions:
    """First occupied voxel along N segments, capsules or rays (mapping/query/map_query.h)."""
    hit: np.ndarray                 # (N,) bool
    hit_distance_m: np.ndarray      # (N,) along the segment, to the hit voxel's centre projection
    hit_voxel: np.ndarray           # (N, 3) int32
    hit_point: np.ndarray           # (N, 3) centre of the hit voxel
    crossed_unknown: np.ndarray     # (N,) bool
    unknown_distance_m: np.ndarray  # (N,)
    stopped_at_unknown: np.ndarray  # (N,) bool
    clear: np.ndarray               # (N,) bool: safe to travel
    map_version: int = 0


@dataclass
class Frontier:
    """One cluster of frontier voxels (free voxels with an unknown 6-neighbour)."""
    id: int
    num_voxels: int
    centroid: np.ndarray    # (3,)
    bounds_min: np.ndarray  # (3,)
    bounds_max: np.ndarray  # (3,)
    direction: np.ndarray   # (3,) mean unit direction into the unknown
    distance_m: float       # of the centroid from the position asked about


@dataclass
class Extract:
    """Voxels whose centre lies in a box."""
    voxel_size_m: float
    ijk: np.ndarray            # (N, 3) int32
    states: np.ndarray         # (N,) uint8
    probabilities: np.ndarray  # (N,) float32
    rgb: np.ndarray            # (N, 3) uint8, black where a voxel has no colour
    map_version: int = 0

    @property
    def centres(self):
        """(N, 3) voxel centres in metres."""
        return (self.ijk.astype(np.float64) + 0.5) * self.voxel_size_m


@dataclass
class MapInfo:
    voxel_size_m: float
    frame_id: str
    bounds_min: np.ndarray  # of the known voxels; empty map: min > max
    bounds_max: np.ndarray
    occupied: int
    free: int
    prob_hit: float
    prob_miss: float
    clamp_min: float
    clamp_max: float
    occupied_threshold: float
    max_range_m: float
    max_distance_m: float
    map_version: int


@dataclass
class StageTiming:
    name: str
    median_ms: float
    p95_ms: float
    count: int


@dataclass
class MethodStats:
    method: str  # e.g. "Query/GetVoxels"
    calls: int
    errors: int
    p50_ms: float
    p99_ms: float


@dataclass
class Stats:
    uptime_s: float
    frames_received: int
    frames_processed: int
    frames_skipped: int
    frames_rejected: int
    batches_integrated: int
    poses_received: int
    occupied: int
    free: int
    map_memory_bytes: int
    process_memory_bytes: int
    map_version: int
    subscribers: int
    last_snapshot_age_s: float  # -1: none yet
    stages: List[StageTiming] = field(default_factory=list)
    methods: List[MethodStats] = field(default_factory=list)

    def method(self, name):
        """The MethodStats of one method ("Query/GetVoxels"), or None."""
        return next((m for m in self.methods if m.method == name), None)


@dataclass
class IntegrateResult:
    voxels_updated: int
    changed_blocks: int
    map_version: int


@dataclass
class Ack:
    """The acknowledgement of one streamed frame or pose, in stream order."""
    sequence: int
    timestamp_s: float
    outcome: str       # frames: PROCESSED, SKIPPED_NO_POSE, SKIPPED_NOT_KEYFRAME, REJECTED; poses: STORED, REJECTED
    status: str        # gRPC status name: OK unless rejected
    message: str


@dataclass
class Change:
    """What a clear, crop or reset changed."""
    changed_blocks: int
    bounds_min: np.ndarray
    bounds_max: np.ndarray
    map_version: int


@dataclass
class SnapshotResult:
    path: str  # absolute path written on the server
    bytes: int
    map_version: int


@dataclass
class Block:
    """One 8 x 8 x 8 block of an update: states[i, j, k] is voxel (8 x + i, 8 y + j, 8 z + k)."""
    index: np.ndarray                    # (3,) int32 block index
    states: np.ndarray                   # (8, 8, 8) uint8; all unknown: the block was cleared
    probabilities: Optional[np.ndarray]  # (8, 8, 8) float32 when asked for, else None

    def voxel_indices(self):
        """(512, 3) int32 voxel indices in the order of states.ravel()."""
        i, j, k = np.meshgrid(np.arange(8), np.arange(8), np.arange(8), indexing="ij")
        local = np.stack([i.ravel(), j.ravel(), k.ravel()], axis=1).astype(np.int32)
        return local + 8 * self.index.astype(np.int32)


@dataclass
class MapUpdate:
    sequence: int  # the map's version after this change
    snapshot: bool
    snapshot_complete: bool
    resync: bool
    bounds_min: np.ndarray
    bounds_max: np.ndarray
    voxel_size_m: float
    blocks: List[Block]
