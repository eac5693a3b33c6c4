"""One real number where a value enters: a finite float, or an error naming the argument."""

from __future__ import annotations

import math

import numpy as np

from pfaff.core.errors import PfaffError, StateError


def real_number(value: object, arg: str, error: type[PfaffError] = StateError) -> float:
    """``value`` as a finite real float, else ``error`` (a :class:`StateError` by default)
    naming ``arg``.

    Strings, booleans, complex numbers and arrays of more than one number are refused, not
    converted (``float("1")``, ``float(True)`` and NumPy's complex-to-real cast would pass them).

    Parameters
    ----------
    value : object
        The value to check.
    arg : str
        The argument as the message names it.
    error : type
        The :class:`~pfaff.errors.PfaffError` subclass raised.

    Returns
    -------
    float

    Examples
    --------
    >>> real_number(2, "g")
    2.0
    >>> real_number("2", "g")
    Traceback (most recent call last):
    pfaff.core.errors.StateError: `g` must be a real number; got '2'
    """
    if isinstance(value, float) or type(value) is int:  # the common case (np.float64 too)
        v = float(value)
    else:
        if isinstance(value, str | bytes | bool | np.bool_) or np.ndim(value) != 0:
            raise error(f"`{arg}` must be a real number; got {value!r:.80}")
        if np.iscomplexobj(value) or isinstance(value, complex):
            raise error(f"`{arg}` must be a real number; got the complex value {value!r:.80}")
        try:
            v = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise error(f"`{arg}` must be a real number; got {value!r:.80}") from None
    if not math.isfinite(v):
        raise error(f"`{arg}` is not finite ({v})")
    return v
