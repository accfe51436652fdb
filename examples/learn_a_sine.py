#!/usr/bin/env python3
"""Learn a repeated sine: the error per trial falls to near the sensor's noise.

With the Python client (clients/python): identify the actuator when no model is active, then
``track(..., learn=N)`` at each frequency. A trial is one period; the first plays the model's
inverse, each next one the drive before it corrected by its measured error. Prints each
trial's rms error in % of range and where the daemon saved the learned drive (``t,u``, one
period; ``hystbench excite --input-file`` replays it open loop).

    hystbenchd --config config/loopback.toml --socket /tmp/hb.sock --log-dir /tmp/hb/logs \\
               --model-dir /tmp/hb/models &
    PYTHONPATH=clients/python/src python3 examples/learn_a_sine.py --socket /tmp/hb.sock

``--quick``: two frequencies, four trials each (a smoke test).
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Optional, Sequence

try:
    import hystbench  # noqa: F401
except ImportError:  # run from a checkout without installing the package
    sys.path.insert(
        0,
        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "clients", "python", "src"),
    )

from hystbench import Bench, BenchError


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--socket", help="hystbenchd socket (default $HYSTBENCH_SOCKET)")
    parser.add_argument("--trials", type=int, default=10, help="learned trials per frequency")
    parser.add_argument(
        "--frequencies", default="1,10,50,200", help="comma-separated sine frequencies [Hz]"
    )
    parser.add_argument("--quick", action="store_true", help="10 and 50 Hz, 4 trials")
    args = parser.parse_args(argv)
    frequencies = [10.0, 50.0] if args.quick else [float(f) for f in args.frequencies.split(",")]
    trials = 4 if args.quick else args.trials

    with Bench(args.socket) as bench:
        try:
            bench.model_get()
        except BenchError:  # no_model: identify first
            identified = bench.identify(wait=True, timeout=600)
            if not identified.completed:
                print(f"identify did not complete: {identified.end} {identified.get('reason')}")
                return 1
            print(f"identified {identified['model']['type']}")
        print(f"{'f [Hz]':>8}  rms % of range per trial (the first: the inverse's own drive)")
        for f in frequencies:
            result = bench.track("sine", frequency_hz=f, learn=trials, wait=True, timeout=600)
            if not result.completed:
                print(f"{f:8.1f}  did not complete: {result.end} {result.get('reason', '')}")
                return 1
            learning = result["learning"]
            rms = " ".join(f"{t['rms_error_percent']:.3f}" for t in learning["trials"])
            print(f"{learning['frequency_hz']:8.1f}  {rms}")
            if learning["stopped"]:
                print(f"          {learning['why']}")
            print(f"          learned drive: {learning.get('drive_file', '-')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
