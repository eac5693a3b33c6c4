"""Compile stage, small systems: the machine code of the compiled stepping loop besides the rhs.

The compiled loop (:mod:`pfaff.integrate.loop`) steps DOP853, projects every step onto the
constraints and integrates the work of the applied forces without returning to Python. The
right-hand side is the fused kernel's machine code (:func:`pfaff.derive.fused.build_fused`);
this module compiles the two other functions the loop calls, with SymEngine's LLVM backend, on
the same flat input ``x = [t, q, q̇, params]`` (the first ``1 + 2n + len(params)`` entries of the
right-hand side's):

``con``
    ``[M entries, A entries, b, f]``: the fused kernel's outputs that the projection needs (the
    mass-metric correction M⁻¹Aᵀ(A M⁻¹Aᵀ + δ²I)⁻¹ r is computed from them in the loop), in the
    order of the kernel's ``mass`` and ``acon`` patterns; None without constraints.
``power``
    ``[P]``, P = Qᵀq̇ the power of the applied forces (:mod:`pfaff.derive.fusedpower`); None
    without applied forces.

Both are made on first use and kept in memory and in the on-disk cache
(:func:`pfaff.derive.machine_kernel.cached_machine`), as the right-hand side is.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import symengine

from pfaff.derive.machine_kernel import cached_machine

if TYPE_CHECKING:
    from collections.abc import Callable

LoopParts = tuple[list, int, object, list]  # kernel outputs, len(mass) + len(acon), P, args


def loop_factory(
    n: int, m: int, key: str | None, parts: Callable[[], LoopParts]
) -> Callable[..., tuple | None]:
    """``make(build=True) -> (con, power)``: the loop's machine code (module docstring), built on
    the first call from ``parts()`` = (the fused kernel's outputs ``[M, A, Q − h, −(Ȧq̇ + ḃ), b,
    f]``, the number of M and A entries, the power expression or None, the arguments ``_t, _y…,
    _p…``), then cached; ``make(build=False)`` only loads it from the cache.

    Examples
    --------
    >>> import symengine as se
    >>> t, x, v, p = (se.Symbol(s) for s in ("_t", "_y0", "_y1", "_p0"))
    >>> outs = [p, x, -p * se.sin(x), 0 * x, v * x, x - 1]  # M, A, Q - h, -bias, b, f (n = m = 1)
    >>> con, power = loop_factory(1, 1, None, lambda: (outs, 2, p * v, [t, x, v, p]))()
    >>> con([0.0, 2.0, 0.5, 3.0]).tolist(), power([0.0, 2.0, 0.5, 3.0]).tolist()
    ([3.0, 2.0, 1.0, 1.0], [1.5])
    """
    return cached_machine(key, "loop", lambda: _loop_functions(n, m, *parts()))


def _loop_functions(
    n: int, m: int, exprs: list, entries: int, power: object, args: list
) -> tuple[Callable | None, Callable | None]:
    se = symengine
    inputs = [se.Symbol(str(a)) for a in args]  # _t, _y…, _p…
    outs = [se.sympify(e) for e in exprs]
    con = None
    if m:
        rows = outs[:entries] + outs[entries + n + m :]  # M, A, then b and f
        con = se.Lambdify(inputs, rows, backend="llvm", cse=True, real=True)
    pfn = None
    if power is not None:
        pfn = se.Lambdify(inputs, [se.sympify(power)], backend="llvm", cse=True, real=True)
    return con, pfn
