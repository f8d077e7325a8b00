"""cenote_client: Python client of cenote-server (proto/cenote/v1), with numpy in and out.

    from cenote_client import MapClient, VoxelState
    with MapClient("127.0.0.1:50051", token="secret") as client:
        states, probabilities = client.voxels([[1.0, 0.0, 0.0]])

The gRPC stubs are generated at build time (target cenote_python_stubs); set CENOTE_PYTHON_STUBS to
<build>/clients/python/gen or call use_stubs(path) before making a client.
"""

from ._stubs import StubsNotFound, use_stubs
from .client import SNAPSHOT_FORMATS, MapClient
from .dive import paced, read_dive
from .errors import CenoteError
from .local_server import LocalServer
from .types import (Ack, Block, BoxCounts, Change, Collisions, Extract, Frontier, IntegrateResult, MapInfo, MapUpdate,
                    MethodStats, SnapshotResult, StageTiming, Stats, VoxelState)

__all__ = ["MapClient", "read_dive", "paced", "CenoteError", "LocalServer", "VoxelState", "use_stubs", "StubsNotFound", "SNAPSHOT_FORMATS", "Ack",
           "Block", "BoxCounts", "Change", "Collisions", "Extract", "Frontier", "IntegrateResult", "MapInfo",
           "MapUpdate", "MethodStats", "SnapshotResult", "StageTiming", "Stats"]
