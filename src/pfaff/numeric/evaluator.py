"""How a general model evaluates a state: one of three evaluators, chosen by rule.

``"template"``
    The template kernels (:class:`pfaff.numeric.kernel.StreamKernel`, NumPy over index arrays)
    and a LAPACK solve: every model has them.
``"python"``
    The fused kernel (:class:`pfaff.numeric.fused.FusedKernel`): the whole system as one
    generated Python function on floats, and the range-space solve as generated code.
``"machine"``
    The same right-hand side compiled to machine code by SymEngine's LLVM (built on first use,
    kept in the on-disk cache).

The rule (:func:`choose`): the template kernels where there is no fused kernel (too large, a
solver other than ``range-space``, or a function the printer cannot write); else machine code
from :data:`MACHINE_FROM` unknowns n + m on (up to :data:`MACHINE_LIMIT`; above
``FUSED_LIMIT`` it is the kernel alone, solved with LAPACK or, without constraints, in one
compiled call with the kernel (:mod:`pfaff.numeric.kernelchol`, LLVM's JIT through llvmlite), its LLVM optimization level by
:func:`machine_opt_level`), where one call of it beats the generated Python: through the
unchecked entry point into a preallocated array (:func:`preallocated`) the machine-code right-hand
side of the chain on a cart costs 2.3, 2.4, 2.7 and 2.8 µs at n + m = 3, 4, 5 and 6 against
2.2, 3.5, 5.3 and 7.7 µs in generated Python (1.0 against 2.1 µs on a pendulum; measured on
this project's busy machine), so machine code from n + m = 4 on (through SymEngine's checked
call, 17–20 µs, it paid only from 8 on);
or from :data:`MACHINE_OPS` operations in the kernel's generated code (a spatial 6R arm of six
unknowns: 1700 operations, 90 µs per right-hand side in generated Python against 14 µs in
machine code; a cart with 4 links, 250 operations, 13 µs either way, ``benchmarks/engines.py``);
else the generated Python. No timing decides anything at run time: the same model, state and
options take the same path in every process. ``compile(..., evaluator=...)`` overrides the rule.
Machine code is compiled on a model's first evaluation (0.15 s for an 8-link chain, 0.8 s for the
Whipple bicycle, measured here) and kept in the on-disk cache, so later processes load it in
milliseconds; ``compile_machine_code()`` switches a model to machine code now (and so moves that
cost to a moment of the user's choosing).
"""

from __future__ import annotations

import math
import threading
import warnings
from collections.abc import Callable

import numpy as np

from pfaff.core.errors import OptionError
from pfaff.core.stack import outside_pfaff

EVALUATORS = ("template", "python", "machine")
MACHINE_FROM = 4  # n + m from which machine code is the default evaluator
MACHINE_OPS = 500  # operations of the fused kernel from which machine code is, at any n + m
OPTIMIZED_LIMIT = 72  # n + m up to which LLVM optimizes the machine code (opt_level 2)
MACHINE_LIMIT = 72  # n + m up to which the fused kernel is compiled to machine code at all


def machine_opt_level(n: int, m: int) -> int | None:
    """SymEngine's LLVM ``opt_level`` for the machine code of a system of n + m unknowns, or None
    where none is made: the compile time of the kernel alone grows faster than its size. Its
    sums of parameters grouped and split into functions of at most 512 outputs
    (:mod:`pfaff.derive.machine_kernel`), the kernel of the chain on a cart compiles at level 2
    in 1.1 s at 33 unknowns, 4.1 s at 65 and 5.8 s at 72 (CPU seconds on this project's busy
    2-core machine; 11.3 s at 65 as one function, and before the grouping 2.5 s at 33 and 9.8 s
    at 41), so the optimizer runs up to :data:`OPTIMIZED_LIMIT` (once: the result is cached on
    disk), level 0 up to :data:`MACHINE_LIMIT`, and above that the model keeps the generated
    Python kernel (a rule on the sizes, never a timing).

    Examples
    --------
    >>> machine_opt_level(33, 0), machine_opt_level(64, 1), machine_opt_level(100, 0)
    (2, 2, None)
    """
    size = n + m
    if size > MACHINE_LIMIT:
        return None
    return 2 if size <= OPTIMIZED_LIMIT else 0


def choose(
    requested: str | None,
    n: int,
    m: int,
    has_fused: bool,
    why_not: str,
    has_machine: bool,
    ops: int = 0,
) -> str:
    """The evaluator of a model: ``requested`` if it is possible, else the rule's.

    Parameters
    ----------
    requested : {None, "template", "python", "machine"}
    n, m : int
        Coordinates and constraints.
    has_fused : bool
        Whether the model has a fused kernel; ``why_not`` says why not.
    has_machine : bool
        Whether the fused kernel can be compiled to machine code (SymEngine has LLVM).
    ops : int
        Operations in the fused kernel's generated code (:attr:`FusedKernel.ops`): from
        :data:`MACHINE_OPS` on, machine code at any n + m.

    Examples
    --------
    >>> choose(None, 1, 0, True, "", True), choose(None, 6, 3, True, "", True)
    ('python', 'machine')
    >>> choose("template", 6, 3, True, "", True)
    'template'
    >>> choose(None, 6, 0, True, "", True, ops=1700)  # a spatial 6R arm of point masses
    'machine'
    """
    if requested is not None and requested not in EVALUATORS:
        raise OptionError(
            f"`evaluator` must be one of {', '.join(EVALUATORS)}; got {requested!r:.80}"
        )
    if requested == "template":
        return "template"
    if not has_fused:
        if requested is not None:
            raise OptionError(f"`evaluator`: {requested!r} needs the fused kernel, and {why_not}")
        return "template"
    if requested == "machine" and not has_machine:
        raise OptionError("`evaluator`: 'machine' needs SymEngine built with LLVM, and it is not")
    if requested is not None:
        return requested
    big = n + m >= MACHINE_FROM or ops >= MACHINE_OPS
    return "machine" if has_machine and big else "python"


class MachineCode:
    """The machine code of a fused kernel, made once (on first use) and shared by every model
    built from the same parts (``with_parameters`` copies, run copies, unpickled copies).

    ``get()`` returns the compiled function, or None after warning once with the reason (the
    model then evaluates with the generated Python).
    """

    def __init__(self, build: Callable[[], Callable | None] | None) -> None:
        self._build = build
        self._lock = threading.Lock()
        self._done = False
        self.compiled: Callable | None = None
        self.seconds = 0.0

    @property
    def available(self) -> bool:
        """Whether it can give machine code: a compiler to build it, or the code itself."""
        return self._build is not None or self.compiled is not None

    def get(self, check: Callable[[Callable], str]) -> Callable | None:
        """The compiled function, checked once by ``check`` (returns "" when it agrees)."""
        if self._done:
            return self.compiled
        with self._lock:
            if not self._done:
                self.compiled = self._make(check)
                self._done = True
        return self.compiled

    def _make(self, check: Callable[[Callable], str]) -> Callable | None:
        import time

        start = time.process_time()
        reason = ""
        compiled = None
        if self._build is None:
            reason = "SymEngine has no LLVM"
        else:
            try:
                compiled = self._build()
            except Exception as e:
                reason = f"{type(e).__name__}: {str(e)[:200]}"
            if compiled is None and not reason:
                reason = "SymEngine could not compile it"
            if compiled is not None:
                reason = check(compiled)
        self.seconds = time.process_time() - start
        if reason:
            warnings.warn(
                f"pfaff: machine code unavailable ({reason}); evaluating with the generated "
                "Python code instead",
                RuntimeWarning,
                stacklevel=outside_pfaff(),
            )
            return None
        return compiled

    def __getstate__(self) -> dict:
        return {"compiled": self.compiled if self._done else None, "done": self._done}

    def __setstate__(self, state: dict) -> None:
        self._build, self._lock, self.seconds = None, threading.Lock(), 0.0
        self.compiled, self._done = state["compiled"], state["done"]


def preallocated(compiled: Callable, buf: np.ndarray) -> Callable[[], np.ndarray]:
    """``call() -> out``: ``compiled(buf)`` written into one array allocated here, through the
    unchecked entry point of SymEngine's LLVM functions (``unsafe_real``: no argument checks,
    no new array; about 1 µs a call of a small function against 8 µs through ``compiled(buf)``,
    measured on this project's machine); ``compiled(buf)`` where there is no such entry point.
    ``buf`` (float64, contiguous) is the input the caller refills; ``out`` is overwritten by the
    next call.

    Examples
    --------
    >>> call = preallocated(lambda x: 2.0 * x, np.array([1.0, 3.0]))
    >>> call().tolist()
    [2.0, 6.0]
    """
    fast = getattr(compiled, "unsafe_real", None)
    if fast is None:
        return lambda: compiled(buf)
    out = np.empty(len(compiled(buf)))

    def call() -> np.ndarray:
        fast(buf, out)
        return out

    return call


def machine_rhs(
    compiled: Callable, py: Callable, n: int, fixed: list, live: list | None = None
) -> Callable:
    """The machine-code right-hand side on lists, ``py`` (the generated Python) where it gives
    anything non-finite (M not positive definite, a value out of its domain: ``py`` then takes
    the slow path or names the error). The compiled function's first 2n outputs are [q̇, q̈].
    ``fixed`` = [params, alpha, beta, taus, cap]; ``live``: a run's parameter vector, read at
    every call (inputs change it during a run)."""
    buf = np.zeros(1 + 2 * n + len(fixed))
    buf[1 + 2 * n :] = fixed
    isfinite = math.isfinite
    k = 2 * n
    p0, p1 = 1 + 2 * n, 1 + 2 * n + (len(live) if live is not None else 0)
    call = preallocated(compiled, buf)

    def rhs(t: float, yl: list) -> list:
        buf[0] = t
        buf[1 : 1 + 2 * n] = yl
        if live is not None:
            buf[p0:p1] = live
        out = call()[:k].tolist()
        return out if isfinite(sum(out)) else py(t, yl)

    return rhs
