"""``--json`` output that is JSON: a non-finite number (NaN, ±∞) is written as ``null``.

Python's ``json.dumps`` writes ``NaN`` and ``Infinity``, which no JSON parser accepts; a report
holds them when a run fails (an energy drift of a run that blew up, a residual of NaN). Every
command's ``--json`` goes through :func:`dumps`, which writes them as ``null`` (documented in the
README) and refuses anything else that is not JSON.
"""

from __future__ import annotations

import json
import math


def dumps(report: object, indent: int | None = 1) -> str:
    """The report as JSON text, non-finite numbers as ``null``.

    Examples
    --------
    >>> dumps({"drift": float("nan"), "t": [0.0, float("inf")], "n": 2}, indent=None)
    '{"drift": null, "t": [0.0, null], "n": 2}'
    """
    return json.dumps(_finite(report), indent=indent, allow_nan=False)


def _finite(obj: object) -> object:
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    if type(obj).__module__ == "numpy":  # an array or a NumPy scalar (NumPy not imported here)
        obj = obj.tolist()  # type: ignore[attr-defined]
        if isinstance(obj, list):
            return _finite(obj)
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj
