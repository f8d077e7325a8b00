"""local_server.py: LocalServer starts a cenote-server process on loopback for tests and examples.

It runs `cenote-server --listen 127.0.0.1:0 --port-file F` in a temporary folder (which also holds
the token file and the snapshot directory), waits for the port file, and stops the process with
SIGTERM (SIGKILL after a grace period) when closed. Use it as a context manager:

    with LocalServer("/path/to/cenote-server", token="secret") as server:
        client = MapClient(server.target, token="secret")

Threads: one owner.
"""

import os
import shutil
import signal
import subprocess
import tempfile
import time


class LocalServer:
    def __init__(self, binary, token=None, config=None, extra_args=(), start_timeout_s=60.0, log_path=None):
        if not os.access(binary, os.X_OK):
            raise FileNotFoundError(f"cenote-server binary {binary!r} is not an executable file")
        self.binary = binary
        self.token = token
        self.dir = tempfile.mkdtemp(prefix="cenote-server-")
        self.snapshot_dir = os.path.join(self.dir, "snapshots")
        os.makedirs(self.snapshot_dir)
        port_file = os.path.join(self.dir, "port")
        args = [binary, "--listen", "127.0.0.1:0", "--port-file", port_file, "--snapshot-dir", self.snapshot_dir]
        if config:
            args += ["--config", config]
        if token:
            token_file = os.path.join(self.dir, "token")
            with open(token_file, "w") as f:
                f.write(token + "\n")
            os.chmod(token_file, 0o600)
            args += ["--token-file", token_file]
        args += list(extra_args)
        self.log_path = log_path or os.path.join(self.dir, "server.log")
        self._log = open(self.log_path, "wb")
        self.process = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self.returncode = None
        try:
            self.port = self._wait_for_port(port_file, start_timeout_s)
        except Exception:
            self.close()
            raise
        self.target = f"127.0.0.1:{self.port}"

    def _wait_for_port(self, port_file, timeout_s):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"cenote-server exited with {self.process.returncode} before serving:\n"
                                   + self.log())
            try:
                with open(port_file) as f:
                    text = f.read().strip()
                if text:
                    return int(text)
            except (FileNotFoundError, ValueError):
                pass
            time.sleep(0.05)
        raise TimeoutError(f"cenote-server wrote no port file in {timeout_s} s:\n" + self.log())

    def log(self):
        """What the server printed so far."""
        if not self._log.closed:
            self._log.flush()
        with open(self.log_path, "rb") as f:
            return f.read().decode(errors="replace")

    def close(self, grace_s=20.0):
        """SIGTERM (the server drains, snapshots and exits 0), SIGKILL after grace_s; returns the exit code."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=grace_s)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.returncode = self.process.returncode
        self._log.close()
        return self.returncode

    def remove(self):
        """Deletes the temporary folder (after close())."""
        shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        self.remove()
