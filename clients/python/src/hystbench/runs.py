"""The runs of ``Bench``: ``identify``, ``track``, ``excite`` and ``sweep``, and ``wait``, which
follows a run's events until it ends."""

from __future__ import annotations

import math
import os
import time
from typing import Any, Dict, Iterable, List, Optional, Tuple, Union

from ._shared import PathLike, Progress, _without_none
from .commands import _Commands
from .errors import BenchError
from .results import RunResult, SweepResult
from .runlog import _read_signal_lines


class _Runs(_Commands):
    """``Bench``'s runs (client.py gives the connection and uploads they go through)."""

    def _upload_signal(
        self,
        kind: str,
        values: Optional[Iterable[float]],
        rate_hz: Optional[float],
        t: Optional[Iterable[float]],
        path: Optional[PathLike],
        columns: Tuple[Optional[str], str],
        progress: Optional[Progress],
    ) -> Tuple[str, Optional[Tuple[str, List[int]]]]:
        """Uploads the samples or the file's; returns (upload id, (file, line of each sample))."""
        source = None
        if path is not None:
            if values is not None or t is not None:
                raise ValueError("give the samples or a file, not both")
            t_column, value_column = columns
            t, values, lines = _read_signal_lines(path, value_column, t_column, rate_hz)
            source = (os.fspath(path), lines)
        if values is None:
            raise ValueError("no samples")
        try:
            upload_id = self.upload(
                kind,
                values,
                rate_hz=rate_hz,
                t=t,
                progress=progress,
                source=os.path.basename(source[0]) if source is not None else None,
            )
        except BenchError as e:
            _name_the_line(e, source)
            raise
        return upload_id, source

    # ---- runs ---------------------------------------------------------------------------------

    def _start(
        self,
        cmd: str,
        params: Dict[str, Any],
        wait: bool,
        progress: Optional[Progress],
        timeout: Optional[float],
        upload_id: Optional[str] = None,
        source: Optional[Tuple[str, List[int]]] = None,
    ) -> Dict[str, Any]:
        try:
            started = self.request(cmd, params)
        except BenchError as e:
            # The daemon keeps a refused run's upload for a retry; this client uploads again on
            # the next call, so it frees it (at most 16 may be open on the daemon).
            if upload_id is not None:
                self._cancel_quietly(upload_id)
            _name_the_line(e, source)
            raise
        self._own_runs.append(started["run_id"])
        if not wait:
            return started
        return self.wait(started["run_id"], progress=progress, timeout=timeout)

    def wait(
        self, run_id: str, *, progress: Optional[Progress] = None, timeout: Optional[float] = None
    ) -> RunResult:
        """Follows a run's events until its ``run.finished``; returns its ``RunResult``.

        Works for a run started on another connection too (a run that already ended returns
        the daemon's ``last_result`` when it is that run).

        Args:
            run_id: the ``run_id`` of a start reply.
            progress: called with (fraction, label) for each ``run.progress`` (label: the
                stage, e.g. ``"verify mpi"``, or the run's kind) and ``fit.progress`` (label
                ``"fitting: <stage>"``; its fraction restarts at 0).
            timeout: give up after this long [s] (TimeoutError; the run goes on); None waits.

        Returns:
            The result; check ``result["end"]`` (or ``result.completed`` / ``result.check()``):
            a stopped, aborted or faulted run is returned, not raised.
        """
        deadline = None if timeout is None else time.monotonic() + timeout
        found = self._scan_buffered(run_id, progress)
        if found is not None:
            return found
        if run_id in self._finished:
            return self._finished[run_id]
        if run_id not in self._own_runs:
            # Started elsewhere: its run.finished reaches this connection only if it has not
            # gone out yet.
            st = self.status()
            found = self._scan_buffered(run_id, progress)
            if found is not None:
                return found
            active = st.get("run") or {}
            last = st.get("last_result") or {}
            if active.get("run_id") != run_id:
                if last.get("run_id") == run_id:
                    return RunResult(last)
                raise BenchError(
                    "no_run", f"run {run_id} is neither active nor the last one", command="wait"
                )
        while True:
            msg = self._read_message(deadline)
            if msg is None:
                raise TimeoutError(
                    f"{self.socket_path}: run {run_id} did not finish within {timeout:g} s "
                    "(it goes on; stop() or abort() ends it)"
                )
            if "event" not in msg or "id" in msg:
                continue
            done = self._handle_event(msg, run_id, progress)
            if done is not None:
                return done

    def _scan_buffered(self, run_id: str, progress: Optional[Progress]) -> Optional[RunResult]:
        while self._events:
            done = self._handle_event(self._events.popleft(), run_id, progress)
            if done is not None:
                return done
        return None

    def _handle_event(
        self, event: Dict[str, Any], run_id: str, progress: Optional[Progress]
    ) -> Optional[RunResult]:
        name = event.get("event")
        if name == "run.finished":
            result = RunResult(event.get("result") or {})
            finished = str(result.get("run_id"))
            # Kept for a later wait() on the same run (the event comes once).
            self._finished[finished] = result
            while len(self._finished) > 64:
                self._finished.popitem(last=False)
            return result if finished == run_id else None
        if progress is None or event.get("run_id") != run_id:
            return None
        fraction = float(event.get("fraction") or 0.0)
        if name == "run.progress":
            progress(fraction, str(event.get("stage") or event.get("kind") or "run"))
        elif name == "fit.progress":
            progress(fraction, "fitting: " + str(event.get("stage") or ""))
        return None

    def identify(
        self,
        *,
        wait: bool = False,
        progress: Optional[Progress] = None,
        timeout: Optional[float] = None,
        **params: Any,
    ) -> Dict[str, Any]:
        """Identifies a model: precondition, excitation (about 30-40 s), fit, verification;
        the model becomes active.

        Args:
            **params: sent as given (None values left out): ``model`` (``"pi"``, ``"mpi"``,
                ``"cpi"``, ``"rpi"``, ``"auto"``), ``operators`` (plays; 0 = by held-out
                error), ``dead_zones`` (per side; -1 = by held-out error), ``u_min`` / ``u_max``
                (excitation range [V]).
            wait: follow the run until it ends and return its ``RunResult`` (``model``,
                ``verification``, ``candidates``, ...); else return the start reply
                (``run_id``, ``samples``, ``duration_s`` [s], ``log``).
            progress: see ``wait()``. timeout: see ``wait()``.
        """
        return self._start("identify", _without_none(params), wait, progress, timeout)

    def track(
        self,
        reference: Union[str, Iterable[float], None] = None,
        *,
        rate_hz: Optional[float] = None,
        t: Optional[Iterable[float]] = None,
        reference_file: Optional[PathLike] = None,
        columns: Tuple[Optional[str], str] = ("t", "yr"),
        compensator: Optional[str] = None,
        frequency_hz: Optional[float] = None,
        periods: Optional[float] = None,
        duration_s: Optional[float] = None,
        range_fraction: Optional[float] = None,
        min_um: Optional[float] = None,
        max_um: Optional[float] = None,
        precondition_s: Optional[float] = None,
        approach_s: Optional[float] = None,
        learn: Optional[int] = None,
        learn_gain: Optional[float] = None,
        learned: Optional[str] = None,
        wait: bool = False,
        progress: Optional[Progress] = None,
        timeout: Optional[float] = None,
        **params: Any,
    ) -> Dict[str, Any]:
        """Follows a reference with a compensator and reports the tracking error.

        The reference is either one of the daemon's waveforms or your own trajectory:

        * ``reference="triangle"`` (``sine``, ``sawtooth``, ``decaying_sine``,
          ``multi_frequency``, ``chirp``; default triangle) with ``frequency_hz`` [Hz],
          ``periods`` or ``duration_s`` [s], and ``range_fraction`` (centred share of the
          actuator range) or ``min_um`` / ``max_um`` [µm];
        * ``reference=[...]``: positions [µm] sampled uniformly at ``rate_hz`` [Hz], or at the
          times ``t`` [s]; or ``reference_file="ref.csv"`` with the columns ``columns``
          (time [s], position [µm]; default ``("t", "yr")``; time column None with
          ``rate_hz``). The samples are uploaded in chunks, then the run starts (the daemon
          resamples them to its loop rate). It refuses a trajectory beyond the actuator range
          (``out_of_range``) or faster than the slew limit (``slew_limit``); the error's
          ``details["sample"]`` is the first offending sample (0-based), and for a file
          ``details["file"]`` / ``details["line"]`` name its line.

        Args:
            compensator: ``none``, ``inverse``, ``inverse_multiplicative``, ``inverse+pid``,
                ``pid`` (default: inverse with a model, none without).
            precondition_s: open-loop sweep u_max -> u_min first [s] (daemon default 1 s).
            approach_s: uploaded reference only: the unscored approach from where the
                precondition left the output to the first sample [s] (daemon default 0.2 s,
                longer when the slew limit needs it); the error is scored over the whole
                trajectory after it.
            learn: learn over this many trials (a sine, triangle or sawtooth: a trial is one
                period, instead of ``periods`` / ``duration_s``; an uploaded trajectory: a
                trial is one pass, its approach from the trajectory's end then the trajectory,
                scored on the trajectory): after a start-up period and one with the
                compensator's drive, each plays the one before's drive corrected by its error. The result's ``learning["trials"]`` lists each trial's
                rms and max error [% of range]; ``rms_error_percent`` is the last trial's; the
                learned drive is saved in the daemon's model folder (``learning["drive_file"]``).
            learn_gain: the share of the error corrected per trial (daemon default 0.5).
            learned: start from a drive learned before (``learning["drive"]`` of its run; also
                after a restart of the daemon): after the start-up period it plays instead of
                the compensator's drive, for one scored period, or as the first trial with
                ``learn``. Only for the waveform, range and loop rate it was learned for, or
                the same uploaded trajectory (``bad_params`` names both otherwise). On a stage,
                the learning run's id (``learned_drive`` of its result) starts every axis from
                its own drive.
            **params: further request parameters, sent as given (``kp``, ``ki``, ``kd``,
                ``learn_cutoff_hz``; ``lead_in_max_s``: with ``learned``, the longest lead-in
                [s] while the actuator's offset moves toward the one the drive was learned at,
                daemon default 60, 0 the shortest).
            wait, progress, timeout: as for ``identify``; ``progress`` also sees the upload
                (label ``"upload"``).
        """
        if reference is not None and reference_file is not None:
            raise ValueError("track: give reference or reference_file, not both")
        upload_id: Optional[str] = None
        source = None
        request = _without_none(
            {
                "compensator": compensator,
                "precondition_s": precondition_s,
                "learn_trials": learn,
                "learn_gain": learn_gain,
                "learned": learned,
                **params,
            }
        )
        waveform = dict(
            frequency_hz=frequency_hz,
            periods=periods,
            duration_s=duration_s,
            range_fraction=range_fraction,
            min_um=min_um,
            max_um=max_um,
        )
        if isinstance(reference, str) or (reference is None and reference_file is None):
            if rate_hz is not None or t is not None or approach_s is not None:
                raise ValueError(
                    "track: rate_hz, t and approach_s go with a reference given as samples"
                )
            if reference is not None:
                request["reference"] = reference
            request.update(_without_none(waveform))
        else:
            given = sorted(k for k, v in waveform.items() if v is not None)
            if given:
                raise ValueError(
                    f"track: {', '.join(given)} describe a waveform, not an uploaded reference"
                )
            if approach_s is not None:
                request["approach_s"] = approach_s
            upload_id, source = self._upload_signal(
                "reference", reference, rate_hz, t, reference_file, columns, progress
            )
            request["reference_upload"] = upload_id
        return self._start("track", request, wait, progress, timeout, upload_id, source)

    def excite(
        self,
        drive: Optional[Iterable[float]] = None,
        *,
        rate_hz: Optional[float] = None,
        t: Optional[Iterable[float]] = None,
        input_file: Optional[PathLike] = None,
        columns: Tuple[Optional[str], str] = ("t", "u"),
        wait: bool = False,
        progress: Optional[Progress] = None,
        timeout: Optional[float] = None,
        **params: Any,
    ) -> Dict[str, Any]:
        """Plays an open-loop drive and records the response (a record ``hystbench fit`` reads).

        Args:
            drive: the output [V] sampled uniformly at ``rate_hz`` [Hz], or at the times ``t``
                [s]; or ``input_file="drive.csv"`` with the columns ``columns`` (time [s],
                drive [V]; default ``("t", "u")``). Uploaded in chunks, then the run starts: the
                daemon ramps the output from where it is to the first sample, then plays the
                drive resampled to its loop rate. It refuses a drive beyond [u_min, u_max]
                (``out_of_range``) or faster than the slew limit (``slew_limit``), with
                ``details`` as for ``track``.
            **params: further request parameters, sent as given.
            wait, progress, timeout: as for ``identify``; ``progress`` also sees the upload
                (label ``"upload"``).

        Returns:
            The start reply (``run_id``, ``log``, ``duration_s``, ``ramp_samples``, ...) or,
            with ``wait=True``, the ``RunResult``; its ``log`` is the record (t, u, y).
        """
        request = _without_none(params)
        upload_id, source = self._upload_signal(
            "drive", drive, rate_hz, t, input_file, columns, progress
        )
        request["drive_upload"] = upload_id
        return self._start("excite", request, wait, progress, timeout, upload_id, source)

    def sweep(
        self,
        frequencies: Iterable[float],
        compensators: Iterable[str] = ("none", "inverse"),
        *,
        reference: str = "sine",
        periods: float = 5.0,
        min_duration_s: float = 1.0,
        range_fraction: float = 0.8,
        precondition_s: Optional[float] = None,
        learn: Optional[int] = None,
        progress: Optional[Progress] = None,
        timeout: Optional[float] = None,
    ) -> SweepResult:
        """Tracks a waveform at each frequency with each compensator, one ``track`` run each.

        As ``hystbench sweep``: for each compensator, for each frequency f [Hz], a run of
        max(``periods``, ceil(``min_duration_s`` * f)) periods (the first is not scored) over
        ``range_fraction`` of the actuator range; ``precondition_s`` [s] is passed to every run
        when given.

        Args:
            learn: add a column ``"learned"``: at each frequency a ``track(learn=N)`` run
                from the daemon's default compensator; its row has the last trial's error and
                ``learning`` (``trials_rms_percent``, ``drive``).
            progress: called with (fraction of the whole sweep, label such as
                ``"inverse 5 Hz (2/4)"``).
            timeout: for each run [s]; None waits.

        Returns:
            A ``SweepResult`` (a list of row dicts; ``.table()``, ``.completed``). The sweep
            stops at the first run that does not complete (its row is the last). A refused run
            raises ``BenchError``; its ``rows`` attribute then holds the rows so far.
        """
        freqs = [float(f) for f in frequencies]
        comps = list(compensators) + (["learned"] if learn else [])
        rows = SweepResult([], freqs, comps)
        total = len(freqs) * len(comps)
        done = 0
        for comp in comps:
            for f in freqs:
                learned = comp == "learned"
                n = None if learned else max(float(periods), float(math.ceil(min_duration_s * f)))
                params = _without_none(
                    {
                        "reference": reference,
                        "frequency_hz": f,
                        "periods": n,
                        "compensator": None if learned else comp,
                        "learn_trials": learn if learned else None,
                        "range_fraction": range_fraction,
                        "precondition_s": precondition_s,
                    }
                )
                label = f"{comp} {f:g} Hz ({done + 1}/{total})"
                try:
                    started = self.request("track", params)
                except BenchError as e:
                    e.rows = rows  # type: ignore[attr-defined]
                    raise
                self._own_runs.append(started["run_id"])
                run_progress = None
                if progress is not None:
                    run_progress = _scaled(progress, done / total, 1.0 / total, label)
                result = self.wait(started["run_id"], progress=run_progress, timeout=timeout)
                done += 1
                row: Dict[str, Any] = {"frequency_hz": f, "compensator": comp}
                row.update(_without_none({"periods": n, "learn_trials": learn if learned else None}))
                learning = result.get("learning")
                if isinstance(learning, dict):
                    row["learning"] = {
                        "frequency_hz": learning.get("frequency_hz"),
                        "trials_rms_percent": [
                            t["rms_error_percent"] for t in learning.get("trials", [])
                        ],
                        "stopped": learning.get("stopped"),
                        "drive": learning.get("drive"),
                    }
                for key in (
                    "run_id",
                    "end",
                    "reason",
                    "rms_error_percent",
                    "max_error_percent",
                    "rms_error_um",
                    "max_error_um",
                    "range_um",
                    "model_rms_error_percent",
                    "log",
                ):
                    if key in result:
                        row[key] = result[key]
                ref = started.get("reference") or {}
                for key in ("min_um", "max_um"):
                    if key in ref:
                        row[key] = ref[key]
                rows.append(row)
                if progress is not None:
                    progress(done / total, label)
                if not result.completed:
                    return rows
        return rows


def _name_the_line(error: BenchError, source: Optional[Tuple[str, List[int]]]) -> None:
    """Adds the file and line of the sample a daemon error names (``details["sample"]``)."""
    sample = error.details.get("sample")
    if source is None or not isinstance(sample, int):
        return
    path, lines = source
    if 0 <= sample < len(lines):
        error.details.setdefault("file", path)
        error.details.setdefault("line", lines[sample])
        error.message = f"{error.message} ({path}:{lines[sample]})"


def _scaled(
    progress: Progress, start: float, span: float, label: Optional[str] = None
) -> Progress:
    """The run's own progress (label "track", its kind) maps onto [start, start + span]; a stage
    before it (e.g. "planning the feedforward") holds the bar at start and names itself."""

    def report(fraction: float, what: str) -> None:
        if label is not None and what != "track":
            progress(start, f"{label}: {what}")
            return
        progress(start + span * min(max(fraction, 0.0), 1.0), label if label is not None else what)

    return report
