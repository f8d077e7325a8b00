"""test_explore.py: the example exploration planner (clients/python/examples/explore.py) run to the
end on the small scene against a real cenote-server: it must stop by itself because no frontier is
left (or none is reachable, or its scans stopped adding), well before its step limit, with most of the room's free space known
and no move through an obstacle of the true scene; and it must save its plot.

Run: CENOTE_SERVER_BINARY=<build>/server/cenote-server CENOTE_PYTHON_STUBS=<build>/clients/python/gen \
     /usr/bin/python3 tests/clients/python/test_explore.py
"""

import os
import shutil
import sys
import tempfile
import unittest

from client_env import CLIENT_DIR, SERVER_BINARY, TOKEN, require_server

sys.path.insert(0, os.path.join(os.path.abspath(CLIENT_DIR), "examples"))
import explore  # noqa: E402

MAX_STEPS = 40
# Measured: the small scene ends after 6 steps at coverage 0.994 (0.804 after the first scan), the
# same on every run (the map does not depend on thread count; the roadmap's samples are seeded).
MIN_COVERAGE = 0.97


class ExploreTest(unittest.TestCase):
    def test_explores_small_scene_to_the_end(self):
        require_server(self)
        out = tempfile.mkdtemp(prefix="cenote-explore-")
        plot = os.path.join(out, "coverage.png")
        lines = []
        args = explore.parse_args(["--server-binary", SERVER_BINARY, "--token", TOKEN, "--scene", "small",
                                   "--max-steps", str(MAX_STEPS), "--plot", plot])
        result = explore.explore(args, log=lines.append)
        print("\n".join(lines))
        self.assertTrue(result.reason.startswith(("no frontier left", "no reachable", "converged")), result.reason)
        self.assertLess(result.steps, MAX_STEPS)
        self.assertEqual(len(result.coverage), result.steps + 1)
        self.assertGreater(result.coverage[-1], MIN_COVERAGE)
        self.assertGreaterEqual(result.coverage[-1], result.coverage[0])
        self.assertEqual(result.collisions, 0)
        self.assertGreater(os.path.getsize(plot), 1000)
        self.assertTrue(any(line.startswith("step 1:") for line in lines))
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    unittest.main(verbosity=2)
