"""Exceptions raised by the hystbench client."""

from __future__ import annotations

from typing import Any, Dict, Optional


class BenchError(Exception):
    """The daemon refused a request: its error ``code`` and ``message``.

    ``code`` is the daemon's machine-readable code (``"bad_params"``, ``"no_model"``, ``"busy"``,
    ``"fault"``, ``"no_run"``, ``"unknown_command"``, ``"out_of_range"``, ``"slew_limit"``, ...),
    ``message`` its human-readable text. ``details`` holds any further keys the daemon put in
    the error object (for example the offending ``row`` or ``sample`` of an upload), ``command``
    the request that was refused.
    """

    def __init__(
        self,
        code: str,
        message: str,
        details: Optional[Dict[str, Any]] = None,
        command: Optional[str] = None,
    ) -> None:
        self.code = code
        self.message = message
        self.details: Dict[str, Any] = dict(details or {})
        self.command = command
        super().__init__(code, message)

    def __str__(self) -> str:
        prefix = f"{self.command}: " if self.command else ""
        return f"{prefix}{self.message} [{self.code}]"

    def __repr__(self) -> str:
        return f"BenchError({self.code!r}, {self.message!r})"


class RunEndedError(BenchError):
    """A run ended but did not complete (``RunResult.check()``).

    ``code`` is the run's ``end`` (``"stopped"``, ``"aborted"``, ``"fault"``) or ``"fit_error"``
    when an identification's fit failed; ``result`` is the whole run result.
    """

    def __init__(self, code: str, message: str, result: Dict[str, Any]) -> None:
        super().__init__(code, message, command=result.get("kind"))
        self.result = result


class BenchConnectionError(ConnectionError):
    """The daemon cannot be reached, or the connection broke; the message names the socket."""

    def __init__(self, socket_path: str, message: str) -> None:
        self.socket_path = socket_path
        super().__init__(f"{socket_path}: {message}")
