"""client.py: MapClient, typed access to a running cenote-server from Python.

Every method is one gRPC call (queries larger than max_batch items are split into several calls,
each its own consistent read of the map) and returns numpy arrays or the dataclasses of types.py.
Units: metres, seconds; frame: the map's world frame. Points go in as anything numpy reads as
(N, 3) (a single point (3,) is a batch of one).
Errors: a failed call raises CenoteError (code = the gRPC status name, message = the server's
text); an argument of the wrong shape raises ValueError before any call.
Threads: one MapClient may be used from several threads at once (gRPC channels are thread-safe);
a subscription generator belongs to the thread iterating it.
"""

import os

import grpc
import numpy as np

from . import _stubs
from .errors import CenoteError, from_rpc_error, status_name
from .types import (Ack, Block, BoxCounts, Change, Collisions, Extract, Frontier, IntegrateResult, MapInfo, MapUpdate,
                    MethodStats, SnapshotResult, StageTiming, Stats)

SNAPSHOT_FORMATS = {"vdb": 1, "bt": 2, "ot": 3, "mesh_ply": 4, "points_ply": 5, "points_pcd": 6}
_MAX_MESSAGE_BYTES = 64 * 1024 * 1024


def _points(value, name):
    """(N, 3) float64 array from anything array-like; a single point becomes a batch of one."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape == (3,):
        arr = arr.reshape(1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name}: expected an (N, 3) array of points, got shape {arr.shape}")
    return arr


def _vec3(msg, value):
    x, y, z = (float(v) for v in np.asarray(value, dtype=np.float64).reshape(3))
    msg.x, msg.y, msg.z = x, y, z
    return msg


def _np3(v):
    return np.array([v.x, v.y, v.z], dtype=np.float64)


# The table of mapping/io/map_file_format.h, which the server and the C++ clients use: the format
# follows the extension, and a format given must agree with it (a plain .ply needs one).
# tests/mapping/io/map_file_format_cases.txt checks this copy against the C++ one.
_EXTENSIONS = ((".vdb", 1), (".bt", 2), (".ot", 3), (".mesh.ply", 4), (".points.ply", 5), (".pcd", 6))
_FORMAT_NAMES = {v: k.replace("_", "-") for k, v in SNAPSHOT_FORMATS.items()}
_TABLE = ", ".join(f"{ext} {_FORMAT_NAMES[f]}" for ext, f in _EXTENSIONS) + ", .ply mesh-ply or points-ply as given"


def _format_number(fmt):
    if fmt is None:
        return 0
    if isinstance(fmt, str):
        key = fmt.lower().replace(".", "").replace("-", "_")
        if key not in SNAPSHOT_FORMATS:
            raise ValueError(f"format: {fmt!r} is not one of {sorted(SNAPSHOT_FORMATS)}")
        return SNAPSHOT_FORMATS[key]
    return int(fmt)


def _snapshot_format(fmt, path, method="Admin/Snapshot"):
    """The SnapshotFormat number of path by the table above; raises CenoteError INVALID_ARGUMENT
    (the server's code for the same refusal) for an unknown extension, a plain .ply without a
    format, or a format the extension disagrees with."""
    requested = _format_number(fmt)
    name = os.path.basename(path).lower()
    named = next((f for ext, f in _EXTENSIONS if name.endswith(ext) and len(name) > len(ext)), 0)
    plain_ply = named == 0 and name.endswith(".ply") and len(name) > 4
    ext = os.path.splitext(path)[1]
    ext_text = f"the extension {ext}" if ext else "no extension"
    if requested == 0:
        if named:
            return named
        if plain_ply:
            raise CenoteError("INVALID_ARGUMENT", f"{path}: a .ply file holds a mesh or points: name it .mesh.ply or "
                              ".points.ply, or give the format mesh-ply or points-ply", method)
        raise CenoteError("INVALID_ARGUMENT", f"{path}: {ext_text} names no map file format ({_TABLE})", method)
    if requested == named or (plain_ply and requested in (4, 5)):
        return requested
    wanted = _FORMAT_NAMES.get(requested, str(requested))
    if named == 0 and not plain_ply:
        raise CenoteError("INVALID_ARGUMENT", f"{path}: {ext_text} does not match format {wanted} ({_TABLE})", method)
    means = "mesh-ply or points-ply" if plain_ply else _FORMAT_NAMES[named]
    raise CenoteError("INVALID_ARGUMENT", f"{path}: {ext_text} means format {means}, not {wanted} "
                      f"(the format follows the extension: {_TABLE})", method)


def _read_bytes(value):
    if value is None or isinstance(value, bytes):
        return value
    with open(value, "rb") as f:
        return f.read()


class MapClient:
    """A connection to one cenote-server.

    target: "host:port". token: the bearer token (sent as `authorization: Bearer <token>` on every
    call). root_cert: PEM bytes or a file path; given, the channel uses TLS (client_cert and
    client_key add mutual TLS; server_name overrides the name checked in the server's certificate).
    timeout_s: deadline of every unary call. max_batch: queries with more items are split.
    """

    def __init__(self, target, token=None, root_cert=None, timeout_s=10.0, client_cert=None, client_key=None,
                 server_name=None, max_batch=100000):
        self.pb = _stubs.load()
        self.target = target
        self.timeout_s = timeout_s
        self.max_batch = int(max_batch)
        self._metadata = (("authorization", f"Bearer {token}"),) if token else ()
        options = [("grpc.max_receive_message_length", _MAX_MESSAGE_BYTES),
                   ("grpc.max_send_message_length", _MAX_MESSAGE_BYTES)]
        if root_cert is not None:
            creds = grpc.ssl_channel_credentials(root_certificates=_read_bytes(root_cert),
                                                 private_key=_read_bytes(client_key),
                                                 certificate_chain=_read_bytes(client_cert))
            if server_name:
                options.append(("grpc.ssl_target_name_override", server_name))
            self._channel = grpc.secure_channel(target, creds, options=options)
        else:
            self._channel = grpc.insecure_channel(target, options=options)
        self._query = self.pb.query_grpc.QueryStub(self._channel)
        self._ingest = self.pb.ingest_grpc.IngestStub(self._channel)
        self._admin = self.pb.admin_grpc.AdminStub(self._channel)
        self._updates = self.pb.updates_grpc.UpdatesStub(self._channel)

    # -- connection -------------------------------------------------------------------------------
    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def wait_ready(self, timeout_s=10.0):
        """Blocks until the channel is connected; CenoteError UNAVAILABLE after timeout_s."""
        try:
            grpc.channel_ready_future(self._channel).result(timeout=timeout_s)
        except grpc.FutureTimeoutError:
            raise CenoteError("UNAVAILABLE", f"no server at {self.target} after {timeout_s} s") from None

    def _call(self, method, stub_method, request, timeout_s=None):
        try:
            return stub_method(request, timeout=timeout_s or self.timeout_s, metadata=self._metadata)
        except grpc.RpcError as e:
            raise from_rpc_error(e, method) from None

    def _chunks(self, n):
        step = max(1, self.max_batch)
        return [(i, min(n, i + step)) for i in range(0, max(n, 1), step)]

    def _point_calls(self, pts, method, stub_method, request_type):
        """The replies of one call of stub_method per chunk of the (N, 3) points pts, each sent as
        request_type(xyz=...)."""
        return [self._call(method, stub_method, request_type(xyz=pts[a:b].ravel().tolist()))
                for a, b in self._chunks(len(pts))]

    # -- queries ----------------------------------------------------------------------------------
    def voxels(self, points):
        """States (uint8, VoxelState) and occupancy probabilities (float32, 0.5 where unknown) of
        the voxels holding each point."""
        replies = self._point_calls(_points(points, "points"), "Query/GetVoxels", self._query.GetVoxels,
                                    self.pb.query.VoxelsRequest)
        return (np.concatenate([np.array(r.states, dtype=np.uint8) for r in replies]),
                np.concatenate([np.array(r.probabilities, dtype=np.float32) for r in replies]))

    def boxes(self, mins, maxs):
        """Unknown / free / occupied voxel counts of each box [mins[i], maxs[i]]."""
        lo, hi = _points(mins, "mins"), _points(maxs, "maxs")
        if lo.shape != hi.shape:
            raise ValueError(f"boxes: {len(lo)} mins but {len(hi)} maxs")
        rows, version = [], 0
        for a, b in self._chunks(len(lo)):
            req = self.pb.query.BoxesRequest()
            for mn, mx in zip(lo[a:b], hi[a:b]):
                box = req.boxes.add()
                _vec3(box.min, mn)
                _vec3(box.max, mx)
            reply = self._call("Query/GetBoxes", self._query.GetBoxes, req)
            rows.extend((c.unknown, c.free, c.occupied, c.any_occupied) for c in reply.counts)
            version = reply.map_version
        arr = np.array(rows, dtype=np.uint64).reshape(-1, 4)
        return BoxCounts(arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3].astype(bool), version)

    def segments(self, starts, ends, radius_m=0.0, stop_at_unknown=False):
        """First occupied voxel along each segment starts[i] -> ends[i]; radius_m (a scalar or one
        per segment) > 0 makes capsules. stop_at_unknown: unknown is not free to pass."""
        p0, p1 = _points(starts, "starts"), _points(ends, "ends")
        if p0.shape != p1.shape:
            raise ValueError(f"segments: {len(p0)} starts but {len(p1)} ends")
        radii = np.broadcast_to(np.asarray(radius_m, dtype=np.float64), (len(p0),))
        replies = []
        for a, b in self._chunks(len(p0)):
            req = self.pb.query.SegmentsRequest(stop_at_unknown=bool(stop_at_unknown))
            for s, e, r in zip(p0[a:b], p1[a:b], radii[a:b]):
                seg = req.segments.add(radius_m=float(r))
                _vec3(seg.start, s)
                _vec3(seg.end, e)
            replies.append(self._call("Query/CheckSegments", self._query.CheckSegments, req))
        return self._collisions(replies)

    def capsules(self, starts, ends, radius_m, stop_at_unknown=False):
        """segments() with a radius: does a body of radius_m fit along each straight path?"""
        return self.segments(starts, ends, radius_m, stop_at_unknown)

    def raycast(self, origins, directions, max_range_m, stop_at_unknown=False):
        """First occupied voxel along each ray within max_range_m (directions of any non-zero length)."""
        o, d = _points(origins, "origins"), _points(directions, "directions")
        if len(o) == 1 and len(d) > 1:
            o = np.repeat(o, len(d), axis=0)
        if o.shape != d.shape:
            raise ValueError(f"raycast: {len(o)} origins but {len(d)} directions")
        replies = []
        for a, b in self._chunks(len(o)):
            req = self.pb.query.RaycastRequest(max_range_m=float(max_range_m), stop_at_unknown=bool(stop_at_unknown))
            for oo, dd in zip(o[a:b], d[a:b]):
                ray = req.rays.add()
                _vec3(ray.origin, oo)
                _vec3(ray.direction, dd)
            replies.append(self._call("Query/Raycast", self._query.Raycast, req))
        return self._collisions(replies)

    def _collisions(self, replies):
        results = [r for reply in replies for r in reply.results]
        n = len(results)
        get = lambda f, dt: np.fromiter((f(r) for r in results), dtype=dt, count=n)  # noqa: E731
        return Collisions(
            hit=get(lambda r: r.hit, bool),
            hit_distance_m=get(lambda r: r.hit_distance_m, np.float64),
            hit_voxel=np.array([(r.hit_voxel.x, r.hit_voxel.y, r.hit_voxel.z) for r in results],
                               dtype=np.int32).reshape(n, 3),
            hit_point=np.array([(r.hit_point.x, r.hit_point.y, r.hit_point.z) for r in results],
                               dtype=np.float64).reshape(n, 3),
            crossed_unknown=get(lambda r: r.crossed_unknown, bool),
            unknown_distance_m=get(lambda r: r.unknown_distance_m, np.float64),
            stopped_at_unknown=get(lambda r: r.stopped_at_unknown, bool),
            clear=get(lambda r: r.clear, bool),
            map_version=replies[-1].map_version if replies else 0)

    def distances(self, points):
        """Distance to the nearest occupied voxel (float32, max_distance_m where none is nearer) and
        its gradient ((N, 3) float32, unit, away from the obstacle; zero at max) at each point.
        Unknown voxels are not obstacles: check voxels() too."""
        replies = self._point_calls(_points(points, "points"), "Query/GetDistances", self._query.GetDistances,
                                    self.pb.query.DistancesRequest)
        return (np.concatenate([np.array(r.distances_m, dtype=np.float32) for r in replies]),
                np.concatenate([np.array(r.gradients, dtype=np.float32).reshape(-1, 3) for r in replies]))

    def frontiers(self, position, region=None, max_clusters=0):
        """Frontier clusters sorted by distance of their centroid from position; region: only
        clusters whose centroid lies in the box (min, max); max_clusters 0: all."""
        req = self.pb.query.FrontiersRequest(max_clusters=int(max_clusters))
        _vec3(req.position, position)
        if region is not None:
            _vec3(req.region.min, region[0])
            _vec3(req.region.max, region[1])
        reply = self._call("Query/GetFrontiers", self._query.GetFrontiers, req)
        return [Frontier(id=f.id, num_voxels=f.num_voxels, centroid=_np3(f.centroid), bounds_min=_np3(f.bounds.min),
                         bounds_max=_np3(f.bounds.max), direction=_np3(f.direction), distance_m=f.distance_m)
                for f in reply.frontiers]

    def extract(self, box_min, box_max, include_unknown=False):
        """Every known voxel (and the unknown ones too with include_unknown) whose centre lies in
        the box."""
        req = self.pb.query.ExtractRequest(include_unknown=bool(include_unknown))
        _vec3(req.box.min, box_min)
        _vec3(req.box.max, box_max)
        reply = self._call("Query/ExtractVoxels", self._query.ExtractVoxels, req)
        n = len(reply.states)
        rgb = np.frombuffer(reply.rgb, dtype=np.uint8)
        return Extract(voxel_size_m=reply.voxel_size_m,
                       ijk=np.array(reply.ijk, dtype=np.int32).reshape(n, 3),
                       states=np.array(reply.states, dtype=np.uint8),
                       probabilities=np.array(reply.probabilities, dtype=np.float32),
                       rgb=rgb.reshape(n, 3) if rgb.size == 3 * n else np.zeros((n, 3), np.uint8),
                       map_version=reply.map_version)

    def info(self):
        """The map's metadata: voxel size, frame, bounds of the known voxels, sensor model."""
        r = self._call("Query/GetMapInfo", self._query.GetMapInfo, self.pb.query.MapInfoRequest())
        return MapInfo(voxel_size_m=r.voxel_size_m, frame_id=r.frame_id, bounds_min=_np3(r.bounds.min),
                       bounds_max=_np3(r.bounds.max), occupied=r.occupied, free=r.free, prob_hit=r.prob_hit,
                       prob_miss=r.prob_miss, clamp_min=r.clamp_min, clamp_max=r.clamp_max,
                       occupied_threshold=r.occupied_threshold, max_range_m=r.max_range_m,
                       max_distance_m=r.max_distance_m, map_version=r.map_version)

    # -- ingest -----------------------------------------------------------------------------------
    def integrate_points(self, origin, points, rgb=None, timestamp_s=0.0):
        """Integrates world-frame points seen from the sensor origin (free space along each ray, a
        hit at its end). rgb: None or (N, 3) uint8."""
        pts = _points(points, "points")
        # float32 on the wire: half the bytes, and the server's map stores float32 points anyway.
        req = self.pb.ingest.PointBatch(timestamp_s=float(timestamp_s),
                                        xyz_f32=pts.astype(np.float32).ravel().tolist())
        _vec3(req.origin, origin)
        if rgb is not None:
            colours = np.asarray(rgb, dtype=np.uint8)
            if colours.shape != pts.shape:
                raise ValueError(f"rgb: expected shape {pts.shape} (one colour per point), got {colours.shape}")
            req.rgb = colours.tobytes()
        ack = self._call("Ingest/IntegratePoints", self._ingest.IntegratePoints, req)
        if ack.status_code != 0:
            raise CenoteError(status_name(ack.status_code), ack.message, "Ingest/IntegratePoints")
        return IntegrateResult(ack.voxels_updated, ack.changed_blocks, ack.map_version)

    def _image(self, msg, image, bayer=None):
        """Fills an Image message: bytes are sent as encoded (PNG / JPEG), a uint8 array (H, W) or
        (H, W, 3) BGR as raw pixels; with `bayer` an (H, W) array is that Bayer mosaic."""
        if isinstance(image, (bytes, bytearray)):
            msg.encoded = bytes(image)
            return
        arr = np.ascontiguousarray(image, dtype=np.uint8)
        if bayer is not None and arr.ndim == 2:
            encoding = getattr(self.pb.ingest, "IMAGE_ENCODING_BAYER_" + bayer.upper() + "8")
        elif arr.ndim == 2:
            encoding = self.pb.ingest.IMAGE_ENCODING_MONO8
        elif arr.ndim == 3 and arr.shape[2] == 3:
            encoding = self.pb.ingest.IMAGE_ENCODING_BGR8
        else:
            raise ValueError(f"image: expected encoded bytes or a uint8 (H, W) or (H, W, 3) array, got shape {arr.shape}")
        msg.raw.width, msg.raw.height, msg.raw.encoding = arr.shape[1], arr.shape[0], encoding
        msg.raw.data = arr.tobytes()

    def _pose(self, msg, pose):
        """pose: (position (3,), quaternion (x, y, z, w)) of the raw left camera in the world."""
        position, quaternion = pose
        _vec3(msg.position, position)
        q = np.asarray(quaternion, dtype=np.float64).reshape(4)
        msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = (float(v) for v in q)

    def _stream(self, method, stub_method, requests, ack_of, timeout_s):
        # No default deadline, unlike unary calls: a stream lasts as long as its input (a whole
        # dive's frames), which the client cannot know; the caller bounds it with timeout_s.
        # A server that goes away closes the connection, which ends the stream with UNAVAILABLE.
        try:
            replies = stub_method(requests, timeout=timeout_s, metadata=self._metadata)
            return [ack_of(r) for r in replies]
        except grpc.RpcError as e:
            raise from_rpc_error(e, method) from None

    def stream_frames(self, frames, timeout_s=None, bayer=None):
        """Sends stereo frames through the server's pipeline (rectify, stereo, fusion, map) in one
        stream and returns one Ack per frame. frames: iterable of (timestamp_s, left, right) or
        (timestamp_s, left, right, pose); images as encoded bytes or uint8 arrays; pose as in
        stream_poses (without one, the server matches streamed poses by time). bayer: "rggb",
        "bggr", "gbrg" or "grbg" to send (H, W) arrays as a raw colour camera's mosaics of that
        pattern (the server demosaics them), None for grey. The call returns once every frame's
        points are in the map. A bad frame is rejected in its Ack; the stream goes on."""
        if bayer not in (None, "rggb", "bggr", "gbrg", "grbg"):
            raise ValueError(f"bayer: expected None, 'rggb', 'bggr', 'gbrg' or 'grbg', got {bayer!r}")
        outcomes = {v: k.replace("FRAME_OUTCOME_", "") for k, v in self.pb.ingest.FrameOutcome.items()}

        def requests():
            for frame in frames:
                msg = self.pb.ingest.StereoFrame(timestamp_s=float(frame[0]))
                self._image(msg.left, frame[1], bayer)
                self._image(msg.right, frame[2], bayer)
                if len(frame) > 3 and frame[3] is not None:
                    self._pose(msg.pose, frame[3])
                yield msg

        return self._stream("Ingest/StreamFrames", self._ingest.StreamFrames, requests(),
                            lambda a: Ack(a.sequence, a.timestamp_s, outcomes.get(a.outcome, str(a.outcome)),
                                          status_name(a.status_code), a.message), timeout_s)

    def stream_poses(self, timestamps_s, positions, quaternions_xyzw, timeout_s=None):
        """Streams camera poses (T_world_cam of the raw left camera, at VIO rate) for frames sent
        without a pose of their own. Returns one Ack per pose (outcome STORED or REJECTED)."""
        t = np.asarray(timestamps_s, dtype=np.float64).reshape(-1)
        p = _points(positions, "positions")
        q = np.asarray(quaternions_xyzw, dtype=np.float64).reshape(-1, 4)
        if not (len(t) == len(p) == len(q)):
            raise ValueError(f"poses: {len(t)} timestamps, {len(p)} positions, {len(q)} quaternions")

        def requests():
            for i in range(len(t)):
                msg = self.pb.ingest.PoseStamped(timestamp_s=float(t[i]))
                self._pose(msg.pose, (p[i], q[i]))
                yield msg

        return self._stream("Ingest/StreamPoses", self._ingest.StreamPoses, requests(),
                            lambda a: Ack(a.sequence, a.timestamp_s, "STORED" if a.status_code == 0 else "REJECTED",
                                          status_name(a.status_code), a.message), timeout_s)

    # -- updates ----------------------------------------------------------------------------------
    def subscribe(self, region=None, include_probabilities=False, timeout_s=None):
        """Generator of MapUpdate: first the whole map (snapshot updates, the last with
        snapshot_complete), then every change. region: only blocks holding a voxel whose centre lies in the box (min, max).
        Runs until closed (close() the generator or leave its loop), timeout_s, or the server ends."""
        req = self.pb.updates.SubscribeRequest(include_probabilities=bool(include_probabilities))
        if region is not None:
            _vec3(req.region.min, region[0])
            _vec3(req.region.max, region[1])
        call = self._updates.Subscribe(req, timeout=timeout_s, metadata=self._metadata)
        return self._updates_of(call)

    def _updates_of(self, call):
        try:
            for msg in call:
                yield self._to_update(msg)
        except grpc.RpcError as e:
            if e.code() == grpc.StatusCode.DEADLINE_EXCEEDED and call.time_remaining() is not None:
                return  # the subscription's own timeout: a normal end
            raise from_rpc_error(e, "Updates/Subscribe") from None
        finally:
            call.cancel()

    @staticmethod
    def _to_update(msg):
        blocks = []
        for b in msg.blocks:
            states = np.frombuffer(b.states, dtype=np.uint8)
            probs = np.array(b.probabilities, dtype=np.float32).reshape(8, 8, 8) if len(b.probabilities) else None
            blocks.append(Block(index=np.array([b.index.x, b.index.y, b.index.z], dtype=np.int32),
                                states=states.reshape(8, 8, 8) if states.size == 512 else states,
                                probabilities=probs))
        return MapUpdate(sequence=msg.sequence, snapshot=msg.snapshot, snapshot_complete=msg.snapshot_complete,
                         resync=msg.resync, bounds_min=_np3(msg.changed_bounds.min),
                         bounds_max=_np3(msg.changed_bounds.max), voxel_size_m=msg.voxel_size_m, blocks=blocks)

    # -- admin ------------------------------------------------------------------------------------
    def snapshot(self, path, format=None):
        """Writes the map on the server under its snapshot directory (path relative to it) in the
        format its extension names; format: "vdb", "bt", "ot", "mesh_ply", "points_ply",
        "points_pcd" or None (from the extension); one given must agree with the extension.
        Raises CenoteError INVALID_ARGUMENT, before any call, when it does not."""
        req = self.pb.admin.SnapshotRequest(path=path, format=_snapshot_format(format, path))
        r = self._call("Admin/Snapshot", self._admin.Snapshot, req)
        return SnapshotResult(r.path, r.bytes, r.map_version)

    def download_snapshot(self, dest=None, format=None, timeout_s=None):
        """Streams the map file from the server. dest given: written there (atomically, through
        dest + ".part") and its path returned, in the format dest's extension names, as in
        snapshot(); else the file's bytes, in format (VDB when None)."""
        if dest is None:
            req = self.pb.admin.SnapshotRequest(format=_format_number(format) or SNAPSHOT_FORMATS["vdb"])
        else:
            fmt = _snapshot_format(format, dest, "Admin/DownloadSnapshot")
            req = self.pb.admin.SnapshotRequest(path=os.path.basename(dest), format=fmt)
        data, total = bytearray(), None
        try:
            for chunk in self._admin.DownloadSnapshot(req, timeout=timeout_s or max(self.timeout_s, 60.0),
                                                      metadata=self._metadata):
                if chunk.offset != len(data):
                    raise CenoteError("DATA_LOSS", f"chunk at offset {chunk.offset} but {len(data)} bytes received",
                                      "Admin/DownloadSnapshot")
                total = chunk.total_bytes
                data += chunk.data
        except grpc.RpcError as e:
            raise from_rpc_error(e, "Admin/DownloadSnapshot") from None
        if total is not None and total != len(data):
            raise CenoteError("DATA_LOSS", f"received {len(data)} of {total} bytes", "Admin/DownloadSnapshot")
        if dest is None:
            return bytes(data)
        with open(dest + ".part", "wb") as f:
            f.write(data)
        os.replace(dest + ".part", dest)
        return dest

    def clear_box(self, box_min, box_max):
        """Forgets (makes unknown) the voxels whose centre lies in the box."""
        req = self.pb.admin.ClearBoxRequest()
        _vec3(req.box.min, box_min)
        _vec3(req.box.max, box_max)
        return self._change(self._call("Admin/ClearBox", self._admin.ClearBox, req))

    def clear_sphere(self, centre, radius_m):
        req = self.pb.admin.ClearSphereRequest(radius_m=float(radius_m))
        _vec3(req.centre, centre)
        return self._change(self._call("Admin/ClearSphere", self._admin.ClearSphere, req))

    def crop(self, centre, radius_m):
        """Forgets everything outside the sphere."""
        req = self.pb.admin.CropRequest(radius_m=float(radius_m))
        _vec3(req.centre, centre)
        return self._change(self._call("Admin/Crop", self._admin.Crop, req))

    def reset(self):
        return self._change(self._call("Admin/Reset", self._admin.Reset, self.pb.admin.ResetRequest()))

    @staticmethod
    def _change(r):
        return Change(r.changed_blocks, _np3(r.changed_bounds.min), _np3(r.changed_bounds.max), r.map_version)

    def stats(self):
        r = self._call("Admin/GetStats", self._admin.GetStats, self.pb.admin.StatsRequest())
        return Stats(uptime_s=r.uptime_s, frames_received=r.frames_received, frames_processed=r.frames_processed,
                     frames_skipped=r.frames_skipped, frames_rejected=r.frames_rejected,
                     batches_integrated=r.batches_integrated, poses_received=r.poses_received, occupied=r.occupied,
                     free=r.free, map_memory_bytes=r.map_memory_bytes, process_memory_bytes=r.process_memory_bytes,
                     map_version=r.map_version, subscribers=r.subscribers, last_snapshot_age_s=r.last_snapshot_age_s,
                     stages=[StageTiming(s.name, s.median_ms, s.p95_ms, s.count) for s in r.stages],
                     methods=[MethodStats(m.method, m.calls, m.errors, m.p50_ms, m.p99_ms) for m in r.methods])
