"""What a general model hands the compiled stepping loop: machine code and its fixed inputs.

The compiled loop (:mod:`pfaff.integrate.loop`) calls three functions made by SymEngine's LLVM
backend, through their C entry points, never through Python: the right-hand side of the fused
kernel (``FusedKernel.llvm``: [q̇, q̈, λ, the kernel's outputs] of ``[t, q, q̇, params, α, β,
τ…, cap]``, with the floored range-space solve), and ``con`` and ``power`` of
:mod:`pfaff.derive.loopcode` (on ``[t, q, q̇, params]``). :func:`machine_loop` says whether a run
of a model can use them, exactly as the Python path would run it: the model's fused kernel
with its generated solve (the same floor, the same reference row sizes), M positive definite
and the constraints independent at the start, no inputs and no stabilization; each function is
checked against the generated Python code at a random state before it is used.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pfaff.numeric.field import AccelerationField
from pfaff.numeric.kkt import FLOOR

if TYPE_CHECKING:
    from collections.abc import Callable

    from pfaff.numeric.model import NumericModel


@dataclass(frozen=True)
class LoopCode:
    """The machine code of one run and its buffers (see the module docstring).

    Attributes
    ----------
    functions : ndarray of int64, shape (6,)
        The C entry point and its ``user_data`` of ``rhs``, ``con`` and ``power`` (0 for a
        function the run does not need): ``f(double *out, const double *in, void *data)``.
    rhs_in : ndarray, shape (1 + 2n + len(params) + 2 + m + 1,)
        The right-hand side's input with its fixed tail (params, α = β = 0, τ, cap) set.
    con_in : ndarray, shape (1 + 2n + len(params),)
        The input of ``con`` and ``power`` with the parameters set.
    rhs_size, con_size : int
        Their output lengths.
    mass, acon : ndarray of int64, shape (k, 2)
        (i, j) of each M entry (upper triangle) and each A entry, in ``con``'s output order.
    holonomic : ndarray, shape (m,)
        1.0 for a position-level row, 0.0 for a velocity-level one.
    keep : tuple
        The compiled objects, kept alive while their entry points are in use.
    """

    functions: np.ndarray
    rhs_in: np.ndarray
    con_in: np.ndarray
    rhs_size: int
    con_size: int
    mass: np.ndarray
    acon: np.ndarray
    holonomic: np.ndarray
    keep: tuple


def entry_point(fn: Callable | None) -> tuple[int, int]:
    """(address, user_data) of a SymEngine LLVM function's C entry point; (0, 0) for None.

    Examples
    --------
    >>> import symengine as se
    >>> x = se.Symbol("x")
    >>> address, data = entry_point(se.Lambdify([x], [2 * x], backend="llvm"))
    >>> address > 0 and data > 0, entry_point(None)
    (True, (0, 0))
    """
    if fn is None:
        return 0, 0
    cfunc, data = fn.as_ctypes()  # type: ignore[attr-defined]
    return int(ctypes.cast(cfunc, ctypes.c_void_p).value or 0), int(data.value or 0)


def machine_loop(model: NumericModel, field: AccelerationField) -> tuple[LoopCode | None, str]:
    """The loop's machine code for a run of ``model`` on ``field`` (its ODE function), or None
    and the reason it does not apply.

    Parameters
    ----------
    model : NumericModel
        A run copy (``model.for_run()``), after ``check_determined`` at the run's first state.
    field : AccelerationField
        ``model.ode_function(start=...)``: its reference row sizes set the floor's τ.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> m = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> run = m.for_run()
    >>> code, why = machine_loop(run, run.ode_function(start=(0.0, np.array([1.0, 0.0]), np.zeros(2))))
    >>> code.mass.tolist(), code.acon.tolist(), code.rhs_size, why  # M diagonal, A = [2x, 2y]
    ([[0, 0], [1, 1]], [[0, 0], [0, 1]], 17, '')
    >>> machine_loop(run, run.ode_function(alpha=10.0, beta=10.0))[1]  # Baumgarte
    'the run stabilizes, rescales the floor, or has inputs'
    """
    if type(field) is not AccelerationField:
        return None, "the run's ODE function is not the model's own"
    fk, run = model._fused, model._run_state
    if fk is None or not fk.solves or fk.rfn is None or fk.loop is None:
        return None, "the model has no generated right-hand side with its solve"
    if run["full"] or run["rows"] is not None or run["live"]:
        return None, "M is singular, the constraints redundant, or inputs drive the run"
    if field.alpha or field.beta or field.active or field.before is not None:
        return None, "the run stabilizes, rescales the floor, or has inputs"
    mc = model._machine_code
    rhs = mc.get(model._machine_agrees) if mc is not None and mc.available else None
    if rhs is None:
        return None, "no machine code for the right-hand side"
    try:
        con, power = fk.loop()
    except Exception as e:  # SymEngine could not compile it: the Python path
        return None, f"the loop's machine code could not be made ({type(e).__name__})"
    n, m, p = model.n, model.m, list(model._p)
    if (m and con is None) or (model.applied_power and power is None):
        return None, "the loop's machine code is incomplete"
    scales = field.scales
    taus = [0.0] * m if scales is None else (FLOOR * np.asarray(scales)).tolist()
    cap = FLOOR if scales is not None else 0.0
    rhs_in = np.array([0.0] * (1 + 2 * n) + p + [0.0, 0.0, *taus, cap])
    con_in = np.array([0.0] * (1 + 2 * n) + p)
    power = power if model.applied_power else None
    reason = _disagrees(model, con if m else None, power, con_in)
    if reason:
        return None, reason
    o = fk.offsets
    points = [*entry_point(rhs), *entry_point(con if m else None), *entry_point(power)]
    code = LoopCode(
        np.array(points, dtype=np.int64), rhs_in, con_in, len(rhs(rhs_in)),
        o[0] + 2 * m if m else 0,
        np.array(_mass_pattern(fk.entry_index, n + m, n), dtype=np.int64).reshape(-1, 2),
        np.array(list(zip(fk.arows, fk.acols, strict=True)), dtype=np.int64).reshape(-1, 2),
        np.asarray(model.holonomic, dtype=float), (rhs, con, power),
    )  # fmt: skip
    return code, ""


def _mass_pattern(entries: np.ndarray, N: int, n: int) -> list:
    """(i, j) of the M entries among the kernel's entries (``entry_index`` = i·N + j, the M
    entries first, then A's with rows below n)."""
    return [(int(e) // N, int(e) % N) for e in entries.tolist() if int(e) // N < n]


def _disagrees(
    model: NumericModel, con: Callable | None, power: Callable | None, x: np.ndarray
) -> str:
    """ "" when ``con`` and ``power`` agree with the generated Python code at a random state."""
    fk, n = model._fused, model.n
    assert fk is not None
    rng = np.random.default_rng(13)
    t, q, qd = 0.37, rng.uniform(0.2, 0.9, n), rng.uniform(-0.5, 0.5, n)
    x = x.copy()
    x[0], x[1 : 1 + n], x[1 + n : 1 + 2 * n] = t, q, qd
    args = (t, *q.tolist(), *qd.tolist(), *model._p)
    try:
        if con is not None:
            v = np.array(fk.fn(*args), dtype=float)
            o = fk.offsets
            want = np.concatenate([v[: o[0]], v[o[2] :]])
            if not np.allclose(np.asarray(con(x)), want, rtol=1e-11, atol=1e-13):
                return "the loop's constraint code disagrees with the generated Python code"
        if power is not None:
            want = float(fk.pfn(*args)[0])  # type: ignore[misc]
            if not np.isclose(float(np.asarray(power(x))[0]), want, rtol=1e-11, atol=1e-13):
                return "the loop's power code disagrees with the generated Python code"
    except (ValueError, ArithmeticError, TypeError) as e:
        return f"the loop's machine code could not be checked ({type(e).__name__})"
    return ""
