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
import time
from collections.abc import Callable
from types import ModuleType

from pfaff.core.held import signals_held

_LOCK = threading.Lock()
_DONE: dict[str, Callable | None] = {}  # per loop (module.name): compiled, or None
_MODULES_LOCK = threading.RLock()
_MODULES: dict[str, tuple[ModuleType | None, str, float]] = {}  # per module: see loaded()


def enabled() -> bool:
    """False with ``PFAFF_JIT=0`` (or false, no, off): every loop stays in NumPy.

    Examples
    --------
    >>> import os
    >>> enabled() == (os.environ.get("PFAFF_JIT", "1") not in ("0", "false", "no", "off"))
    True
    """
    return os.environ.get("PFAFF_JIT", "1").strip().lower() not in ("0", "false", "no", "off")


def compiled(fn: Callable, *warm: tuple, contract: bool = False) -> Callable | None:
    """``fn`` compiled by numba (once per process), or None (numba missing or failing, or
    ``PFAFF_JIT=0``).

    Parameters
    ----------
    fn : callable
        A module-level function numba can compile in nopython mode.
    *warm : tuple
        Argument tuples it is called with once now, so that it is compiled (or loaded from the
        cache) here, on the asking thread, for those types, and not inside a later call.
    contract : bool
        Let LLVM fuse a multiplication and an addition into one multiply-add where the CPU has
        one (numba's ``fastmath={"contract"}``, no other fast-math licence): one rounding
        instead of two, so results differ from the unfused loop's in the last bit, the same
        from run to run on one machine.

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
                _DONE[key] = _compile(fn, warm, contract)
    return _DONE[key]


def _compile(fn: Callable, warm: tuple, contract: bool) -> Callable | None:
    try:
        from pfaff.numeric.numbacode import cached
    except ImportError:
        return None
    try:
        out = cached(fn, nogil=True, **({"fastmath": {"contract"}} if contract else {}))
        for args in warm:
            out(*args)
        return out
    except Exception:  # numba could not compile it: the caller's NumPy passes
        return None


def loaded(
    name: str, load: Callable[[], ModuleType], needs: str = "numba"
) -> tuple[ModuleType | None, str, float]:
    """A module of compiled code (numba's, or llvmlite's JIT), imported and warmed by ``load()``
    once per process with Ctrl-C and SIGTERM held (a compiler could swallow them): (the module,
    "", CPU seconds), or (None, why, CPU seconds) where its compiler is missing or fails (the
    caller then keeps its other path).

    Parameters
    ----------
    name : str
        The key of this module (the same ``load`` each time).
    load : callable
        Imports the module and compiles its functions (or loads them from numba's cache) for
        the argument types of its callers; returns the module.
    needs : str
        The compiler it needs, named where ``load`` cannot import (default ``"numba"``).

    Examples
    --------
    >>> import math
    >>> loaded("math", lambda: math)[:2] == (math, "")
    True
    >>> loaded("nothing", lambda: __import__("no_such_module"))[:2]
    (None, 'numba is not installed')
    """
    with _MODULES_LOCK:
        if name not in _MODULES:
            start = time.process_time()
            with signals_held():
                try:
                    module, why = load(), ""
                except ImportError:
                    module, why = None, f"{needs} is not installed"
                except Exception as e:  # the compiler could not compile it
                    module, why = None, f"compiling failed ({type(e).__name__}: {str(e)[:120]})"
            _MODULES[name] = (module, why, time.process_time() - start)
        return _MODULES[name]
