"""_stubs.py: finds and imports the gRPC stubs generated at build time (cenote/v1/*_pb2.py).

The stubs are not in the source tree: CMake target `cenote_python_stubs` writes them to
<build>/clients/python/gen. The generated modules import each other as `cenote.v1.types_pb2`, so
that folder must be on sys.path; this module prepends it, taken from (first found):
  1. the environment variable CENOTE_PYTHON_STUBS,
  2. a folder given to `use_stubs(path)` before the first client is made,
  3. whatever sys.path already holds (PYTHONPATH=<build>/clients/python/gen).
"""

import importlib
import os
import sys

_MODULES = ("types", "ingest", "query", "updates", "admin")
_loaded = None


class StubsNotFound(ImportError):
    pass


def use_stubs(path):
    """Puts a generated-stubs folder (the one holding cenote/v1/) first on sys.path."""
    path = os.path.abspath(path)
    if not os.path.isfile(os.path.join(path, "cenote", "v1", "query_pb2.py")):
        raise StubsNotFound(f"cenote_client: no generated stubs in {path} (expected cenote/v1/query_pb2.py); "
                            "build target cenote_python_stubs")
    if path not in sys.path:
        sys.path.insert(0, path)


def load():
    """Returns a namespace with the *_pb2 and *_pb2_grpc modules (pb.query, pb.query_grpc, ...)."""
    global _loaded
    if _loaded is not None:
        return _loaded
    env = os.environ.get("CENOTE_PYTHON_STUBS")
    if env:
        use_stubs(env)
    modules = {}
    try:
        for name in _MODULES:
            modules[name] = importlib.import_module(f"cenote.v1.{name}_pb2")
            modules[name + "_grpc"] = importlib.import_module(f"cenote.v1.{name}_pb2_grpc")
    except ImportError as e:
        raise StubsNotFound(
            f"cenote_client: cannot import the generated stubs ({e}). Build them with "
            "`cmake --build <build> --target cenote_python_stubs` and set "
            "CENOTE_PYTHON_STUBS=<build>/clients/python/gen") from e
    _loaded = type("Stubs", (), modules)
    return _loaded
