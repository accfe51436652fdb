"""A finished run's result (``RunResult``) and a sweep's rows (``SweepResult``), as ``Bench``
returns them."""

from __future__ import annotations

from typing import Any, Dict, Iterable, List, Optional, Sequence

from .errors import RunEndedError


class RunResult(dict):
    """A finished run's result, as the daemon's ``run.finished`` event carries it (a dict).

    Always check how the run ended: ``result["end"]`` is ``"completed"``, ``"stopped"``,
    ``"aborted"`` or ``"fault"`` (``result["reason"]`` says why); an identification whose fit
    failed completed its run but has ``"fit_error"``. ``completed`` is True only for a completed
    run without a fit error; ``check()`` raises ``RunEndedError`` otherwise. Common keys:
    ``run_id``, ``kind``, ``samples``, ``log`` (the run log's path on the daemon's machine),
    ``rms_error_um`` / ``max_error_um`` / ``*_percent`` (tracking error; % of ``range_um``),
    ``model`` and ``verification`` (identify), ``loop`` (timing) and ``clock``.
    """

    @property
    def clock(self) -> str:
        """The loop's clock the run was timed by: ``wall``, or ``simulated`` (virtual time: no
        wake latency, no overruns, every sample logged; ``[loop] clock`` in the daemon's config)."""
        return str(self.get("clock", "wall"))

    @property
    def end(self) -> str:
        """How the run ended: ``completed``, ``stopped``, ``aborted`` or ``fault``."""
        return str(self.get("end", ""))

    @property
    def completed(self) -> bool:
        """True when the run completed (and, for identify, its fit succeeded)."""
        return self.get("end") == "completed" and "fit_error" not in self

    def check(self) -> "RunResult":
        """Returns the result when ``completed``, else raises ``RunEndedError``."""
        if self.completed:
            return self
        if self.get("end") == "completed":
            raise RunEndedError("fit_error", f"the fit failed: {self.get('fit_error')}", self)
        reason = self.get("reason") or "no reason given"
        raise RunEndedError(
            self.end or "unknown", f"run {self.get('run_id')} {self.end}: {reason}", self
        )


class SweepResult(list):
    """The rows of a ``Bench.sweep()``: one dict per run, in the order they ran.

    Each row has ``frequency_hz``, ``compensator``, ``periods`` and, from the run's result,
    ``run_id``, ``end``, ``reason``, ``rms_error_percent``, ``max_error_percent`` (% of the
    reference's range ``range_um``), ``rms_error_um``, ``max_error_um``,
    ``model_rms_error_percent``, ``log``, and ``min_um`` / ``max_um`` (the reference's span).
    The sweep stops at the first run that does not complete, as ``hystbench sweep`` does:
    ``completed`` tells whether every planned run completed.
    """

    def __init__(
        self,
        rows: Iterable[Dict[str, Any]],
        frequencies: Sequence[float],
        compensators: Sequence[str],
    ) -> None:
        super().__init__(rows)
        self.frequencies: List[float] = [float(f) for f in frequencies]
        self.compensators: List[str] = list(compensators)

    @property
    def completed(self) -> bool:
        """True when every planned run (frequency x compensator) completed."""
        planned = len(self.frequencies) * len(self.compensators)
        return len(self) == planned and all(r.get("end") == "completed" for r in self)

    def row(self, frequency_hz: float, compensator: str) -> Optional[Dict[str, Any]]:
        """The row of one frequency [Hz] and compensator, or None."""
        for r in self:
            if r["frequency_hz"] == float(frequency_hz) and r["compensator"] == compensator:
                return r
        return None

    def table(self) -> str:
        """The rows as ``hystbench sweep`` prints them: rms / max error, % of range."""
        lines = ["tracking error rms / max, % of range"]
        lines.append(f"{'f [Hz]':>12}" + "".join(f"{c:>24}" for c in self.compensators))
        for f in self.frequencies:
            cells = []
            for c in self.compensators:
                r = self.row(f, c)
                if r is None:
                    cell = "-"
                elif "rms_error_percent" in r and "max_error_percent" in r:
                    cell = f"{r['rms_error_percent']:.3f} / {r['max_error_percent']:.3f}"
                else:
                    cell = str(r.get("end", "?"))
                cells.append(f"{cell:>24}")
            lines.append(f"{f:>12.3f}" + "".join(cells))
        return "\n".join(lines)
