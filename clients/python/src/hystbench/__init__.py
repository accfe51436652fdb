"""Python client for hystbenchd, the hystbench piezo test bench daemon (standard library only).

    from hystbench import Bench, BenchError, read_run

    with Bench() as bench:                       # $HYSTBENCH_SOCKET or the service's socket
        bench.identify(wait=True)                # the model becomes active
        r = bench.track(compensator="inverse", frequency_hz=1, periods=5, wait=True)
        print(r["end"], r["rms_error_percent"], "% of range")
        log = read_run(r["log"])                 # .header (dict), .columns (name -> floats)

Units: positions in µm, drive in V, times in s, frequencies and rates in Hz.
"""

from .client import DEFAULT_SOCKET, MAX_LINE_BYTES, Bench, default_socket_path
from .errors import BenchConnectionError, BenchError, RunEndedError
from .results import RunResult, SweepResult
from .runlog import RunLog, read_run, read_signal

__version__ = "0.1.0"

__all__ = [
    "Bench",
    "BenchConnectionError",
    "BenchError",
    "DEFAULT_SOCKET",
    "MAX_LINE_BYTES",
    "RunEndedError",
    "RunLog",
    "RunResult",
    "SweepResult",
    "default_socket_path",
    "read_run",
    "read_signal",
    "__version__",
]
