"""What the client's modules share: the progress callback's type, a path's, and a request's
parameters without those left unset."""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Mapping, Union

Progress = Callable[[float, str], None]
"""A progress callback: ``progress(fraction, label)``, fraction in [0, 1]."""

PathLike = Union[str, "os.PathLike[str]"]


def _without_none(params: Mapping[str, Any]) -> Dict[str, Any]:
    return {k: v for k, v in params.items() if v is not None}
