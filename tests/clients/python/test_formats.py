"""test_formats.py: the Python client's copy of the extension table (cenote_client/client.py) gives
what the C++ table (mapping/io/map_file_format.h) gives, case by case from the file both tests read,
tests/mapping/io/map_file_format_cases.txt; a refusal is CenoteError INVALID_ARGUMENT, as the server's.
No server needed.

Run: /usr/bin/python3 tests/clients/python/test_formats.py
"""

import os
import unittest

from client_env import HERE

from cenote_client import CenoteError
from cenote_client.client import SNAPSHOT_FORMATS, _snapshot_format

CASES = os.path.join(HERE, "..", "..", "mapping", "io", "map_file_format_cases.txt")


class FormatTableTest(unittest.TestCase):
    def test_every_case_of_the_shared_table(self):
        names = {v: k.replace("_", "-") for k, v in SNAPSHOT_FORMATS.items()}
        cases = 0
        with open(CASES) as f:
            for line in f:
                if not line.strip() or line.startswith("#"):
                    continue
                path, requested, expected = line.split()
                fmt = None if requested == "-" else requested
                cases += 1
                with self.subTest(path=path, requested=requested):
                    if expected == "error":
                        with self.assertRaises(CenoteError) as ctx:
                            _snapshot_format(fmt, path)
                        self.assertEqual(ctx.exception.code, "INVALID_ARGUMENT")
                    else:
                        self.assertEqual(names[_snapshot_format(fmt, path)], expected)
        self.assertEqual(cases, 33)

    def test_refusal_texts_are_the_cpp_ones(self):
        with self.assertRaises(CenoteError) as ctx:
            _snapshot_format("points_ply", "map.vdb")
        self.assertEqual(ctx.exception.message,
                         "map.vdb: the extension .vdb means format vdb, not points-ply (the format follows the extension: "
                         ".vdb vdb, .bt bt, .ot ot, .mesh.ply mesh-ply, .points.ply points-ply, .pcd points-pcd, "
                         ".ply mesh-ply or points-ply as given)")
        with self.assertRaises(CenoteError) as ctx:
            _snapshot_format(None, "mesh.ply")
        self.assertEqual(ctx.exception.message,
                         "mesh.ply: a .ply file holds a mesh or points: name it .mesh.ply or .points.ply, or give the "
                         "format mesh-ply or points-ply")
        with self.assertRaises(ValueError):
            _snapshot_format("ply", "m.ply")


if __name__ == "__main__":
    unittest.main(verbosity=2)
