"""``Bench``: a connection to hystbenchd over its Unix socket (JSON lines, protocol 1).

The daemon greets a new connection with ``{"hello": "hystbenchd", "version": .., "protocol": 1}``;
a request is ``{"id": .., "cmd": .., "params": {..}}``, its reply ``{"id": .., "ok": true,
"result": ..}`` or ``{"id": .., "ok": false, "error": {"code": .., "message": ..}}``. Events have
no id and go to every connection: ``run.progress``, ``fit.progress`` and ``run.finished`` (with
the run's result).

Here the connection and the uploads; the commands that answer at once are in commands.py, the
runs in runs.py and stage_runs.py (the classes ``Bench`` derives from), their results in
results.py.
"""

from __future__ import annotations

import collections
import json
import math
import os
import socket
import time
from typing import Any, Deque, Dict, Iterable, List, Mapping, Optional

from ._shared import PathLike, Progress  # noqa: F401  (re-exported by hystbench.client)
from .errors import BenchConnectionError, BenchError
from .results import RunResult, SweepResult  # noqa: F401  (re-exported by hystbench.client)
from .stage_runs import _StageRuns

DEFAULT_SOCKET = "/run/hystbench/hystbench.sock"
"""The service's socket, used when neither ``socket_path`` nor ``$HYSTBENCH_SOCKET`` is given."""

MAX_LINE_BYTES = 1024 * 1024
"""The daemon's longest request line, the newline excluded [bytes]: a model file with its measured
frequency responses (about 85 kB) fits many times."""

_MAX_BUFFERED_EVENTS = 10000


def default_socket_path() -> str:
    """``$HYSTBENCH_SOCKET`` when set and not empty, else ``/run/hystbench/hystbench.sock``."""
    return os.environ.get("HYSTBENCH_SOCKET") or DEFAULT_SOCKET


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


class Bench(_StageRuns):
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
