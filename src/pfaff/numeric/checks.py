"""Checks where values enter the numeric stage: states, models, and values computed at a state.

Every numeric entry point validates its arguments here, so a wrong type, a complex or non-finite
value or a wrong shape is a :class:`pfaff.StateError` naming the argument, never NumPy's cast or
traceback; and a value that overflowed at a state is an error naming the time.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ModelTypeError, OptionError, StateError
from pfaff.core.reals import real_number
from pfaff.numeric.protocol import DynamicsModel

__all__ = ["real_number"]  # re-exported: the numeric stage's entry checks use it

SHORT = 64  # entries up to which a vector's finiteness is tested on a Python list


def real_vector(value: object, arg: str, n: int, names: Sequence[str] | None = None) -> np.ndarray:
    """``value`` as a finite float array of shape (n,), else a :class:`StateError` naming ``arg``.

    Complex arrays are refused (NumPy would drop the imaginary part with a mere warning), and so
    are strings, booleans, dicts, None and ragged or misshapen sequences.
    """
    if type(value) is np.ndarray and value.dtype == np.float64:  # the common case: no copy
        a = value
    else:
        if value is None or isinstance(value, str | bytes | dict | set):
            raise StateError(
                f"`{arg}` must be an array of {n} real numbers; got {type(value).__name__} "
                f"{value!r:.80}"
            )
        try:
            raw = np.asarray(value)
        except (TypeError, ValueError) as e:  # ragged nesting
            raise StateError(f"`{arg}` must be an array of {n} real numbers: {e}") from None
        kind = raw.dtype.kind
        if kind == "c":
            raise StateError(
                f"`{arg}` is complex (dtype {raw.dtype}); states are real: pass the real part "
                "explicitly if that is what you mean"
            )
        if kind == "O" and any(isinstance(v, str | bytes | bool | complex) for v in raw.flat):
            kind = "U"
        if kind not in "iufO":
            raise StateError(
                f"`{arg}` must be an array of {n} real numbers; got an array of dtype {raw.dtype}"
            )
        try:
            a = np.asarray(raw, dtype=float)
        except (TypeError, ValueError) as e:  # an object array holding something else
            raise StateError(f"`{arg}` must be an array of {n} real numbers: {e}") from None
    if a.shape != (n,):
        which = ","
        if names is not None:
            which = f" for coordinates {', '.join(names[:6])}{'...' if n > 6 else ''};"
        raise StateError(f"`{arg}` must have shape ({n},){which} got shape {a.shape}")
    # one pass and no temporary: a finite sum means finite entries (NaN and ±inf propagate);
    # only a sum that overflowed needs the elementwise test; a short vector is summed as a
    # list (0.3 µs against 3 µs for np.sum at n = 9: a checked call of a small model pays it)
    total = sum(a.tolist()) if n <= SHORT else float(a.sum())
    if not (math.isfinite(total) or np.isfinite(a).all()):
        raise StateError(f"`{arg}` contains NaN or infinity")
    return a


def check_state(
    t: object,
    q: object,
    qd: object,
    n: int,
    names: Sequence[str] | None = None,
    args: tuple[str, str, str] = ("t", "q", "qd"),
) -> tuple[float, np.ndarray, np.ndarray]:
    """Validate a numeric state: real finite t, real finite q and q̇ of shape (n,).

    Every numeric entry point of a model goes through here. ``names`` (the coordinates) and
    ``args`` (the caller's names of t, q and q̇, e.g. ``("t0", "q0", "qd0")``) go in the messages.
    """
    tt = real_number(t, args[0])
    return tt, real_vector(q, args[1], n, names), real_vector(qd, args[2], n, names)


def check_model(model: object, arg: str = "model") -> None:
    """Refuse anything but a compiled model with a :class:`ModelTypeError` naming ``arg``.

    The common slip, equations or a system passed before ``.compile(parameters)``, is named.
    """
    if isinstance(model, DynamicsModel):
        return
    kind = type(model).__name__
    if hasattr(model, "compile"):
        hint = "call `.compile(parameters)` on it first"
    elif hasattr(model, "equations"):
        hint = "call `.equations().compile(parameters)` on it first"
    else:
        hint = "make one with `system.equations().compile(parameters)`"
    raise ModelTypeError(
        f"`{arg}` must be a compiled model (NumericModel or StructuredModel); got {kind}: {hint}"
    )


def projection_options(tol: object, max_iter: object) -> tuple[float, int]:
    """A projection's ``tol`` (a positive finite number) and ``max_iter`` (an integer >= 0), or
    an :class:`OptionError` naming the argument.

    Examples
    --------
    >>> projection_options(1e-12, 8)
    (1e-12, 8)
    """
    if isinstance(tol, bool) or not isinstance(tol, numbers.Real) or not 0 < tol < math.inf:
        raise OptionError(f"`tol` must be a positive finite number; got {tol!r:.80}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, int | np.integer) or max_iter < 0:
        raise OptionError(f"`max_iter` must be an integer >= 0; got {max_iter!r:.80}")
    return float(tol), int(max_iter)


def check_finite(t: float, what: str, *arrays: np.ndarray | sps.spmatrix) -> None:
    """A NaN or infinity computed at a state is a :class:`StateError` naming ``what`` and t.

    NumPy kernels overflow to infinity (with a warning) where Python's math raises: the values a
    single-state call returns, or feeds to a solve, are checked here.
    """
    for a in arrays:
        data = a.data if sps.issparse(a) else a
        if not np.isfinite(data).all():
            raise StateError(
                f"{what} is NaN or infinite at t = {t:.17g}: the equations overflowed the "
                "floating-point range or divided by zero there"
            )
