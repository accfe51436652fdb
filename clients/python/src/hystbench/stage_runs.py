"""The runs of ``Bench`` on a stage of several axes: ``track_axes`` and ``excite_axes``, each
axis's signal uploaded under its name."""

from __future__ import annotations

from typing import Any, Dict, Iterable, Optional

from ._shared import PathLike, Progress, _without_none
from .errors import BenchError
from .runs import _Runs


class _StageRuns(_Runs):
    """``Bench``'s runs on every axis of a stage at once."""

    def track_axes(
        self,
        references: Optional[Dict[str, Iterable[float]]] = None,
        *,
        rate_hz: Optional[float] = None,
        t: Optional[Iterable[float]] = None,
        reference_file: Optional[PathLike] = None,
        t_column: Optional[str] = "t",
        compensator: Optional[str] = None,
        decouple: Optional[bool] = None,
        decoupling: Optional[str] = None,
        precondition_s: Optional[float] = None,
        approach_s: Optional[float] = None,
        wait: bool = False,
        progress: Optional[Progress] = None,
        timeout: Optional[float] = None,
    ) -> Dict[str, Any]:
        """Tracks your own trajectory on a stage of several axes (``status()["axes"]``).

        ``references={"x": [...], "y": [...]}``: each axis's positions [µm], sampled uniformly
        at ``rate_hz`` [Hz] or at the times ``t`` [s]; or ``reference_file="scan.csv"`` with the
        time column ``t_column`` and a column per axis, named as the axes. Every axis needs its
        reference (``ValueError`` names a missing one). Built-in references go through
        ``track(reference="raster" | "lissajous" | "spiral", frequencies_hz=[...])``.

        The result holds ``axes`` (each axis's ``rms_error_percent``, ``max_error_percent``,
        ...), ``coupling_error`` (what the other axes' motion left on each) and
        ``decoupling``. ``decouple=False`` leaves the coupling in the feedforward's targets;
        ``decoupling="dynamic"`` takes out each coupling path's modes and lag too, fitted to the
        responses identify measured (by default, ``"static"``, its gains).
        """
        uploads = self._upload_per_axis(
            "track_axes", "reference", references, rate_hz, t, reference_file, t_column, progress
        )
        request = _without_none(
            {
                "reference_uploads": uploads,
                "compensator": compensator,
                "decouple": decouple,
                "decoupling": decoupling,
                "precondition_s": precondition_s,
                "approach_s": approach_s,
            }
        )
        return self._start_on_axes("track", request, uploads, wait, progress, timeout)

    def _upload_per_axis(
        self,
        caller: str,
        kind: str,
        signals: Optional[Dict[str, Iterable[float]]],
        rate_hz: Optional[float],
        t: Optional[Iterable[float]],
        path: Optional[PathLike],
        t_column: Optional[str],
        progress: Optional[Progress],
    ) -> Dict[str, str]:
        """Uploads each axis's signal (or the file's column named as the axis); returns the
        upload ids by axis. ``ValueError`` names a missing or unknown axis; on any failure the
        uploads already made are cancelled."""
        axes = list(self.status().get("axes", {}))
        if not axes:
            raise ValueError(f"{caller}: the bench drives one axis")
        if (signals is None) == (path is None):
            raise ValueError(f"{caller}: give the samples per axis or a file")
        if signals is not None:
            unknown = sorted(set(signals) - set(axes))
            if unknown:
                raise ValueError(f"{caller}: {', '.join(unknown)}: no axis of the stage {axes}")
        times = list(t) if t is not None else None  # every axis's samples at these times
        uploads: Dict[str, str] = {}
        try:
            for axis in axes:
                if signals is not None:
                    if axis not in signals:
                        raise ValueError(f"{caller}: no {kind} for axis {axis!r}")
                    upload_id, _ = self._upload_signal(
                        kind, signals[axis], rate_hz, times, None, (None, axis), progress
                    )
                else:
                    upload_id, _ = self._upload_signal(
                        kind, None, rate_hz, None, path, (t_column, axis), progress
                    )
                uploads[axis] = upload_id
        except Exception:
            for upload_id in uploads.values():
                self._cancel_quietly(upload_id)
            raise
        return uploads

    def excite_axes(
        self,
        drives: Optional[Dict[str, Iterable[float]]] = None,
        *,
        rate_hz: Optional[float] = None,
        t: Optional[Iterable[float]] = None,
        input_file: Optional[PathLike] = None,
        t_column: Optional[str] = "t",
        wait: bool = False,
        progress: Optional[Progress] = None,
        timeout: Optional[float] = None,
    ) -> Dict[str, Any]:
        """Plays an open-loop drive on every axis of a stage at once and records the responses.

        ``drives={"x": [...], "y": [...]}``: each axis's output [V] sampled uniformly at
        ``rate_hz`` [Hz] or at the times ``t`` [s]; or ``input_file="drive.csv"`` with the time
        column ``t_column`` and a column per axis, named as the axes. Every axis needs its drive
        (``ValueError`` names a missing one). Each axis ramps from where it is to its drive's
        first sample; an axis whose drive ends first holds its last value. The log has a set of
        columns per axis (``u_x``, ``y_x``, ...), a record ``hystbench fit`` reads.
        """
        uploads = self._upload_per_axis(
            "excite_axes", "drive", drives, rate_hz, t, input_file, t_column, progress
        )
        return self._start_on_axes(
            "excite", {"drive_uploads": uploads}, uploads, wait, progress, timeout
        )

    def _start_on_axes(
        self,
        cmd: str,
        request: Dict[str, Any],
        uploads: Dict[str, str],
        wait: bool,
        progress: Optional[Progress],
        timeout: Optional[float],
    ) -> Dict[str, Any]:
        """Starts a stage's run on its per-axis uploads; a refusal cancels them."""
        try:
            return self._start(cmd, request, wait, progress, timeout)
        except BenchError:
            for upload_id in uploads.values():
                self._cancel_quietly(upload_id)
            raise
