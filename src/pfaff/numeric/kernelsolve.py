"""The right-hand side of a mid-size model: its machine-code kernel and a LAPACK solve.

Above ``FUSED_LIMIT`` unknowns the machine code is the fused kernel alone
(:mod:`pfaff.derive.machine_kernel`): :func:`kernel_rhs` fills one preallocated augmented
matrix from its outputs and solves it by the range-space method with the floor
(:func:`pfaff.numeric.kkt.solve_floored`, the algorithm of the model's ``range-space`` solver),
without the assembly of :meth:`pfaff.NumericModel._kkt` (a new matrix per call, the velocity
residual). Without constraints, M q̈ = Q − h is one compiled call where llvmlite is installed
(:mod:`pfaff.numeric.kernelchol`: the kernel's LLVM functions through their C entry points and
the Cholesky solve in loops compiled by LLVM's JIT; the 32-link chain on a cart, 33 unknowns, about 1.0×
Pinocchio's ``aba``, ``benchmarks/engines.py``), else one in-place Cholesky solve on the kernel's
outputs by SciPy's LAPACK (``dppsv`` in packed storage, or ``dposv``; about 1.3–1.6× ``aba``),
the kernel called through its unchecked entry point into a preallocated array
(:func:`pfaff.numeric.evaluator.preallocated`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from pfaff.numeric.evaluator import preallocated
from pfaff.numeric.jit import loaded
from pfaff.numeric.kkt import solve_floored
from pfaff.numeric.machineloop import entry_point

_posv = scipy.linalg.lapack.dposv
_ppsv = scipy.linalg.lapack.dppsv
PACKED_LIMIT = 48  # n up to which a dense M is solved in packed storage (``dppsv``)

if TYPE_CHECKING:
    from pfaff.numeric.fused import FusedKernel


def kernel_rhs(
    fk: FusedKernel,
    compiled: Callable,
    n: int,
    fixed: list,
    live: list | None,
    solve: tuple[float, float, float, np.ndarray | None],
    slow: Callable[[float, list], list],
    stats: dict,
) -> Callable[[float, list], list]:
    """``rhs(t, y: list) -> [q̇, q̈]`` (a list) from the machine-code kernel ``compiled``.

    Parameters
    ----------
    fk : FusedKernel
        The kernel's layout (``kkt_index``, ``kkt_source``, ``offsets``).
    compiled : callable
        ``compiled(x) -> fn's outputs`` on ``x = [t, q, q̇, *fixed]``.
    n : int
        Coordinates.
    fixed : list
        [params, alpha, beta, taus, cap]: the rest of ``x``.
    live : list or None
        A run's parameter vector, read at every call (inputs change it), or None.
    solve : tuple
        (alpha, beta, floor, scales) of the constraint rows and the rank-loss floor.
    slow : callable
        The model's array path, taken where the kernel is not finite or M is not positive
        definite (it names the error or takes the LU solve).
    stats : dict
        The model's counters (``kkt_solves``).

    Examples
    --------
    A unit mass on a spring, M = [1], Q − h = −q, with the layout of a one-coordinate kernel:

    >>> from pfaff.numeric.fused import FusedKernel
    >>> fk = FusedKernel(None, None, None, None, None, np.array([0]), np.array([0]),
    ...                  np.array([0]), (1, 2, 2, 2), (), ())
    >>> def kernel(x):
    ...     return np.array([1.0, -x[1]])
    >>> rhs = kernel_rhs(fk, kernel, 1, [0.0, 0.0, 0.0], None, (0.0, 0.0, 0.0, None),
    ...                  None, {"kkt_solves": 0})
    >>> rhs(0.0, [0.5, 2.0])
    [2.0, -0.5]
    """
    o0, o1, o2, o3 = fk.offsets
    m = o2 - o1  # constraint rows: the −(Ȧq̇ + ḃ) block
    N = n + m
    buf = np.zeros(1 + 2 * n + len(fixed))
    buf[1 + 2 * n :] = fixed
    p0, p1 = 1 + 2 * n, 1 + 2 * n + (len(live) if live is not None else 0)
    call = preallocated(compiled, buf)

    def load(t: float, yl: list) -> np.ndarray:
        buf[0] = t
        buf[1 : 1 + 2 * n] = yl
        if live is not None:
            buf[p0:p1] = live
        return call()

    if not m:
        compiled_call = _compiled_rhs(fk, compiled, n, buf, live, slow, stats)
        if compiled_call is not None:
            return compiled_call
        return _cholesky_rhs(fk, load, n, slow, stats)
    K = np.zeros((N, N))
    flat = K.reshape(-1)  # a view: the pattern's entries are refilled, the rest stays zero
    index, source = fk.kkt_index, fk.kkt_source
    alpha, beta, floor, scales = solve
    M, A = K[:n, :n], K[n:, :n]
    isfinite = math.isfinite

    def rhs(t: float, yl: list) -> list:
        v = load(t, yl)
        flat[index] = v[source]
        c = v[o1:o2]
        if alpha:
            c = c - 2.0 * alpha * (A @ buf[1 + n : 1 + 2 * n] + v[o2:o3])
        if beta:
            c = c - beta * beta * v[o3:]
        try:
            qdd = solve_floored(M, A, v[o0:o1], c, floor, scales)[0].tolist()
        except np.linalg.LinAlgError:  # M not positive definite: the array path decides
            return slow(t, yl)
        stats["kkt_solves"] += 1
        out = yl[n:] + qdd
        return out if isfinite(sum(qdd)) else slow(t, yl)

    return rhs


def _compiled_rhs(
    fk: FusedKernel,
    compiled: Callable,
    n: int,
    buf: np.ndarray,
    live: list | None,
    slow: Callable[[float, list], list],
    stats: dict,
) -> Callable[[float, list], list] | None:
    """:func:`kernel_rhs` without constraints as one compiled call
    (:func:`pfaff.numeric.kernelchol.kernel_cholesky`: the kernel's LLVM functions through
    their C entry points, then the Cholesky solve in compiled loops); the array path where M is
    not positive definite or q̈ is not finite. None where llvmlite is not installed or
    ``compiled`` has no C entry points (then :func:`_cholesky_rhs`)."""
    functions = _entry_points(compiled)
    module = compiled_solver()[0] if functions is not None else None
    if module is None or functions is None:
        return None
    solver = module.compile_solver()
    plan, work = module.plan_of(functions, fk.entry_index, n, int(compiled.offsets[-1]))
    done = work[work.size - 2 * n :]
    p0, p1 = 1 + 2 * n, 1 + 2 * n + (len(live) if live is not None else 0)
    pa, xa, wa = plan.ctypes.data, buf.ctypes.data, work.ctypes.data  # (kept alive below)

    def rhs(t: float, yl: list) -> list:
        buf[0] = t
        buf[1 : 1 + 2 * n] = yl
        if live is not None:
            buf[p0:p1] = live
        if solver(pa, xa, wa) == 0:
            stats["kkt_solves"] += 1
            return done.tolist()
        return slow(t, yl)

    rhs.keep = (compiled, plan, buf, work)  # type: ignore[attr-defined]  # (their addresses)
    rhs.compiled_solve = compiled_solver()[1]  # type: ignore[attr-defined]
    return rhs


def compiled_solver() -> tuple[ModuleType | None, float]:
    """:mod:`pfaff.numeric.kernelchol` with its function compiled by LLVM's JIT (once per
    process, :func:`pfaff.numeric.jit.loaded`: 0.1–0.25 s), or None where llvmlite is missing or
    fails (the model then solves with SciPy's LAPACK wrappers); and the CPU seconds that took
    (``timings["compiled_solve"]``)."""
    module, _, seconds = loaded("kernelchol", _load_kernelchol, needs="llvmlite")
    return module, seconds


def _load_kernelchol() -> ModuleType:
    from pfaff.numeric import kernelchol

    kernelchol.compile_solver()
    return kernelchol


def _entry_points(compiled: Callable) -> list[tuple[int, int, int]] | None:
    """(address, data, offset) of each LLVM function of a :class:`SplitKernel`, or None."""
    parts, offsets = getattr(compiled, "parts", None), getattr(compiled, "offsets", None)
    if parts is None or offsets is None:
        return None
    out = []
    for part, offset in zip(parts, offsets):  # noqa: B905 - one more offset
        if not hasattr(part, "as_ctypes"):
            return None
        out.append((*entry_point(part), int(offset)))
    return out


def _cholesky_rhs(
    fk: FusedKernel,
    load: Callable[[float, list], np.ndarray],
    n: int,
    slow: Callable[[float, list], list],
    stats: dict,
) -> Callable[[float, list], list]:
    """:func:`kernel_rhs` without constraints: M q̈ = Q − h by one LAPACK call, the Cholesky
    factorization in place; the array path where M is not positive definite or q̈ is not
    finite. Where M's pattern is its whole upper triangle row by row (a chain's) and n is at
    most :data:`PACKED_LIMIT`, the kernel's outputs already are M in LAPACK's packed storage
    (column-major lower = row-major upper) and ``dppsv`` solves on them with no copy (33
    unknowns: 8.1 µs against 10.4 µs for the matrix form; equal at 65, where the blocked
    ``dposv`` on the full matrix is as fast); else M's upper triangle is written from the
    outputs (``entry_index``) into a matrix zeroed each call (the last factor's fill-in where M
    has structural zeros) for ``dposv``."""
    o0 = fk.offsets[0]
    upper = fk.entry_index
    rows, cols = np.triu_indices(n)
    isfinite = math.isfinite
    if n <= PACKED_LIMIT and np.array_equal(upper, rows * n + cols):

        def solve(v: np.ndarray) -> tuple[np.ndarray, int]:
            return _ppsv(n, v[:o0], v[o0 : o0 + n], lower=1, overwrite_b=1)

    else:
        W = np.zeros((n, n))
        wflat = W.reshape(-1)

        def solve(v: np.ndarray) -> tuple[np.ndarray, int]:
            W.fill(0.0)
            wflat[upper] = v[:o0]
            # W.T in Fortran order, its lower triangle W's upper one
            return _posv(W.T, v[o0 : o0 + n], lower=1, overwrite_a=1, overwrite_b=1)[1:]

    def rhs(t: float, yl: list) -> list:
        x, info = solve(load(t, yl))
        qdd = x.ravel().tolist()
        if info == 0 and isfinite(sum(qdd)):
            stats["kkt_solves"] += 1
            return yl[n:] + qdd
        return slow(t, yl)

    return rhs
