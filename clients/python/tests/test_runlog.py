"""read_run and read_signal on files written here (the real logs are read in test_daemon.py)."""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import unittest

import _support  # noqa: F401  (puts this tree's package on sys.path)
from hystbench import RunLog, read_run, read_signal

LOG = """\
# {"created":"2026-11-25T18:30:13Z","run_id":"r-1","schema":"hystbench.samples/1"}
# {"run":{"kind":"track","rate_hz":10000.0}}
# {"units":{"t":"s","yr":"um","u":"V","y":"um"}}
# {"columns":["index","t","yr","u","y"]}
index,t,yr,u,y
0,0,NaN,0.03,-8.6
1,1e-04,NaN,0.06,-8.5
2,2e-04,4.4,0.09,4.5
"""


def have_pandas() -> bool:
    try:
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True


class RunLogTest(unittest.TestCase):
    def setUp(self) -> None:
        self.dir = tempfile.mkdtemp(prefix="hbrunlog-")
        self.addCleanup(shutil.rmtree, self.dir, True)

    def write(self, name: str, text: str) -> str:
        path = os.path.join(self.dir, name)
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        return path

    def test_header_objects_merged_and_columns_as_floats(self) -> None:
        log = read_run(self.write("run.csv", LOG))
        self.assertIsInstance(log, RunLog)
        self.assertEqual(len(log.header_objects), 4)
        self.assertEqual(log.header["run_id"], "r-1")
        self.assertEqual(log.header["run"]["kind"], "track")
        self.assertEqual(log.units["y"], "um")
        self.assertEqual(log.names, ["index", "t", "yr", "u", "y"])
        self.assertEqual(log.names, log.header["columns"])
        self.assertEqual(len(log), 3)
        self.assertEqual(log["t"], [0.0, 1e-4, 2e-4])
        self.assertTrue(math.isnan(log["yr"][0]))
        self.assertEqual(log.columns["y"][2], 4.5)
        self.assertIn("track", repr(log))

    def test_some_columns_only(self) -> None:
        log = read_run(self.write("run.csv", LOG), columns=["t", "y"])
        self.assertEqual(log.names, ["t", "y"])
        with self.assertRaisesRegex(ValueError, "no column 'nope'"):
            read_run(self.write("run2.csv", LOG), columns=["nope"])

    def test_errors_name_the_line(self) -> None:
        path = self.write("bad.csv", LOG + "3,3e-04,4.5,oops,4.6\n")
        with self.assertRaisesRegex(ValueError, r"bad\.csv:9: column 'u': 'oops'"):
            read_run(path)
        path = self.write("short.csv", LOG + "3,3e-04\n")
        with self.assertRaisesRegex(ValueError, r"short\.csv:9: 2 fields, the header has 5"):
            read_run(path)

    def test_pandas(self) -> None:
        path = self.write("run.csv", LOG)
        if have_pandas():
            frame = read_run(path, pandas=True)
            self.assertEqual(list(frame.columns), ["index", "t", "yr", "u", "y"])
            self.assertEqual(frame.attrs["header"]["run"]["kind"], "track")
            self.assertEqual(len(read_run(path).to_pandas()), 3)
            some = read_run(path, pandas=True, columns=["t", "y"])
            self.assertEqual(list(some.columns), ["t", "y"])
            self.assertTrue(math.isnan(read_run(path, pandas=True)["yr"][0]))
        else:
            with self.assertRaisesRegex(ImportError, "pandas is not installed"):
                read_run(path, pandas=True)
            with self.assertRaisesRegex(ImportError, r"RunLog\.to_pandas\(\)"):
                read_run(path).to_pandas()

    def test_signals_with_times_by_rate_or_by_position(self) -> None:
        path = self.write("ref.csv", "t,yr\n0,1\n0.5,2\n1.0,3\n")
        self.assertEqual(read_signal(path, "yr"), ([0.0, 0.5, 1.0], [1.0, 2.0, 3.0]))
        self.assertEqual(read_signal(path, "yr", rate_hz=2.0), (None, [1.0, 2.0, 3.0]))
        blank = self.write("ntu.dat", "  0.0   1.5  7\n 0.1 2.5 8\n")
        self.assertEqual(read_signal(blank, "3", "1"), ([0.0, 0.1], [7.0, 8.0]))
        with self.assertRaisesRegex(ValueError, "give rate_hz"):
            read_signal(blank, "3", None)


if __name__ == "__main__":
    unittest.main()
