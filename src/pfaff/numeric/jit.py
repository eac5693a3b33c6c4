"""numba's compilation of pfaff's own loops over long arrays, on first use, or None without it.

The streaming passes of the largest models (sin and cos of a family's angles,
:mod:`pfaff.numeric.trigjit`; DOP853's stage sums, :mod:`pfaff.integrate.inplacejit`) are loops
that NumPy runs as many passes with temporaries. :func:`compiled` compiles such a loop with numba
(``nogil``: the kernel threads run it side by side; numba's on-disk cache beside the module, or
numba's user-wide folder when that is read-only, or ``NUMBA_CACHE_DIR``) the first time it is
asked for, in the asking process, and gives None where numba is missing or fails, or with
``PFAFF_JIT=0``: the caller then keeps its NumPy passes, whose results agree to rounding.
numba is imported only then (about 0.2 s of CPU; loading a cached loop about 0.05 s).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable

from pfaff.core.held import signals_held

_LOCK = threading.Lock()
_DONE: dict[str, Callable | None] = {}  # per loop (module.name): compiled, or None


def enabled() -> bool:
    """False with ``PFAFF_JIT=0`` (or false, no, off): every loop stays in NumPy.

    Examples
    --------
    >>> import os
    >>> enabled() == (os.environ.get("PFAFF_JIT", "1") not in ("0", "false", "no", "off"))
    True
    """
    return os.environ.get("PFAFF_JIT", "1").strip().lower() not in ("0", "false", "no", "off")


def compiled(fn: Callable, *warm: tuple) -> Callable | None:
    """``fn`` compiled by numba (once per process), or None (numba missing or failing, or
    ``PFAFF_JIT=0``).

    Parameters
    ----------
    fn : callable
        A module-level function numba can compile in nopython mode.
    *warm : tuple
        Argument tuples it is called with once now, so that it is compiled (or loaded from the
        cache) here, on the asking thread, for those types, and not inside a later call.

    Examples
    --------
    >>> import numpy as np
    >>> def twice(x, out):
    ...     for i in range(x.shape[0]):
    ...         out[i] = 2.0 * x[i]
    >>> f = compiled(twice, (np.zeros(1), np.zeros(1))) or twice
    >>> out = np.zeros(3)
    >>> f(np.arange(3.0), out)
    >>> out.tolist()
    [0.0, 2.0, 4.0]
    """
    if not enabled():
        return None
    key = f"{fn.__module__}.{fn.__qualname__}"
    with _LOCK:
        if key not in _DONE:
            with signals_held():  # numba could swallow a Ctrl-C while it loads
                _DONE[key] = _compile(fn, warm)
    return _DONE[key]


def _compile(fn: Callable, warm: tuple) -> Callable | None:
    try:
        from numba import njit
    except ImportError:
        return None
    try:
        from pfaff.numeric.numbacode import fresh

        try:
            out = fresh(njit(cache=True, nogil=True, error_model="numpy")(fn))
        except RuntimeError:  # no folder for numba's cache: compiled in this process only
            out = njit(nogil=True, error_model="numpy")(fn)
        for args in warm:
            out(*args)
        return out
    except Exception:  # numba could not compile it: the caller's NumPy passes
        return None
