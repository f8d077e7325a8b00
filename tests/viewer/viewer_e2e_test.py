#!/usr/bin/python3
"""viewer_e2e_test.py: cenote-server's live viewer end to end, with independent clients.

A simulated cave dive (cenote sim) is streamed into a real cenote-server (poses, then stereo frames,
over gRPC with the Python client) while two clients watch its viewer port:
 - npm @foxglove/ws-protocol on Node (web/test/protocol_client.mjs): the channels and their
   schemas, messages on every channel, error statuses for bad client messages, HTTP 401 without
   the token (given as an Authorization header here), and the map it mirrors: its occupied voxels
   at full detail equal the server's occupied count; the camera images are a frame of the dive
   (left) and its disparity within 2 px of the simulator's true depth (preview);
 - Debian's headless Chromium driven by npm playwright-core (web/test/browser_check.mjs) loading the
   browser viewer from the same port (token in the URL): the page reports the same voxel count and
   the frames it received; its screenshot is saved as a test artifact.

usage: viewer_e2e_test.py CENOTE CENOTE_SERVER WEB_SOURCE_DIR WEB_DIST_DIR ARTIFACT_DIR
"""

import base64
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.abspath(os.path.join(HERE, "..", "..", "clients", "python")))

import cv2  # noqa: E402
import numpy as np  # noqa: E402
from cenote_client import LocalServer, MapClient, read_dive  # noqa: E402

CENOTE, SERVER, WEB, DIST, ARTIFACTS = sys.argv[1:6]
TOKEN = "viewer-e2e-token"
FRAMES = 16


def viewer_port(server, timeout_s=30.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        match = re.search(r"viewer on http://127\.0\.0\.1:(\d+)/", server.log())
        if match:
            return int(match.group(1))
        time.sleep(0.1)
    raise RuntimeError("cenote-server did not report its viewer port:\n" + server.log())


class ViewerEndToEnd(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="cenote-viewer-e2e-")
        cls.dive = os.path.join(cls.tmp.name, "dive")
        subprocess.run([CENOTE, "sim", "--scene", "cave", "--frames", str(FRAMES), "--width", "400", "--height", "300",
                        "--quiet", "--out", cls.dive], check=True, stdout=subprocess.DEVNULL)
        config = os.path.join(cls.tmp.name, "viewer.yaml")
        with open(config, "w") as f:
            f.write(f"server:\n  viewer:\n    web_dir: {DIST}\n")
        cls.server = LocalServer(SERVER, token=TOKEN, config=config,
                                 extra_args=["--calibration", cls.dive, "--viewer-listen", "127.0.0.1:0"])
        cls.port = viewer_port(cls.server)
        cls.client = MapClient(cls.server.target, token=TOKEN, timeout_s=120)
        # The protocol client watches from before the first frame: it sees the map grow.
        env = dict(os.environ, AUTH_HEADER=f"Bearer {TOKEN}")
        cls.watcher = subprocess.Popen(["node", os.path.join(WEB, "test", "protocol_client.mjs"),
                                        f"ws://127.0.0.1:{cls.port}/"], cwd=WEB, env=env, stdin=subprocess.PIPE,
                                       stdout=subprocess.PIPE, text=True)
        time.sleep(1.0)
        # The poses first, then the frames without them: the server matches each frame to the
        # streamed poses by time.
        dive = read_dive(cls.dive)
        cls.client.stream_poses([f[0] for f in dive], [f[3][0] for f in dive], [f[3][1] for f in dive])
        frames = [(t_s, left, right) for t_s, left, right, _ in dive]
        cls.acks = cls.client.stream_frames(frames, timeout_s=300)
        cls.occupied = cls.client.info().occupied
        out, _ = cls.watcher.communicate(f"occupied {cls.occupied}\n", timeout=180)
        cls.report = json.loads(out.strip().splitlines()[-1])
        cls.watcher_code = cls.watcher.returncode

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.server.close()
        cls.server.remove()
        cls.tmp.cleanup()

    def test_the_dive_was_mapped(self):
        self.assertEqual([a.outcome for a in self.acks], ["PROCESSED"] * FRAMES)
        self.assertGreater(self.occupied, 5000)

    def test_channels_are_advertised_with_their_schemas(self):
        channels = {c["topic"]: c for c in self.report["channels"]}
        expected = {"/map": "foxglove.SceneUpdate", "/camera": "foxglove.FrameTransform",
                    "/trajectory": "foxglove.PosesInFrame", "/cloud": "foxglove.PointCloud",
                    "/frontiers": "foxglove.SceneUpdate", "/stats": "cenote.MapStats",
                    "/camera/image": "foxglove.CompressedImage", "/camera/disparity": "foxglove.CompressedImage"}
        self.assertEqual({t: c["schemaName"] for t, c in channels.items()}, expected)
        for topic, channel in channels.items():
            self.assertEqual(channel["encoding"], "json", topic)
            self.assertEqual(channel["schemaEncoding"], "jsonschema", topic)
            schema = json.loads(channel["schema"])
            self.assertEqual(schema["title"], expected[topic], topic)
        self.assertIn("entities", json.loads(channels["/map"]["schema"])["properties"])
        self.assertEqual(self.report["serverInfo"]["name"], "cenote-server")

    def test_the_mirrored_map_holds_every_occupied_voxel_of_the_server(self):
        self.assertEqual(self.watcher_code, 0, self.report)
        self.assertEqual(self.report["fullVoxels"], self.occupied)
        self.assertEqual(self.report["coarseBlocks"], 0)
        self.assertEqual(self.report["latestStats"]["occupied"], self.occupied)
        self.assertEqual(self.report["latestStats"]["client_dirty_blocks"], 0)
        self.assertEqual(self.report["malformedMessages"], 0)
        self.assertLessEqual(self.report["maxEntityVoxels"], 512)
        print(f"viewer: {self.report['fullVoxels']} voxels in {self.report['blocks']} blocks, "
              f"{self.report['bytes']} bytes, messages {self.report['messages']}")

    def test_every_channel_carried_messages(self):
        messages = self.report["messages"]
        for topic in ["/map", "/camera", "/trajectory", "/cloud", "/frontiers", "/stats", "/camera/image",
                      "/camera/disparity"]:
            self.assertGreater(messages.get(topic, 0), 0, topic)
        self.assertEqual(self.report["trajectoryPoses"], self.report["latestStats"]["batches"])
        self.assertGreater(self.report["cloudPoints"], 100)
        self.assertLessEqual(self.report["cloudPoints"], 5000)

    def image(self, topic):
        message = self.report["images"][topic]
        self.assertEqual(message["format"], "jpeg", topic)
        image = cv2.imdecode(np.frombuffer(base64.b64decode(message["data"]), np.uint8), cv2.IMREAD_COLOR)
        self.assertIsNotNone(image, topic)
        return image

    def test_the_camera_images_are_a_frame_of_the_dive_and_its_disparity(self):
        left = self.image("/camera/image").astype(np.float32)
        preview = self.image("/camera/disparity")
        self.assertEqual(left.shape, (300, 400, 3))  # the dive's size, below image_max_width_px
        self.assertEqual(preview.shape, left.shape)
        # The left image is one of the dive's (already rectified: the simulated rig has no
        # distortion), up to JPEG's error (its colours are subsampled) and rectification's
        # resampling: find which; the neighbouring frames, 1/15 s apart, differ by twice as much.
        names = sorted(os.listdir(os.path.join(self.dive, "mav0", "cam0", "data")))
        errors = [np.abs(cv2.imread(os.path.join(self.dive, "mav0", "cam0", "data", n)).astype(np.float32) - left).mean()
                  for n in names]
        best = int(np.argmin(errors))
        self.assertLess(errors[best], 6.0, errors)
        self.assertLess(errors[best], 0.6 * min(e for i, e in enumerate(errors) if i != best), errors)
        # Its disparity preview, read back through the turbo colour map over the default search range
        # [0, 112) px, against fx * baseline / true depth of that frame.
        calibration = cv2.FileStorage(os.path.join(self.dive, "groundtruth", "calibration.yaml"), cv2.FILE_STORAGE_READ)
        fx_b = calibration.getNode("K1").mat()[0, 0] * abs(calibration.getNode("T").mat()[0, 0])
        depth = cv2.imread(os.path.join(self.dive, "groundtruth", "depth", names[best].replace(".png", ".pfm")),
                           cv2.IMREAD_UNCHANGED)
        lut = cv2.applyColorMap(np.arange(256, dtype=np.uint8).reshape(256, 1), cv2.COLORMAP_TURBO).reshape(256, 3)
        shown = preview.reshape(-1, 3).astype(np.float32)[::4]  # every fourth pixel
        valid = shown.sum(axis=1) > 60  # black: no depth (turbo's darkest colour sums to 125)
        self.assertGreater(valid.mean(), 0.3)
        lut = lut.astype(np.float32)
        distances = (shown[valid] ** 2).sum(axis=1)[:, None] - 2.0 * shown[valid] @ lut.T + (lut ** 2).sum(axis=1)[None, :]
        nearest = np.argmin(distances, axis=1)
        truth = (fx_b / depth.reshape(-1)[::4])[valid]
        known = np.isfinite(truth)
        error_px = np.abs(nearest[known] * 112.0 / 255.0 - truth[known])
        self.assertLess(np.median(error_px), 2.0)
        print(f"camera images: frame {best} (mean error {errors[best]:.2f} grey levels), disparity preview "
              f"{valid.mean():.0%} valid, median error {np.median(error_px):.2f} px")

    def test_bad_client_messages_get_error_statuses_and_no_token_gets_401(self):
        errors = [s["message"] for s in self.report["statuses"] if s["level"] == 2]
        self.assertEqual(errors, ["client message is not valid JSON", "subscribe: channel 4242 is not advertised",
                                  "binary client messages are not supported: this server does not offer "
                                  "clientPublish or services"])
        self.assertEqual(self.report["refusedStatus"], 401)

    def test_the_browser_viewer_shows_the_map(self):
        screenshot = os.path.join(ARTIFACTS, "viewer.png")
        os.makedirs(ARTIFACTS, exist_ok=True)
        result = subprocess.run(["node", os.path.join(WEB, "test", "browser_check.mjs"),
                                 f"http://127.0.0.1:{self.port}/?token={TOKEN}", str(self.occupied), screenshot],
                                cwd=WEB, capture_output=True, text=True, timeout=300)
        self.assertTrue(result.stdout.strip(), result.stderr)
        page = json.loads(result.stdout.strip().splitlines()[-1])
        self.assertEqual(result.returncode, 0, page)
        self.assertTrue(page["connected"])
        self.assertEqual(page["voxels"], self.occupied)
        self.assertEqual(page["coarseBlocks"], 0)
        self.assertGreater(page["framesReceived"], 0)
        self.assertGreater(page["messages"]["/map"], 0)
        self.assertEqual(page["stats"]["occupied"], self.occupied)
        self.assertEqual(page["images"]["camera-image"], {"width": 400, "height": 300})
        self.assertEqual(page["images"]["disparity-image"], {"width": 400, "height": 300})
        self.assertEqual(page["errors"], [])
        # The click in the middle of the fitted view hits a voxel: the panel gives its state and
        # probability (occupied: above 0.5).
        self.assertRegex(page["picked"], r"occupied, p = (0\.(5[1-9]|[6-9]\d)|1\.00)")
        self.assertTrue(os.path.getsize(screenshot) > 1000)
        # W flew the camera forward, no faster than 1 m/s over the time it was held (plus the one
        # frame the page may count after the key is released: at most 0.1 s).
        self.assertGreater(page["flownMetres"], 0.05)
        self.assertLessEqual(page["flownMetres"], 1.0 * (page["flyHeldSeconds"] + 0.1) + 1e-6)
        print(f"browser: {page['voxels']} voxels, {page['framesReceived']} frames, flew {page['flownMetres']:.2f} m; "
              f"screenshot {screenshot}")

    def test_cenote_view_serves_a_saved_map_the_same_way(self):
        saved = self.client.download_snapshot(os.path.join(self.tmp.name, "saved.vdb"))
        view = subprocess.Popen([CENOTE, "view", saved, "--listen", "127.0.0.1:0", "--web-dir", DIST],
                                stdout=subprocess.PIPE, text=True)
        try:
            line = view.stdout.readline()
            match = re.search(r"\((\d+) occupied voxels\) on http://127\.0\.0\.1:(\d+)/", line)
            self.assertIsNotNone(match, line)
            self.assertEqual(int(match.group(1)), self.occupied)
            watcher = subprocess.run(["node", os.path.join(WEB, "test", "protocol_client.mjs"),
                                      f"ws://127.0.0.1:{match.group(2)}/"], cwd=WEB, input=f"occupied {self.occupied}\n",
                                     capture_output=True, text=True, timeout=180)
            report = json.loads(watcher.stdout.strip().splitlines()[-1])
            self.assertEqual(watcher.returncode, 0, report)
            self.assertEqual(report["fullVoxels"], self.occupied)
            self.assertGreater(report["messages"]["/frontiers"], 0)
        finally:
            view.send_signal(signal.SIGTERM)
            self.assertEqual(view.wait(timeout=30), 0)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
