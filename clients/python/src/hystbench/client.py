"""``Bench``: a connection to hystbenchd over its Unix socket (JSON lines, protocol 1).

The daemon greets a new connection with ``{"hello": "hystbenchd", "version": .., "protocol": 1}``;
a request is ``{"id": .., "cmd": .., "params": {..}}``, its reply ``{"id": .., "ok": true,
"result": ..}`` or ``{"id": .., "ok": false, "error": {"code": .., "message": ..}}``. Events have
no id and go to every connection: ``run.progress``, ``fit.progress`` and ``run.finished`` (with
the run's result).
"""

from __future__ import annotations

import collections
import json
import math
import os
import socket
import time
from typing import (
    Any,
    Callable,
    Deque,
    Dict,
    Iterable,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

from .errors import BenchConnectionError, BenchError, RunEndedError
from .runlog import _read_signal_lines

DEFAULT_SOCKET = "/run/hystbench/hystbench.sock"
"""The service's socket, used when neither ``socket_path`` nor ``$HYSTBENCH_SOCKET`` is given."""

MAX_LINE_BYTES = 1024 * 1024
"""The daemon's longest request line, the newline excluded [bytes]: a model file with its measured
frequency responses (about 85 kB) fits many times."""

Progress = Callable[[float, str], None]
"""A progress callback: ``progress(fraction, label)``, fraction in [0, 1]."""

PathLike = Union[str, "os.PathLike[str]"]

_MAX_BUFFERED_EVENTS = 10000


def default_socket_path() -> str:
    """``$HYSTBENCH_SOCKET`` when set and not empty, else ``/run/hystbench/hystbench.sock``."""
    return os.environ.get("HYSTBENCH_SOCKET") or DEFAULT_SOCKET


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


def _json_default(value: Any) -> Any:
    # numpy arrays and scalars (optional; never imported here).
    if hasattr(value, "tolist"):
        return value.tolist()
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _finite_floats(values: Iterable[Any], what: str) -> List[float]:
    out: List[float] = []
    for k, v in enumerate(values):
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"{what}[{k}] = {v!r}: not a number") from None
        if not math.isfinite(x):
            raise ValueError(f"{what}[{k}] = {x!r}: not a finite number")
        out.append(x)
    return out


def _without_none(params: Mapping[str, Any]) -> Dict[str, Any]:
    return {k: v for k, v in params.items() if v is not None}


class Bench:
    """A connection to hystbenchd; a context manager (``with Bench() as bench: ...``).

    Args:
        socket_path: the daemon's socket; default ``$HYSTBENCH_SOCKET``, else
            ``/run/hystbench/hystbench.sock``.
        timeout: how long a request waits for its reply [s] (not how long a run may take: see
            ``wait``).

    Raises:
        BenchConnectionError: (a ``ConnectionError``) the socket cannot be reached or does not
            greet as hystbenchd; the message names the socket.

    Every method sends one request and returns the daemon's ``result`` (a dict), or raises
    ``BenchError`` with the daemon's error ``code`` and ``message``. The run methods
    (``identify``, ``track``, ``excite``) return the start reply (``run_id``, ``log``,
    ``duration_s``, ...) or, with ``wait=True``, follow the run's events until it ends and
    return its ``RunResult``. A ``Bench`` is not thread-safe: use one per thread.
    """

    def __init__(self, socket_path: Optional[PathLike] = None, *, timeout: float = 30.0) -> None:
        self.socket_path: str = os.fspath(socket_path) if socket_path else default_socket_path()
        self.timeout = timeout
        self._buffer = bytearray()
        self._events: Deque[Dict[str, Any]] = collections.deque(maxlen=_MAX_BUFFERED_EVENTS)
        self._next_id = 0
        self._own_runs: Deque[str] = collections.deque(maxlen=64)
        self._finished: "collections.OrderedDict[str, RunResult]" = collections.OrderedDict()
        self._sock: Optional[socket.socket] = None
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            sock.settimeout(timeout)
            sock.connect(self.socket_path)
        except (FileNotFoundError, ConnectionRefusedError) as e:
            sock.close()
            raise BenchConnectionError(
                self.socket_path,
                f"cannot connect: {e.strerror or e} (is hystbenchd running? start it, or pass "
                "socket_path / set HYSTBENCH_SOCKET)",
            ) from None
        except PermissionError as e:
            sock.close()
            raise BenchConnectionError(
                self.socket_path,
                f"cannot connect: {e.strerror or e} (not in the group that owns the socket?)",
            ) from None
        except OSError as e:
            sock.close()
            raise BenchConnectionError(self.socket_path, f"cannot connect: {e}") from None
        self._sock = sock
        try:
            hello = self._read_message(time.monotonic() + min(timeout, 5.0))
        except BenchConnectionError:
            self.close()
            raise
        if not isinstance(hello, dict) or "hello" not in hello:
            self.close()
            raise BenchConnectionError(self.socket_path, "no hystbenchd greeting on this socket")
        self.greeting: Dict[str, Any] = hello
        """The daemon's greeting: ``hello``, ``version``, ``protocol``."""

    # ---- connection ---------------------------------------------------------------------------

    @property
    def version(self) -> str:
        """The daemon's version (from its greeting)."""
        return str(self.greeting.get("version", ""))

    @property
    def protocol(self) -> int:
        """The protocol version the daemon speaks (1)."""
        return int(self.greeting.get("protocol", 0))

    def close(self) -> None:
        """Closes the connection (the daemon discards this connection's uploads; runs go on)."""
        if self._sock is not None:
            try:
                self._sock.close()
            finally:
                self._sock = None

    @property
    def closed(self) -> bool:
        return self._sock is None

    def __enter__(self) -> "Bench":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"hystbenchd {self.version}"
        return f"Bench({self.socket_path!r}, {state})"

    def _fail(self, message: str) -> BenchConnectionError:
        self.close()
        return BenchConnectionError(self.socket_path, message)

    def _read_message(self, deadline: Optional[float]) -> Optional[Dict[str, Any]]:
        """The next line as JSON, or None when the deadline (monotonic time) passes first."""
        while True:
            newline = self._buffer.find(b"\n")
            if newline >= 0:
                line = bytes(self._buffer[:newline])
                del self._buffer[: newline + 1]
                if not line.strip():
                    continue
                try:
                    msg = json.loads(line)
                except ValueError as e:
                    raise self._fail(f"the daemon sent a malformed line: {e}") from None
                if not isinstance(msg, dict):
                    raise self._fail("the daemon sent a line that is not a JSON object")
                return msg
            if self._sock is None:
                raise BenchConnectionError(self.socket_path, "the connection is closed")
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                return None
            self._sock.settimeout(left)
            try:
                chunk = self._sock.recv(65536)
            except socket.timeout:
                return None
            except OSError as e:
                raise self._fail(f"read failed: {e}") from None
            if not chunk:
                raise self._fail("the daemon closed the connection")
            self._buffer += chunk

    def _encode(self, cmd: str, params: Optional[Mapping[str, Any]], request_id: int) -> bytes:
        try:
            text = json.dumps(
                {"id": request_id, "cmd": cmd, "params": dict(params or {})},
                allow_nan=False,
                separators=(",", ":"),
                default=_json_default,
            )
        except ValueError as e:
            raise ValueError(f"{cmd}: the parameters hold NaN or infinity ({e})") from None
        return text.encode("utf-8")

    def _exchange(self, cmd: str, line: bytes, request_id: int, timeout: Optional[float]) -> Any:
        if len(line) > MAX_LINE_BYTES:
            raise ValueError(
                f"{cmd}: the request is {len(line)} bytes; the daemon takes lines of at most "
                f"{MAX_LINE_BYTES} bytes"
            )
        if self._sock is None:
            raise BenchConnectionError(self.socket_path, "the connection is closed")
        wait_s = self.timeout if timeout is None else timeout
        self._sock.settimeout(wait_s)
        try:
            self._sock.sendall(line + b"\n")
        except OSError as e:
            raise self._fail(f"send failed: {e}") from None
        deadline = time.monotonic() + wait_s
        while True:
            msg = self._read_message(deadline)
            if msg is None:
                raise TimeoutError(f"{self.socket_path}: no reply to '{cmd}' within {wait_s:g} s")
            if "event" in msg and "id" not in msg:
                self._events.append(msg)
                continue
            # A reply with a null id answers a line the daemon could not read as a request
            # (only ever ours: one request is in flight at a time).
            if msg.get("id") == request_id or ("id" in msg and msg["id"] is None and "ok" in msg):
                if msg.get("ok"):
                    return msg.get("result")
                error = msg.get("error") or {}
                details = {k: v for k, v in error.items() if k not in ("code", "message")}
                raise BenchError(
                    str(error.get("code", "error")), str(error.get("message", "")), details, cmd
                )
            # Anything else is a stale reply to a request that timed out: skip it.

    def request(
        self,
        cmd: str,
        params: Optional[Mapping[str, Any]] = None,
        *,
        timeout: Optional[float] = None,
    ) -> Any:
        """Sends one request and returns its result (raises ``BenchError`` on an error reply).

        The low-level door to every command, e.g. ``bench.request("status")``. Events that
        arrive meanwhile are kept for ``wait`` / ``next_event``.
        """
        self._next_id += 1
        request_id = self._next_id
        return self._exchange(cmd, self._encode(cmd, params, request_id), request_id, timeout)

    def next_event(self, timeout: Optional[float] = None) -> Optional[Dict[str, Any]]:
        """The next event (``run.progress``, ``fit.progress``, ``run.finished``, ...) or None.

        Args:
            timeout: how long to wait [s]; None waits until one arrives.
        """
        if self._events:
            return self._events.popleft()
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            msg = self._read_message(deadline)
            if msg is None:
                return None
            if "event" in msg and "id" not in msg:
                return msg

    # ---- simple commands ----------------------------------------------------------------------

    def status(self) -> Dict[str, Any]:
        """State (``idle``, ``preparing``, ``running``, ``finalizing``, ``fault``, ...), active run,
        model, loop (``rate_hz``, ``clock``: ``wall`` or ``simulated``, real-time setup, timing),
        output (``output_v`` [V], ``position_um`` [µm]) and the last run's result
        (``last_result``)."""
        return self.request("status")

    def runs(self) -> List[Dict[str, Any]]:
        """The last 200 runs, newest first, kept across restarts: each ``{"run_id",
        "kind", "end", "reason", "finished"`` (UTC), ``"rms_error_percent"`` (or None), ``"log"``
        (the sample log's path, or None)``}``."""
        return self.request("runs")["runs"]

    def run_get(self, run_id: str) -> Dict[str, Any]:
        """One of ``runs()``' results, whole, as the run's end gave it.

        Raises BenchError ``unknown_run`` for a run the daemon does not keep.
        """
        return self.request("run.get", {"run_id": run_id})

    def config_get(self) -> Dict[str, Any]:
        """The daemon's effective configuration (``loop.rate_hz`` [Hz], ``limits``, ...)."""
        return self.request("config.get")

    def stop(self) -> Dict[str, Any]:
        """Ends the active run normally (it ends as ``stopped``, its result is kept).

        Raises BenchError ``no_run`` when no run is active.
        """
        return self.request("stop")

    def abort(self) -> Dict[str, Any]:
        """Safe output now; the active run ends as ``aborted``. Returns ``aborted`` (whether a
        run was active) and ``output_v`` (the safe output [V])."""
        return self.request("abort")

    def reset(self) -> Dict[str, Any]:
        """Leaves FAULT (after the cause is fixed): ``was_fault``, ``state``."""
        return self.request("reset")

    def model_get(self) -> Dict[str, Any]:
        """The active model: ``{"path": <file on the daemon's side>, "model": <model document>}``.

        Raises BenchError ``no_model`` before any identify or model load.
        """
        return self.request("model.get")

    def model_list(self) -> Dict[str, Any]:
        """The daemon's model folder: ``{"folder": .., "models": [{"name", "type",
        "operators", "bytes", "active"}, ..]}``."""
        return self.request("model.list")

    def model_delete(self, name: str) -> Dict[str, Any]:
        """Deletes a model or a learned drive (its JSON and CSV) from the daemon's model folder,
        by the name ``model_list()`` shows; never the active model (``bad_params``).
        Returns ``{"deleted": [file names]}``."""
        return self.request("model.delete", {"name": name})

    def model_load(
        self,
        model: Union[Mapping[str, Any], PathLike, None] = None,
        name: Optional[str] = None,
        *,
        stored: Optional[str] = None,
    ) -> Dict[str, Any]:
        """Makes a model active; the daemon keeps a copy in its model folder.

        Args:
            model: a model document (dict, ``"schema": "hystbench.model/1"``; the dict
                ``model_get()`` returns is accepted too), or the path of a local model file
                (read here and sent as a document: the daemon never opens a client's path).
            name: the name the daemon keeps it under (letters, digits, ``.``, ``_``, ``-``;
                ``.json`` added); default the file's name, or ``uploaded.json`` for a dict.
            stored: instead of ``model``: the name of a model in the daemon's model folder
                (see ``model_list()``); on a stage, the stage identify's run id.

        On a stage of several axes, ``model`` is a list of every axis's file (or document) of
        one stage identify (``RUN-x.json``, ``RUN-y.json``), each sent keyed by the axis it
        names; the reply gives ``stage_run_id``, ``axes`` and ``coupling``.

        Returns:
            ``path``, ``name``, ``type``, ``invertible``, ``reason``.
        """
        if stored is not None:
            if model is not None or name is not None:
                raise ValueError("model_load: give a model (and a name) or stored=, not both")
            return self.request("model.load", {"stored": stored})
        if model is None:
            raise ValueError("model_load: give a model document, a model file, or stored=NAME")
        if isinstance(model, (list, tuple)):
            return self._load_stage_models(model)
        if isinstance(model, Mapping):
            document = dict(model)
            if "schema" not in document and isinstance(document.get("model"), Mapping):
                document = dict(document["model"])  # the result of model_get()
        elif isinstance(model, (str, os.PathLike)):
            path = os.fspath(model)
            with open(path, "r", encoding="utf-8") as f:
                text = f.read()
            try:
                document = json.loads(text)
            except ValueError as e:
                raise ValueError(f"{path}: not a JSON model file: {e}") from None
            if not isinstance(document, dict):
                raise ValueError(f"{path}: a model file holds one JSON object")
            if name is None:
                name = os.path.basename(path)
        else:
            raise TypeError(
                f"model_load: model must be a dict or a file path, not {type(model).__name__}"
            )
        params: Dict[str, Any] = {"model": document}
        if name is not None:
            params["name"] = name
        return self.request("model.load", params)

    def _load_stage_models(self, models: Iterable[Any]) -> Dict[str, Any]:
        """model.load of a stage's files or documents, keyed by their stage_axis."""
        by_axis: Dict[str, Any] = {}
        for m in models:
            if isinstance(m, Mapping):
                document, source = dict(m), "a document"
            else:
                source = os.fspath(m)
                with open(source, "r", encoding="utf-8") as f:
                    document = json.load(f)
            ident = document.get("identification") or {}
            axis = ident.get("stage_axis") if "stage" in ident else None
            if not isinstance(axis, str) or axis in by_axis:
                raise ValueError(
                    f"model_load: {source}: "
                    + ("a second model for axis " + axis if axis in by_axis else
                       "not one axis's model of a stage identify")
                )
            by_axis[axis] = document
        return self.request("model.load", {"models": by_axis})

    # ---- uploads ------------------------------------------------------------------------------

    def upload(
        self,
        kind: str,
        values: Iterable[float],
        *,
        rate_hz: Optional[float] = None,
        t: Optional[Iterable[float]] = None,
        progress: Optional[Progress] = None,
        source: Optional[str] = None,
    ) -> str:
        """Sends a signal to the daemon in chunks; returns the upload's id for one run.

        Args:
            kind: ``"reference"`` (µm, for ``track``) or ``"drive"`` (V, for ``excite``).
            values: the samples.
            rate_hz: the samples are uniform at this rate [Hz]; or
            t: one time per value [s], strictly increasing.
            progress: called with (fraction sent, ``"upload"``).
            source: what to call it in the daemon's messages and the run log's header (a file
                name; the daemon never opens it).

        The upload belongs to this connection: the daemon discards it when the connection
        closes, and the run that uses it consumes it. ``track(reference=[...])`` and
        ``excite(drive=[...])`` call this for you.
        """
        vals = _finite_floats(values, "values")
        if (rate_hz is None) == (t is None):
            raise ValueError("upload: give rate_hz [Hz] (uniform samples) or t [s], one of them")
        times: Optional[List[float]] = None
        if t is not None:
            times = _finite_floats(t, "t")
            if len(times) != len(vals):
                raise ValueError(f"upload: {len(times)} times for {len(vals)} values")
        begin: Dict[str, Any] = {"kind": kind, "samples": len(vals)}
        if rate_hz is not None:
            begin["rate_hz"] = float(rate_hz)
        if source is not None:
            begin["source"] = source
        reply = self.request("upload.begin", begin)
        upload_id = str(reply["upload"])
        try:
            self._send_chunks(
                upload_id, vals, times, int(reply.get("max_chunk_samples", 2000)), progress
            )
        except BaseException:
            self._cancel_quietly(upload_id)
            raise
        return upload_id

    def _send_chunks(
        self,
        upload_id: str,
        values: List[float],
        times: Optional[List[float]],
        max_chunk: int,
        progress: Optional[Progress],
    ) -> None:
        total = len(values)
        offset = 0
        count = max(1, max_chunk)
        while offset < total:
            count = min(count, total - offset)
            while True:
                params: Dict[str, Any] = {
                    "upload": upload_id,
                    "offset": offset,
                    "values": values[offset : offset + count],
                }
                if times is not None:
                    params["t"] = times[offset : offset + count]
                self._next_id += 1
                request_id = self._next_id
                line = self._encode("upload.chunk", params, request_id)
                if len(line) <= MAX_LINE_BYTES or count == 1:
                    break
                # Too long for one line (17 significant digits, with times): fewer samples.
                count = max(1, int(count * MAX_LINE_BYTES / len(line) * 0.95))
            reply = self._exchange("upload.chunk", line, request_id, None)
            offset += count
            received = reply.get("received") if isinstance(reply, dict) else None
            if received is not None and int(received) != offset:
                raise BenchError(
                    "upload_mismatch",
                    f"the daemon has {received} samples of upload {upload_id}, {offset} were sent",
                    command="upload.chunk",
                )
            if progress is not None:
                progress(offset / total, "upload")
            # The next chunk starts from the size that fitted (times make every chunk shorter).

    def upload_cancel(self, upload_id: str) -> Dict[str, Any]:
        """Discards an upload that no run has used."""
        return self.request("upload.cancel", {"upload": upload_id})

    def _cancel_quietly(self, upload_id: str) -> None:
        try:
            if not self.closed:
                self.upload_cancel(upload_id)
        except (BenchError, BenchConnectionError, TimeoutError):
            pass

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
