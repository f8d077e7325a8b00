"""client_env.py: what the Python client tests share: where the server binary, the generated stubs
and the package are (from the environment tests/CMakeLists.txt sets), and the analytic wall scene.

Environment: CENOTE_SERVER_BINARY (required), CENOTE_PYTHON_STUBS (the generated stubs folder),
CENOTE_CLIENT_DIR (clients/python; default: found from this file's place in the tree).

The wall scene: a sensor at the centre of voxel (0, 0, 0) sees a square wall patch whose points are
the centres of voxels (40, j, k), j, k in [-20, 20]: with 5 cm voxels the wall's face is 2.0 m
ahead along +x. Every wall voxel is hit once (occupied, probability prob_hit), the voxels between
origin and wall are crossed (free, probability prob_miss), everything behind the wall is unknown.
"""

import os
import sys
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CLIENT_DIR = os.environ.get("CENOTE_CLIENT_DIR") or os.path.join(HERE, "..", "..", "..", "clients", "python")
sys.path.insert(0, os.path.abspath(CLIENT_DIR))

import cenote_client  # noqa: E402

SERVER_BINARY = os.environ.get("CENOTE_SERVER_BINARY", "")
TOKEN = "python-client-test-token"
WALL_I = 40        # voxel index of the wall along x
WALL_HALF = 20     # wall voxels j, k in [-WALL_HALF, WALL_HALF]
WALL_RGB = (200, 100, 50)


def require_server(test_case):
    if not SERVER_BINARY or not os.access(SERVER_BINARY, os.X_OK):
        raise unittest.SkipTest("CENOTE_SERVER_BINARY is not an executable cenote-server")


def centre(s, i, j, k):
    """Centre of voxel (i, j, k) for voxel size s."""
    return (np.array([i, j, k], dtype=np.float64) + 0.5) * s


def wall_points(s):
    jj, kk = np.meshgrid(np.arange(-WALL_HALF, WALL_HALF + 1), np.arange(-WALL_HALF, WALL_HALF + 1), indexing="ij")
    ijk = np.stack([np.full(jj.size, WALL_I), jj.ravel(), kk.ravel()], axis=1)
    return (ijk + 0.5) * s


def integrate_wall(client, s):
    """Integrates the wall scene once; returns (origin, points)."""
    origin = centre(s, 0, 0, 0)
    points = wall_points(s)
    rgb = np.tile(np.array(WALL_RGB, dtype=np.uint8), (len(points), 1))
    client.integrate_points(origin, points, rgb=rgb, timestamp_s=1.0)
    return origin, points
