"""test_client.py: every MapClient call against a real cenote-server on loopback, with answers
known from an analytic scene (client_env.py: a wall 2.0 m ahead of the sensor), and the error
codes of bad calls (missing or wrong token: UNAUTHENTICATED and the map unchanged; NaN points,
negative radii, empty batches: INVALID_ARGUMENT; a batch over the limit: RESOURCE_EXHAUSTED), and
TLS / mutual TLS with certificates made by the openssl command (skipped without it).

Run: CENOTE_SERVER_BINARY=<build>/server/cenote-server CENOTE_PYTHON_STUBS=<build>/clients/python/gen \
     /usr/bin/python3 tests/clients/python/test_client.py
"""

import os
import shutil
import subprocess
import tempfile
import unittest

import numpy as np

from client_env import (SERVER_BINARY, TOKEN, WALL_HALF, WALL_I, WALL_RGB, centre, cenote_client, integrate_wall,
                        require_server)

from cenote_client import CenoteError, LocalServer, MapClient, VoxelState

S = 0.05  # the default voxel size (config/default.yaml); checked against GetMapInfo


class ServerCase(unittest.TestCase):
    """A fresh server per test class, with the wall integrated once."""

    @classmethod
    def setUpClass(cls):
        require_server(cls)
        cls.server = LocalServer(SERVER_BINARY, token=TOKEN)
        cls.client = MapClient(cls.server.target, token=TOKEN, timeout_s=30.0)
        cls.origin, cls.points = integrate_wall(cls.client, S)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        code = cls.server.close()
        log = cls.server.log()
        cls.server.remove()
        if code != 0:
            raise AssertionError(f"cenote-server exited with {code} after SIGTERM:\n{log}")

    def c(self, i, j, k):
        return centre(S, i, j, k)


class QueryTest(ServerCase):
    def test_info(self):
        info = self.client.info()
        self.assertAlmostEqual(info.voxel_size_m, S)
        self.assertEqual(info.occupied, (2 * WALL_HALF + 1) ** 2)
        self.assertGreater(info.free, 0)
        self.assertLessEqual(info.bounds_min[0], 0.0)
        self.assertGreaterEqual(info.bounds_max[0], (WALL_I + 1) * S - 1e-9)
        self.assertGreater(info.map_version, 0)
        self.assertAlmostEqual(info.prob_hit, 0.7)
        self.assertAlmostEqual(info.prob_miss, 0.4)
        self.assertAlmostEqual(info.max_distance_m, 2.0)

    def test_voxels(self):
        info = self.client.info()
        pts = [self.c(20, 0, 0),           # between origin and wall: free
               self.c(WALL_I, 0, 0),       # the wall
               self.c(WALL_I, 7, -3),
               self.c(WALL_I + 10, 0, 0),  # behind the wall
               [50.0, 50.0, 50.0]]         # never seen
        states, probs = self.client.voxels(pts)
        self.assertEqual(states.dtype, np.uint8)
        np.testing.assert_array_equal(states, [VoxelState.FREE, VoxelState.OCCUPIED, VoxelState.OCCUPIED,
                                               VoxelState.UNKNOWN, VoxelState.UNKNOWN])
        np.testing.assert_allclose(probs, [info.prob_miss, info.prob_hit, info.prob_hit, 0.5, 0.5], atol=1e-5)
        # every voxel on the sensor's axis up to the wall is free
        axis = np.array([self.c(i, 0, 0) for i in range(WALL_I)])
        states, _ = self.client.voxels(axis)
        self.assertTrue(np.all(states == VoxelState.FREE), states)

    def test_voxels_split_into_batches(self):
        small = MapClient(self.server.target, token=TOKEN, max_batch=7)
        axis = np.array([self.c(i, 0, 0) for i in range(WALL_I + 1)])
        states, probs = small.voxels(axis)
        self.assertEqual(len(states), WALL_I + 1)
        self.assertTrue(np.all(states[:-1] == VoxelState.FREE))
        self.assertEqual(states[-1], VoxelState.OCCUPIED)
        small.close()

    def test_boxes(self):
        n = 2 * WALL_HALF  # box edges at +-1.0 m: voxel centres j in [-20, 19]
        mins = [[WALL_I * S + 1e-3, -1.0, -1.0], [2.1, -0.5, -0.5], [0.5, -0.05, -0.05], [5, 5, 5]]
        maxs = [[(WALL_I + 1) * S - 1e-3, 1.0, 1.0], [3.0, 0.5, 0.5], [1.5, 0.05, 0.05], [4, 4, 4]]
        counts = self.client.boxes(mins, maxs)
        # the wall: all occupied
        self.assertEqual((counts.unknown[0], counts.free[0], counts.occupied[0]), (0, 0, n * n))
        self.assertTrue(counts.any_occupied[0])
        # behind it: 18 x 20 x 20 voxel centres, never seen
        self.assertEqual((counts.unknown[1], counts.free[1], counts.occupied[1]), (18 * 20 * 20, 0, 0))
        self.assertFalse(counts.any_occupied[1])
        # a 20 x 2 x 2 rod on the sensor's axis: free
        self.assertEqual((counts.unknown[2], counts.free[2], counts.occupied[2]), (0, 80, 0))
        # an empty box (min > max) counts nothing
        self.assertEqual((counts.unknown[3], counts.free[3], counts.occupied[3]), (0, 0, 0))

    def test_segments(self):
        o = self.origin
        starts = [o, o, o, self.c(20, 0, 0)]
        ends = [[3.0, o[1], o[2]],           # through the wall
                [1.5, o[1], o[2]],           # stops short of it
                [o[0], o[1], 1.5],           # up into the unknown
                [3.0, o[1], o[2]]]
        r = self.client.segments(starts, ends)
        self.assertTrue(r.hit[0])
        self.assertAlmostEqual(r.hit_distance_m[0], WALL_I * S, places=6)  # to the wall voxel's centre
        np.testing.assert_array_equal(r.hit_voxel[0], [WALL_I, 0, 0])
        np.testing.assert_allclose(r.hit_point[0], self.c(WALL_I, 0, 0))
        self.assertFalse(r.hit[1])
        self.assertFalse(r.crossed_unknown[1])
        self.assertTrue(r.clear[1])
        self.assertFalse(r.hit[2])
        self.assertTrue(r.crossed_unknown[2])
        self.assertTrue(r.clear[2])  # unknown is passable without stop_at_unknown
        self.assertAlmostEqual(r.hit_distance_m[3], (WALL_I - 20) * S, places=6)

        r = self.client.segments(starts, ends, stop_at_unknown=True)
        self.assertTrue(r.hit[0])  # the wall comes before the unknown behind it
        self.assertTrue(r.stopped_at_unknown[2])
        self.assertFalse(r.clear[2])
        self.assertFalse(r.hit[2])
        self.assertTrue(r.clear[1])

    def test_capsules(self):
        # a path parallel to the wall, 0.15 m from the wall voxels' centres
        x = (WALL_I - 3 + 0.5) * S
        start, end = [x, -0.5, self.origin[2]], [x, 0.5, self.origin[2]]
        r = self.client.capsules([start, start, start], [end, end, end], [0.0, 0.1, 0.2])
        np.testing.assert_array_equal(r.hit, [False, False, True])
        np.testing.assert_array_equal(r.clear, [True, True, False])
        self.assertEqual(r.hit_voxel[2][0], WALL_I)
        self.assertLessEqual(abs(r.hit_point[2][0] - self.c(WALL_I, 0, 0)[0]), 1e-9)

    def test_raycast(self):
        o = self.origin
        r = self.client.raycast([o, o, o], [[2.0, 0, 0], [1, 0, 0], [0, 0, 1]], max_range_m=5.0)
        self.assertTrue(r.hit[0])
        self.assertAlmostEqual(r.hit_distance_m[0], WALL_I * S, places=6)
        self.assertAlmostEqual(r.hit_distance_m[1], WALL_I * S, places=6)
        self.assertFalse(r.hit[2])
        short = self.client.raycast(o, [1, 0, 0], max_range_m=1.0)
        self.assertFalse(short.hit[0])
        self.assertTrue(short.clear[0])
        up = self.client.raycast(o, [0, 0, 1], max_range_m=1.0, stop_at_unknown=True)
        self.assertTrue(up.stopped_at_unknown[0])
        self.assertFalse(up.clear[0])

    def test_distances(self):
        pts = [self.c(WALL_I - 10, 0, 0),  # 0.5 m from the wall
               self.c(WALL_I - 20, 3, 2),  # 1.0 m
               self.c(WALL_I - 60, 0, 0),  # 3.0 m: beyond max_distance_m (2.0)
               [-20.0, 0.0, 0.0]]
        d, g = self.client.distances(pts)
        self.assertEqual(g.shape, (4, 3))
        # the field is exact Euclidean almost everywhere and never more than one voxel too large
        self.assertGreaterEqual(d[0], 0.5 - 1e-5)
        self.assertLessEqual(d[0], 0.5 + S)
        self.assertGreaterEqual(d[1], 1.0 - 1e-5)
        self.assertLessEqual(d[1], 1.0 + S)
        self.assertAlmostEqual(d[2], 2.0, places=5)
        self.assertAlmostEqual(d[3], 2.0, places=5)
        np.testing.assert_allclose(g[0], [-1, 0, 0], atol=0.1)   # away from the wall
        np.testing.assert_allclose(np.linalg.norm(g[1]), 1.0, atol=1e-4)
        np.testing.assert_array_equal(g[3], [0, 0, 0])

    def test_frontiers(self):
        fs = self.client.frontiers(self.origin)
        self.assertGreater(len(fs), 0)
        ds = [f.distance_m for f in fs]
        self.assertEqual(ds, sorted(ds))
        for f in fs:
            self.assertGreaterEqual(f.num_voxels, 10)  # map.frontier_min_voxels
            self.assertTrue(np.all(f.centroid >= f.bounds_min - 1e-9) and np.all(f.centroid <= f.bounds_max + 1e-9))
            # frontiers are free voxels: between the sensor and the wall
            self.assertGreaterEqual(f.centroid[0], 0.0)
            self.assertLessEqual(f.centroid[0], WALL_I * S)
            self.assertAlmostEqual(np.linalg.norm(f.direction), 1.0, places=3)
            self.assertAlmostEqual(f.distance_m, np.linalg.norm(f.centroid - self.origin), places=4)
        self.assertEqual(len(self.client.frontiers(self.origin, max_clusters=1)), 1)
        self.assertEqual(self.client.frontiers(self.origin, region=([50, 50, 50], [51, 51, 51])), [])

    def test_extract(self):
        info = self.client.info()
        wall = self.client.extract([WALL_I * S + 1e-3, -1.0, -1.0], [(WALL_I + 1) * S - 1e-3, 1.0, 1.0])
        n = (2 * WALL_HALF) ** 2
        self.assertAlmostEqual(wall.voxel_size_m, S)
        self.assertEqual(len(wall.states), n)
        self.assertTrue(np.all(wall.states == VoxelState.OCCUPIED))
        self.assertTrue(np.all(wall.ijk[:, 0] == WALL_I))
        np.testing.assert_allclose(wall.probabilities, info.prob_hit, atol=1e-5)
        np.testing.assert_array_equal(wall.rgb, np.tile(WALL_RGB, (n, 1)))
        np.testing.assert_allclose(wall.centres[:, 0], self.c(WALL_I, 0, 0)[0])
        behind = self.client.extract([2.1, -0.5, -0.5], [3.0, 0.5, 0.5])
        self.assertEqual(len(behind.states), 0)
        behind = self.client.extract([2.1, -0.5, -0.5], [3.0, 0.5, 0.5], include_unknown=True)
        self.assertEqual(len(behind.states), 18 * 20 * 20)
        self.assertTrue(np.all(behind.states == VoxelState.UNKNOWN))

    def test_stats(self):
        self.client.voxels([self.origin])
        st = self.client.stats()
        self.assertEqual(st.batches_integrated, 1)
        self.assertEqual(st.occupied, (2 * WALL_HALF + 1) ** 2)
        self.assertEqual(st.occupied, self.client.info().occupied)
        self.assertGreater(st.uptime_s, 0.0)
        self.assertGreater(st.map_memory_bytes, 0)
        voxels = st.method("Query/GetVoxels")
        self.assertIsNotNone(voxels, [m.method for m in st.methods])
        self.assertGreaterEqual(voxels.calls, 1)

    def assert_map_unchanged(self, before):
        after = self.client.info()
        self.assertEqual((after.map_version, after.occupied, after.free),
                         (before.map_version, before.occupied, before.free))

    def test_token_missing_or_wrong(self):
        before = self.client.info()
        for token in (None, "wrong-token", TOKEN + "x"):
            with MapClient(self.server.target, token=token) as bad:
                for call in (lambda: bad.voxels([self.origin]),
                             lambda: bad.integrate_points(self.origin, [[1.0, 1.0, 1.0]]),
                             lambda: bad.clear_box([-10, -10, -10], [10, 10, 10]),
                             lambda: bad.reset(),
                             lambda: bad.stats(),
                             lambda: next(bad.subscribe(timeout_s=10.0))):
                    with self.assertRaises(CenoteError) as ctx:
                        call()
                    self.assertEqual(ctx.exception.code, "UNAUTHENTICATED", str(ctx.exception))
        self.assert_map_unchanged(before)

    def test_invalid_arguments(self):
        before = self.client.info()
        nan = [float("nan"), 0.0, 0.0]
        calls = {"integrate NaN point": lambda: self.client.integrate_points(self.origin, [[1, 1, 1], nan]),
                 "integrate NaN origin": lambda: self.client.integrate_points(nan, [[1, 1, 1]]),
                 "integrate inf point": lambda: self.client.integrate_points(self.origin, [[np.inf, 0, 0]]),
                 "integrate empty": lambda: self.client.integrate_points(self.origin, np.zeros((0, 3))),
                 "voxels NaN": lambda: self.client.voxels([nan]),
                 "distances NaN": lambda: self.client.distances([nan]),
                 "segment NaN": lambda: self.client.segments([nan], [[1, 1, 1]]),
                 "negative radius": lambda: self.client.capsules([[0, 0, 0]], [[1, 1, 1]], -0.1),
                 "clear sphere negative radius": lambda: self.client.clear_sphere([0, 0, 0], -1.0),
                 "raycast zero direction": lambda: self.client.raycast([0, 0, 0], [0, 0, 0], 1.0)}
        for what, call in calls.items():
            with self.subTest(what):
                with self.assertRaises(CenoteError) as ctx:
                    call()
                self.assertEqual(ctx.exception.code, "INVALID_ARGUMENT", str(ctx.exception))
                self.assertTrue(ctx.exception.message)
        self.assert_map_unchanged(before)

    def test_batch_over_the_limit(self):
        before = self.client.info()
        unsplit = MapClient(self.server.target, token=TOKEN, max_batch=10**7)
        n = 100001  # server.limits.max_batch is 100000
        with self.assertRaises(CenoteError) as ctx:
            unsplit.voxels(np.zeros((n, 3)))
        self.assertEqual(ctx.exception.code, "RESOURCE_EXHAUSTED", str(ctx.exception))
        self.assertIn("max_batch", ctx.exception.message)
        unsplit.close()
        states, _ = self.client.voxels(np.zeros((n, 3)))  # split into two calls by the client
        self.assertEqual(len(states), n)
        self.assert_map_unchanged(before)

    def test_bad_shapes_fail_before_calling(self):
        with self.assertRaises(ValueError):
            self.client.voxels([[1.0, 2.0]])
        with self.assertRaises(ValueError):
            self.client.integrate_points(self.origin, [[1, 1, 1]], rgb=[[1, 2, 3], [4, 5, 6]])


class AdminTest(ServerCase):
    """Snapshots, clearing and the update stream; each test integrates the wall again if it needs it."""

    def setUp(self):
        self.client.reset()
        integrate_wall(self.client, S)

    def test_snapshot_on_server_and_download(self):
        info = self.client.info()
        written = self.client.snapshot("wall.bt")
        self.assertEqual(os.path.realpath(written.path),
                         os.path.realpath(os.path.join(self.server.snapshot_dir, "wall.bt")))
        self.assertEqual(written.map_version, info.map_version)
        with open(written.path, "rb") as f:
            on_disk = f.read()
        self.assertEqual(len(on_disk), written.bytes)
        self.assertEqual(self.client.download_snapshot(format="bt"), on_disk)  # same map, same OctoMap bytes
        vdb = self.client.snapshot("wall.vdb")
        self.assertGreater(vdb.bytes, 0)
        path = os.path.join(self.server.dir, "downloaded.vdb")
        self.assertEqual(self.client.download_snapshot(path), path)
        self.assertGreater(os.path.getsize(path), 0)
        # the format follows the local file's extension: an OctoMap tree, not a VDB named .bt (issue 14)
        bt_path = os.path.join(self.server.dir, "downloaded.bt")
        self.client.download_snapshot(bt_path)
        with open(bt_path, "rb") as f:
            self.assertEqual(f.read(), on_disk)
        for path, fmt in (("map.vdb", "points_ply"), ("mesh.ply", None), ("map.xyz", None)):
            with self.assertRaises(CenoteError) as ctx:
                self.client.snapshot(path, format=fmt)
            self.assertEqual(ctx.exception.code, "INVALID_ARGUMENT", str(ctx.exception))
            self.assertIn(path, ctx.exception.message)
        for bad in ("../escape.vdb", "/tmp/absolute.vdb"):
            with self.assertRaises(CenoteError) as ctx:
                self.client.snapshot(bad)
            self.assertEqual(ctx.exception.code, "PERMISSION_DENIED", str(ctx.exception))  # docs/SERVER.md

    def test_clear_box(self):
        change = self.client.clear_box([WALL_I * S + 1e-3, -1.0, -1.0], [(WALL_I + 1) * S - 1e-3, 1.0, 1.0])
        self.assertGreater(change.changed_blocks, 0)
        counts = self.client.boxes([[WALL_I * S + 1e-3, -1.0, -1.0]], [[(WALL_I + 1) * S - 1e-3, 1.0, 1.0]])
        self.assertEqual((counts.unknown[0], counts.occupied[0]), ((2 * WALL_HALF) ** 2, 0))
        # only the outermost ring of the wall (j or k = 20, centres beyond 1.0 m) is left
        self.assertEqual(self.client.info().occupied, (2 * WALL_HALF + 1) ** 2 - (2 * WALL_HALF) ** 2)

    def test_clear_sphere_and_crop(self):
        self.client.clear_sphere(self.c(20, 0, 0), 0.2)
        states, _ = self.client.voxels([self.c(20, 0, 0), self.c(23, 0, 0), self.c(10, 0, 0)])
        np.testing.assert_array_equal(states, [VoxelState.UNKNOWN, VoxelState.UNKNOWN, VoxelState.FREE])
        self.client.crop(self.origin, 1.0)
        states, _ = self.client.voxels([self.c(10, 0, 0), self.c(30, 0, 0), self.c(WALL_I, 0, 0)])
        np.testing.assert_array_equal(states, [VoxelState.FREE, VoxelState.UNKNOWN, VoxelState.UNKNOWN])
        self.assertEqual(self.client.info().occupied, 0)

    def test_reset(self):
        self.assertGreater(self.client.info().occupied, 0)  # premise: there is a map to reset
        before = self.client.info().map_version
        change = self.client.reset()
        self.assertGreater(change.map_version, before)
        info = self.client.info()
        self.assertEqual((info.occupied, info.free), (0, 0))
        self.assertEqual(self.client.frontiers(self.origin), [])

    def test_subscribe_gets_the_map_then_changes(self):
        info = self.client.info()
        # premise: the snapshot's counts are compared with a map that holds the wall
        self.assertEqual(info.occupied, (2 * WALL_HALF + 1) ** 2)
        self.assertGreater(info.free, 0)
        updates = self.client.subscribe(timeout_s=30.0)
        occupied = free = 0
        for update in updates:
            self.assertTrue(update.snapshot)
            self.assertAlmostEqual(update.voxel_size_m, S)
            for block in update.blocks:
                occupied += int(np.count_nonzero(block.states == VoxelState.OCCUPIED))
                free += int(np.count_nonzero(block.states == VoxelState.FREE))
            if update.snapshot_complete:
                break
        self.assertEqual((occupied, free), (info.occupied, info.free))
        # a change after the snapshot arrives as blocks whose wall voxels are now unknown
        self.client.clear_box([WALL_I * S + 1e-3, -0.2, -0.2], [(WALL_I + 1) * S - 1e-3, 0.2, 0.2])
        update = next(updates)
        self.assertFalse(update.snapshot)
        self.assertGreater(update.sequence, info.map_version)
        wall_block = [b for b in update.blocks if tuple(b.index) == (WALL_I // 8, 0, 0)]
        self.assertEqual(len(wall_block), 1)
        ijk = wall_block[0].voxel_indices()
        states = wall_block[0].states.ravel()
        at = np.flatnonzero((ijk[:, 0] == WALL_I) & (ijk[:, 1] == 0) & (ijk[:, 2] == 0))[0]
        self.assertEqual(states[at], VoxelState.UNKNOWN)
        updates.close()


def make_certificate(folder, name):
    """Self-signed certificate for 127.0.0.1 (openssl command): (pem path, key path)."""
    pem, key = os.path.join(folder, name + ".pem"), os.path.join(folder, name + ".key")
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=" + name,
                    "-addext", "subjectAltName=IP:127.0.0.1", "-keyout", key, "-out", pem],
                   check=True, capture_output=True)
    return pem, key


class TlsTest(unittest.TestCase):
    """TLS and mutual TLS from Python: root_cert, client_cert, client_key."""

    def setUp(self):
        require_server(self)
        if shutil.which("openssl") is None:
            self.skipTest("no openssl command")
        self.dir = tempfile.mkdtemp(prefix="cenote-tls-")
        self.server_pem, self.server_key = make_certificate(self.dir, "server")
        self.client_pem, self.client_key = make_certificate(self.dir, "client")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_tls_with_token(self):
        with LocalServer(SERVER_BINARY, token=TOKEN,
                         extra_args=["--tls-cert", self.server_pem, "--tls-key", self.server_key]) as server:
            with MapClient(server.target, token=TOKEN, root_cert=self.server_pem) as client:
                integrate_wall(client, S)
                states, _ = client.voxels([centre(S, WALL_I, 0, 0)])
                self.assertEqual(states[0], VoxelState.OCCUPIED)
            with MapClient(server.target, token="wrong", root_cert=self.server_pem) as client:
                with self.assertRaises(CenoteError) as ctx:
                    client.info()
                self.assertEqual(ctx.exception.code, "UNAUTHENTICATED")
            with MapClient(server.target, token=TOKEN, timeout_s=5.0) as plaintext:
                with self.assertRaises(CenoteError) as ctx:
                    plaintext.info()
                self.assertEqual(ctx.exception.code, "UNAVAILABLE")

    def test_mutual_tls(self):
        with LocalServer(SERVER_BINARY, extra_args=["--tls-cert", self.server_pem, "--tls-key", self.server_key,
                                                    "--tls-client-ca", self.client_pem]) as server:
            with MapClient(server.target, root_cert=self.server_pem, client_cert=self.client_pem,
                           client_key=self.client_key) as client:
                self.assertAlmostEqual(client.info().voxel_size_m, S)
            with MapClient(server.target, root_cert=self.server_pem, timeout_s=5.0) as anonymous:
                with self.assertRaises(CenoteError) as ctx:
                    anonymous.info()
                self.assertEqual(ctx.exception.code, "UNAVAILABLE")


if __name__ == "__main__":
    unittest.main(verbosity=2)
