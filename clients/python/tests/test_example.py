"""The examples (--quick) against their own hystbenchd on the simulated clock."""

from __future__ import annotations

import os
import subprocess
import sys
import unittest

import _support

EXAMPLE = _support.REPO_ROOT / "examples" / "identify_sweep_track.py"
LEARN_EXAMPLE = _support.REPO_ROOT / "examples" / "learn_a_sine.py"


def _run_example(test: unittest.TestCase, name: str, script, *args: str):
    """Runs ``script --quick --socket S args`` against a daemon of its own on the simulated
    clock; returns (its output, the daemon). The run must exit 0."""
    daemon = _support.Daemon(name, clock="simulated")
    test.addCleanup(daemon.stop)
    env = dict(os.environ, PYTHONPATH=str(_support.SRC_DIR))
    env.pop("HYSTBENCH_SOCKET", None)
    run = subprocess.run(
        [sys.executable, str(script), "--quick", "--socket", daemon.socket, *args],
        cwd=str(daemon.dir),
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=240,
    )
    test.assertEqual(run.returncode, 0, run.stdout + daemon.daemon_log()[-3000:])
    return run.stdout, daemon


class ExampleTest(unittest.TestCase):
    def test_identify_sweep_track_quick(self) -> None:
        out, daemon = _run_example(self, "hbpy-ex", EXAMPLE, "--plot-dir", "plots")
        plots = daemon.dir / "plots"
        self.assertRegex(out, r"identified (mpi, \d+ plays|preisach, \d+ cells per side)")
        self.assertIn("      f [Hz]", out)
        self.assertIn("10.000", out)
        self.assertIn("raster: 2 lines", out)
        if "this hystbenchd cannot take uploaded trajectories" not in out:
            self.assertRegex(out, r"inverse: rms \d+\.\d+ um")
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            self.assertIn("matplotlib is not installed", out)
        else:
            self.assertTrue((plots / "sweep.png").is_file(), out)
            self.assertTrue((plots / "raster.png").is_file(), out)

    def test_learn_a_sine_quick(self) -> None:
        out, _ = _run_example(self, "hbpy-learn", LEARN_EXAMPLE)
        self.assertRegex(out, r"identified (mpi|preisach)")
        rows = [line.split() for line in out.splitlines() if line.strip().startswith(("10.0", "50.0"))]
        self.assertEqual(len(rows), 2, out)
        for row in rows:
            first, last = float(row[1]), float(row[-1])
            # f, then trial 0, its repeat and four learned trials
            self.assertEqual(len(row), 7, out)
            self.assertLess(last, 0.5 * first, out)
        self.assertIn("learned drive: ", out)


if __name__ == "__main__":
    unittest.main()
