#!/usr/bin/env python3
"""Identify the actuator, sweep the tracking error against frequency, then track a raster line.

What a user of the bench does first, with the Python client (clients/python):

1. ``identify``: the daemon excites the actuator, fits a hysteresis model, verifies it and
   makes it active (about 45 s with the default configuration);
2. ``sweep``: a sine at 1, 5 and 10 Hz, without compensation (``none``) and through the
   model's inverse (``inverse``): rms / max error in % of the range;
3. ``track`` a trajectory made here: the fast axis of a raster scan (constant-speed lines
   with smooth turnarounds), uploaded to the daemon, with each compensator;
4. plots (``--plot-dir``) when matplotlib is installed, else tables only.

    hystbenchd --config config/loopback.toml --socket /tmp/hb.sock --log-dir /tmp/hb/logs \\
               --model-dir /tmp/hb/models &
    PYTHONPATH=clients/python/src python3 examples/identify_sweep_track.py --socket /tmp/hb.sock

``--quick`` makes every step short (two frequencies, two raster lines): a smoke test.
The script reads the run logs, so run it where the daemon's log folder is visible.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Dict, List, Optional, Sequence, Tuple

try:
    import hystbench
except ImportError:  # run from a checkout without installing the package
    sys.path.insert(
        0,
        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "clients", "python", "src"),
    )
    import hystbench

from hystbench import Bench, BenchError, read_run


def raster_line(
    lo_um: float,
    hi_um: float,
    rate_hz: float,
    line_s: float,
    turn_s: float,
    lines: int,
) -> List[float]:
    """The fast axis of a raster scan [µm], sampled at ``rate_hz`` [Hz].

    Starts at rest at ``lo_um``, accelerates for ``turn_s / 2``, then ``lines`` constant-speed
    lines of ``line_s`` [s] each, alternately up and down, joined by turnarounds of ``turn_s``
    [s] at constant acceleration (the speed reverses smoothly, the position stays within
    [lo_um, hi_um]); ends at rest.
    """
    # Speed v: a turnaround covers v * turn_s / 4 beyond each line's end, a line v * line_s.
    v = (hi_um - lo_um) / (line_s + turn_s / 2.0)  # [µm/s]
    # Velocity segments: (duration [s], start velocity, end velocity).
    segments: List[Tuple[float, float, float]] = [(turn_s / 2.0, 0.0, v)]
    direction = 1.0
    for k in range(lines):
        segments.append((line_s, direction * v, direction * v))
        if k < lines - 1:
            segments.append((turn_s, direction * v, -direction * v))
        direction = -direction
    segments.append((turn_s / 2.0, -direction * v, 0.0))
    dt = 1.0 / rate_hz
    out = [lo_um]
    y = lo_um
    for duration, v0, v1 in segments:
        n = int(round(duration * rate_hz))
        for i in range(n):
            # Exact integral of a linear velocity over one sample.
            t0, t1 = i * dt, (i + 1) * dt
            slope = (v1 - v0) / duration
            y += v0 * (t1 - t0) + 0.5 * slope * (t1 * t1 - t0 * t0)
            out.append(min(max(y, lo_um), hi_um))
    return out


def bar(fraction: float, label: str) -> None:
    """A one-line progress bar on stderr."""
    width = 30
    filled = int(round(min(max(fraction, 0.0), 1.0) * width))
    sys.stderr.write(
        f"\r[{'#' * filled}{'.' * (width - filled)}] {100 * fraction:3.0f} % {label}\x1b[K"
    )
    sys.stderr.flush()


def end_bar() -> None:
    """Clears the progress bar's line."""
    if sys.stderr.isatty():
        sys.stderr.write("\r\x1b[K")
        sys.stderr.flush()


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--socket", help="hystbenchd socket (default $HYSTBENCH_SOCKET)")
    parser.add_argument(
        "--model", default=None, help="pi, mpi, cpi, rpi or auto (default: the daemon's)"
    )
    parser.add_argument("--quick", action="store_true", help="short runs: a smoke test")
    parser.add_argument(
        "--plot-dir",
        default="identify_sweep_track-plots",
        help="where the PNGs go (with matplotlib)",
    )
    parser.add_argument("--no-plot", action="store_true", help="tables only")
    args = parser.parse_args(argv)
    show = bar if sys.stderr.isatty() else None

    frequencies = [5.0, 10.0] if args.quick else [1.0, 5.0, 10.0]
    compensators = ["none", "inverse"]
    raster_compensators = ["none", "inverse"] if args.quick else ["none", "inverse", "inverse+pid"]

    with Bench(args.socket) as bench:
        print(f"hystbenchd {bench.version} on {bench.socket_path}")
        rate_hz = float(bench.config_get()["loop"]["rate_hz"])

        # 1. The model.
        identified = bench.identify(model=args.model, wait=True, progress=show, timeout=600)
        end_bar()
        if not identified.completed:
            print(
                f"identify did not complete: {identified.end} {identified.get('reason', '')} "
                f"{identified.get('fit_error', '')}"
            )
            return 1
        model = identified["model"]
        verified = identified.get("verification") or {}
        # The plane's operators are its cells per side.
        operators = "cells per side" if model["type"] == "preisach" else "plays"
        print(
            f"identified {model['type']}, {model['operators']} {operators}, "
            f"held-out rms {model['heldout']['rmse']:.4f} um "
            f"({model['heldout']['rmse_percent']:.3f} % of range); "
            f"verified tracking max {verified.get('max_error_percent', float('nan')):.3f} %"
        )

        # 2. The sweep: error against frequency.
        sweep = bench.sweep(
            frequencies,
            compensators,
            periods=2 if args.quick else 5,
            min_duration_s=0.0 if args.quick else 1.0,
            precondition_s=0.2 if args.quick else None,
            progress=show,
        )
        end_bar()
        print("\nsweep: sine over 80 % of the range")
        print(sweep.table())
        if not sweep.completed:
            print("the sweep stopped: a run did not complete")
            return 1

        # 3. A user trajectory: a raster line over the sweep's span (80 % of the range).
        lo, hi = sweep[0]["min_um"], sweep[0]["max_um"]
        line_s, turn_s, lines = (0.1, 0.04, 2) if args.quick else (0.5, 0.1, 6)
        reference = raster_line(lo, hi, rate_hz, line_s, turn_s, lines)
        print(
            f"\nraster: {lines} lines of {line_s} s over [{lo:.2f}, {hi:.2f}] um, "
            f"{turn_s} s turnarounds, {len(reference)} samples at {rate_hz:g} Hz"
        )
        raster: Dict[str, Any] = {}
        for compensator in raster_compensators:
            try:
                result = bench.track(
                    reference,
                    rate_hz=rate_hz,
                    compensator=compensator,
                    precondition_s=0.2 if args.quick else None,
                    wait=True,
                    progress=show,
                )
            except BenchError as e:
                end_bar()
                if e.code == "unknown_command":
                    print(f"this hystbenchd cannot take uploaded trajectories ({e})")
                    break
                raise
            end_bar()
            raster[compensator] = result
            if not result.completed:
                print(f"  {compensator:>12}: {result.end} ({result.get('reason', '')})")
                continue
            print(
                f"  {compensator:>12}: rms {result['rms_error_um']:.4f} um "
                f"({result['rms_error_percent']:.3f} %), max {result['max_error_um']:.4f} um "
                f"({result['max_error_percent']:.3f} %)"
            )

    if args.no_plot:
        return 0
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(
            "\nmatplotlib is not installed: tables only (pip install matplotlib, or apt "
            "install python3-matplotlib, for the plots)"
        )
        return 0
    os.makedirs(args.plot_dir, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, compensator in enumerate(compensators):
        rows = [sweep.row(f, compensator) for f in frequencies]
        ax.loglog(
            frequencies,
            [r["rms_error_percent"] for r in rows],
            "o-",
            color=f"C{i}",
            label=f"{compensator} rms",
        )
        ax.loglog(
            frequencies,
            [r["max_error_percent"] for r in rows],
            "s--",
            color=f"C{i}",
            label=f"{compensator} max",
        )
    ax.set_xlabel("reference frequency [Hz]")
    ax.set_ylabel("tracking error [% of range]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.plot_dir, "sweep.png"), dpi=120)
    if raster:
        fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
        for i, (compensator, result) in enumerate(raster.items()):
            log = read_run(result["log"], columns=["t", "yr", "y", "flags"])
            open_loop = int(log.header["flags"]["open_loop"])  # rows that follow no reference
            keep = [k for k, f in enumerate(log["flags"]) if not int(f) & open_loop]
            t = [log["t"][k] for k in keep]
            if i == 0:
                top.plot(t, [log["yr"][k] for k in keep], "k-", lw=1, label="reference")
            top.plot(t, [log["y"][k] for k in keep], color=f"C{i}", lw=1, label=compensator)
            bottom.plot(
                t,
                [log["y"][k] - log["yr"][k] for k in keep],
                color=f"C{i}",
                lw=1,
                label=compensator,
            )
        top.set_ylabel("position [µm]")
        bottom.set_ylabel("y - yr [µm]")
        bottom.set_xlabel("t [s]")
        top.legend()
        bottom.grid(True, alpha=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(args.plot_dir, "raster.png"), dpi=120)
    print(
        f"\nplots: {os.path.join(args.plot_dir, 'sweep.png')}"
        + (f", {os.path.join(args.plot_dir, 'raster.png')}" if raster else "")
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
