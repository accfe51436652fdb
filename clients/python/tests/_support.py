"""Shared by the tests: the package from this source tree, and a real hystbenchd on the loopback.

The daemon is ``$HYSTBENCHD`` (ctest sets it to the built target), else ``build/bin/hystbenchd``
under the repository root. It runs with ``config/loopback.toml`` (the simulated 150 V / 45 µm
stack the README's demo uses) and its socket, logs and models in a temporary folder. The
identification is shortened through the config, since hystbenchd has no flag for it: no settle
hold and one 2 Hz major loop instead of three 1 Hz ones (about 30 s instead of 45 s; the
excitation's other segments are the daemon's). ``clock="simulated"`` (``hystbenchd --clock``)
runs it on virtual time: runs tick as fast as they compute, for tests whose figures, not timing,
are under test.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path
from typing import Optional

TESTS_DIR = Path(__file__).resolve().parent
CLIENT_DIR = TESTS_DIR.parent
REPO_ROOT = CLIENT_DIR.parent.parent
SRC_DIR = CLIENT_DIR / "src"

# Always test this tree's package, not an installed copy.
if str(SRC_DIR) not in sys.path:
    sys.path.insert(0, str(SRC_DIR))

from hystbench import Bench, BenchConnectionError, BenchError  # noqa: E402

SHORT_IDENTIFY = """
[identify]
settle_s = 0.0
cycles = 1
frequency_hz = 2.0
"""


def hystbenchd_path() -> Path:
    return Path(os.environ.get("HYSTBENCHD") or REPO_ROOT / "build" / "bin" / "hystbenchd")


def loopback_config(extra: str = SHORT_IDENTIFY) -> str:
    """config/loopback.toml with the sections of ``extra`` replacing its own."""
    text = (REPO_ROOT / "config" / "loopback.toml").read_text(encoding="utf-8")
    replaced = set(re.findall(r"^\s*\[([A-Za-z0-9_.]+)\]", extra, flags=re.M))
    out, skipping = [], False
    for line in text.splitlines():
        header = re.match(r"^\s*\[([A-Za-z0-9_.]+)\]", line)
        if header:
            name = header.group(1)
            skipping = any(name == r or name.startswith(r + ".") for r in replaced)
        if not skipping:
            out.append(line)
    return "\n".join(out) + "\n" + extra


class Daemon:
    """hystbenchd as a child process in a temporary folder; ``stop()`` ends it (SIGTERM)."""

    def __init__(
        self, name: str = "hb", config_extra: str = SHORT_IDENTIFY, clock: Optional[str] = None
    ) -> None:
        binary = hystbenchd_path()
        if not binary.is_file():
            raise unittest.SkipTest(
                f"{binary} is not built (cmake --build build --target hystbenchd, or set "
                "HYSTBENCHD)"
            )
        # Short: a Unix socket path holds at most 107 bytes.
        self.dir = Path(tempfile.mkdtemp(prefix=f"{name}-"))
        self.socket = str(self.dir / "s.sock")
        self.log_dir = self.dir / "logs"
        self.model_dir = self.dir / "models"
        self.config = self.dir / "hystbenchd.toml"
        self.config.write_text(loopback_config(config_extra), encoding="utf-8")
        self.output = open(self.dir / "daemon.log", "wb")
        self.process: Optional[subprocess.Popen] = subprocess.Popen(
            [
                str(binary),
                "--config",
                str(self.config),
                "--socket",
                self.socket,
                "--log-dir",
                str(self.log_dir),
                "--model-dir",
                str(self.model_dir),
            ]
            + (["--clock", clock] if clock else []),
            stdout=self.output,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 15.0
        while True:
            if self.process.poll() is not None:
                log = self.daemon_log()
                self.stop()
                raise RuntimeError(f"hystbenchd exited at start:\n{log}")
            try:
                with Bench(self.socket, timeout=2.0):
                    break
            except BenchConnectionError:
                if time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError("hystbenchd did not open its socket within 15 s")
                time.sleep(0.05)

    def bench(self, timeout: float = 30.0) -> Bench:
        return Bench(self.socket, timeout=timeout)

    def daemon_log(self) -> str:
        try:
            return (self.dir / "daemon.log").read_text(encoding="utf-8", errors="replace")
        except OSError:
            return ""

    def stop(self) -> None:
        if self.process is not None:
            if self.process.poll() is None:
                self.process.send_signal(signal.SIGTERM)
                try:
                    self.process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self.process.kill()
                    self.process.wait()
            self.process = None
        self.output.close()
        shutil.rmtree(self.dir, ignore_errors=True)


class DaemonTestCase(unittest.TestCase):
    """Tests against one hystbenchd per class: setUpClass starts `daemon`; each test gets a
    connected `bench`, closed after it; the daemon stops after the class."""

    daemon: Daemon
    bench: Bench

    @classmethod
    def tearDownClass(cls) -> None:
        cls.daemon.stop()

    def setUp(self) -> None:
        self.bench = self.daemon.bench()
        self.addCleanup(self.bench.close)


def supports(bench: Bench, cmd: str) -> bool:
    """Whether the daemon knows ``cmd``: a request with an unknown parameter is refused as
    bad_params by a command the daemon has (and starts nothing), as unknown_command else."""
    try:
        bench.request(cmd, {"probe_unknown_parameter": True})
    except BenchError as e:
        return e.code != "unknown_command"
    return True


def skip_unless_uploads(bench: Bench) -> None:
    """Skips when the daemon has no uploads yet (upload.begin, excite: being implemented)."""
    for cmd in ("upload.begin", "upload.chunk", "upload.cancel"):
        if not supports(bench, cmd):
            raise unittest.SkipTest(
                f"this hystbenchd has no '{cmd}' command yet (uploads are being implemented "
                "in the daemon)"
            )


def skip_unless_excite(bench: Bench) -> None:
    skip_unless_uploads(bench)
    if not supports(bench, "excite"):
        raise unittest.SkipTest(
            "this hystbenchd has no 'excite' command yet (being implemented in the daemon)"
        )
