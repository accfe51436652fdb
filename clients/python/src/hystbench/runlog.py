"""Run logs and data files: ``read_run`` and the CSV reader behind ``track(reference_file=...)``.

A run log (``<log_dir>/<run_id>.csv``) starts with ``#`` comment lines, each a JSON object
(schema, run parameters, model, units, flag bits, columns), then a header row and one numeric
row per sample: ``index,t,t_scheduled_ns,t_wake_ns,exec_ns,yr,u_ff,u_fb,u,y,y_model,flags``
(``t`` in s, ``yr``/``y``/``y_model`` in µm, ``u*`` in V, ``*_ns`` in ns). On open-loop rows
(the precondition sweep, an excitation) the ``open_loop`` flag bit (``header["flags"]``) is set
and ``yr`` holds ``y_model``: no reference is followed there. ``NaN`` marks a value that cannot
exist (a measurement the driver reported as not a number).
"""

from __future__ import annotations

import json
import math
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

PathLike = Union[str, "os.PathLike[str]"]

_PANDAS_MISSING = (
    "pandas is not installed: {what} needs it (pip install pandas, or apt install "
    "python3-pandas); RunLog.columns has the same data as plain lists"
)


class RunLog:
    """One run log: its JSON header and its columns.

    Attributes:
        path: the file read.
        header: every ``#`` JSON object merged into one dict, in file order (a later key
            replaces an earlier one; the daemon writes each top-level key once), e.g.
            ``header["run"]["kind"]``, ``header["units"]["y"] == "um"``, ``header["model"]``.
        header_objects: the ``#`` JSON objects as they appear, one dict per line.
        comments: ``#`` lines that are not JSON objects, as text (a run log has none).
        columns: column name -> list of floats (every column, or those asked for), in the
            order of the header row; ``NaN`` where the log has ``NaN``.
    """

    def __init__(
        self,
        path: str,
        header_objects: List[Dict[str, Any]],
        comments: List[str],
        columns: Dict[str, List[float]],
    ) -> None:
        self.path = path
        self.header_objects = header_objects
        self.comments = comments
        self.header: Dict[str, Any] = {}
        for obj in header_objects:
            self.header.update(obj)
        self.columns = columns

    @property
    def names(self) -> List[str]:
        """The column names, in file order."""
        return list(self.columns)

    @property
    def units(self) -> Dict[str, str]:
        """Column name -> unit (``"s"``, ``"um"``, ``"V"``, ``"ns"``, ``"1"``) from the header."""
        units = self.header.get("units")
        return dict(units) if isinstance(units, dict) else {}

    def __len__(self) -> int:
        """The number of rows (samples)."""
        for values in self.columns.values():
            return len(values)
        return 0

    def __getitem__(self, name: str) -> List[float]:
        return self.columns[name]

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def __repr__(self) -> str:
        kind = (
            self.header.get("run", {}).get("kind", "?")
            if isinstance(self.header.get("run"), dict)
            else "?"
        )
        return f"RunLog({self.path!r}, {kind}, {len(self)} rows, columns={self.names})"

    def to_pandas(self) -> Any:
        """The columns as a ``pandas.DataFrame`` (the header in ``DataFrame.attrs["header"]``).

        Raises ImportError with an explanation when pandas is not installed.
        """
        try:
            import pandas  # type: ignore[import-not-found]
        except ImportError as e:
            raise ImportError(_PANDAS_MISSING.format(what="RunLog.to_pandas()")) from e
        frame = pandas.DataFrame(self.columns)
        frame.attrs["header"] = self.header
        frame.attrs["path"] = self.path
        return frame


def _split(line: str, delimiter: Optional[str]) -> List[str]:
    if delimiter is None:
        return line.split()
    return [cell.strip() for cell in line.split(delimiter)]


def _parse_rows(
    path: str, rows: List[Tuple[int, str]], delimiter: Optional[str], width: int
) -> List[List[str]]:
    cells = []
    for lineno, line in rows:
        row = _split(line, delimiter)
        if len(row) != width:
            raise ValueError(f"{path}:{lineno}: {len(row)} fields, the header has {width}")
        cells.append(row)
    return cells


def _to_floats(path: str, name: str, texts: List[str], linenos: Sequence[int]) -> List[float]:
    try:
        return [float(x) for x in texts]
    except ValueError:
        pass
    out = []
    for text, lineno in zip(texts, linenos):
        try:
            out.append(float(text) if text != "" else math.nan)
        except ValueError:
            raise ValueError(
                f"{path}:{lineno}: column {name!r}: {text!r} is not a number"
            ) from None
    return out


def _keep_comment(line: str, header_objects: List[Dict[str, Any]], comments: List[str]) -> None:
    text = line[1:].strip()
    try:
        obj = json.loads(text)
    except ValueError:
        obj = None
    if isinstance(obj, dict):
        header_objects.append(obj)
    else:
        comments.append(text)


def _read_table(
    path: PathLike, wanted: Optional[Sequence[str]] = None
) -> Tuple[List[Dict[str, Any]], List[str], Dict[str, List[float]], List[int]]:
    """Reads a CSV with ``#`` comment lines; returns (JSON comments, other comments, columns,
    the file's line number of each row).

    The first non-comment line is the header row, unless it is all numbers: then the columns
    are named by position, ``"1"``, ``"2"``, ... (as the ``hystbench`` offline commands do).
    Fields are separated by commas, or by blanks when the first line has no comma.
    """
    spath = os.fspath(path)
    header_objects: List[Dict[str, Any]] = []
    comments: List[str] = []
    data: List[Tuple[int, str]] = []
    with open(spath, "r", encoding="utf-8") as f:
        for lineno, raw in enumerate(f, start=1):
            line = raw.strip()
            if not line:
                continue
            if line.startswith("#"):
                _keep_comment(line, header_objects, comments)
                continue
            data.append((lineno, line))
    if not data:
        raise ValueError(f"{spath}: no header row and no data")
    first_line = data[0][1]
    delimiter: Optional[str] = "," if "," in first_line else None
    first = _split(first_line, delimiter)
    try:
        [float(x) for x in first]
        names = [str(k + 1) for k in range(len(first))]
    except ValueError:
        names = first
        data = data[1:]
    if len(set(names)) != len(names):
        raise ValueError(f"{spath}: the header row repeats a column name: {names}")
    if wanted is not None:
        missing = [w for w in wanted if w not in names]
        if missing:
            raise ValueError(
                f"{spath}: no column {', '.join(repr(m) for m in missing)} "
                f"(columns: {', '.join(names)})"
            )
    cells = _parse_rows(spath, data, delimiter, len(names))
    linenos = [lineno for lineno, _ in data]
    columns: Dict[str, List[float]] = {}
    for j, name in enumerate(names):
        if wanted is not None and name not in wanted:
            continue
        columns[name] = _to_floats(spath, name, [row[j] for row in cells], linenos)
    return header_objects, comments, columns, linenos


def read_run(
    path: PathLike, *, pandas: bool = False, columns: Optional[Sequence[str]] = None
) -> Any:
    """Reads a run log written by hystbenchd (or any CSV with ``#`` comments and a header row).

    Args:
        path: the log, e.g. ``result["log"]`` of a finished run (the daemon's path: read it on
            the daemon's machine, or where its log folder is shared).
        pandas: return a ``pandas.DataFrame`` instead of a ``RunLog`` (ImportError when pandas
            is not installed).
        columns: read only these columns (less memory for long runs); all by default.

    Returns:
        A ``RunLog``: ``.header`` (the ``#`` JSON objects merged into one dict),
        ``.header_objects`` (one dict per line), ``.columns`` (name -> list of floats).
    """
    if pandas:
        try:
            import pandas as pd  # type: ignore[import-not-found]
        except ImportError as e:
            raise ImportError(_PANDAS_MISSING.format(what="read_run(..., pandas=True)")) from e
        return _read_pandas(pd, path, columns)
    header_objects, comments, cols, _ = _read_table(path, columns)
    return RunLog(os.fspath(path), header_objects, comments, cols)


def _read_pandas(pd: Any, path: PathLike, columns: Optional[Sequence[str]]) -> Any:
    """read_run(..., pandas=True): the header here, the rows by pandas.read_csv (faster)."""
    spath = os.fspath(path)
    header_objects: List[Dict[str, Any]] = []
    comments: List[str] = []
    first = None
    with open(spath, "r", encoding="utf-8") as f:
        for raw in f:
            line = raw.strip()
            if line.startswith("#"):
                _keep_comment(line, header_objects, comments)
            elif line:
                first = line
                break
    if first is None:
        raise ValueError(f"{spath}: no header row and no data")
    delimiter: Optional[str] = "," if "," in first else None
    cells = _split(first, delimiter)
    options: Dict[str, Any] = {"comment": "#", "sep": delimiter or r"\s+"}
    try:
        [float(x) for x in cells]
        names = [str(k + 1) for k in range(len(cells))]
        options.update(header=None, names=names)
    except ValueError:
        names = cells
    if columns is not None:
        missing = [c for c in columns if c not in names]
        if missing:
            raise ValueError(
                f"{spath}: no column {', '.join(repr(m) for m in missing)} "
                f"(columns: {', '.join(names)})"
            )
        options["usecols"] = list(columns)
    frame = pd.read_csv(spath, **options)
    log = RunLog(spath, header_objects, comments, {})
    frame.attrs["header"] = log.header
    frame.attrs["path"] = spath
    return frame


def read_signal(
    path: PathLike,
    value_column: str,
    t_column: Optional[str] = "t",
    rate_hz: Optional[float] = None,
) -> Tuple[Optional[List[float]], List[float]]:
    """Reads one signal from a CSV: (times [s] or None, values).

    With ``rate_hz`` the file's time column is not used (None is returned for the times: the
    samples are uniform at ``rate_hz``). Without it the file needs ``t_column``. Columns are
    named by the header row, or ``"1"``, ``"2"``, ... in a file without one.
    """
    t, values, _ = _read_signal_lines(path, value_column, t_column, rate_hz)
    return t, values


def _read_signal_lines(
    path: PathLike, value_column: str, t_column: Optional[str], rate_hz: Optional[float]
) -> Tuple[Optional[List[float]], List[float], List[int]]:
    """``read_signal`` and the file's line number of each sample."""
    if rate_hz is not None or t_column is None:
        if rate_hz is None:
            raise ValueError(f"{os.fspath(path)}: no time column: give rate_hz [Hz]")
        _, _, cols, lines = _read_table(path, [value_column])
        return None, cols[value_column], lines
    _, _, cols, lines = _read_table(path, [t_column, value_column])
    return cols[t_column], cols[value_column], lines
