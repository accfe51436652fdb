"""The commands of ``Bench`` that answer at once: the bench's state, its runs and configuration,
stopping and resetting, and the model folder (``model_get``, ``model_list``, ``model_load``, ...).
"""

from __future__ import annotations

import collections
import json
import os
from typing import (
    TYPE_CHECKING,
    Any,
    Callable,
    Deque,
    Dict,
    Iterable,
    List,
    Mapping,
    Optional,
    Union,
)

from ._shared import PathLike
from .results import RunResult


class _Commands:
    """The base of ``Bench``'s commands; ``Bench`` (client.py) adds the connection and uploads."""

    if TYPE_CHECKING:  # what Bench's connection and uploads give the commands, for type checkers
        socket_path: str
        _events: Deque[Dict[str, Any]]
        _own_runs: Deque[str]
        _finished: "collections.OrderedDict[str, RunResult]"
        request: Callable[..., Any]
        upload: Callable[..., str]
        _read_message: Callable[[Optional[float]], Optional[Dict[str, Any]]]
        _cancel_quietly: Callable[[str], None]

        @property
        def closed(self) -> bool: ...

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
