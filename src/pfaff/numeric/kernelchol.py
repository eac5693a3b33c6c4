"""The right-hand side of a mid-size model without constraints as one compiled call (numba).

Imported only by :func:`pfaff.numeric.kernelsolve.kernel_rhs`, and only where numba is
installed (else the model solves with SciPy's LAPACK wrappers, as before). :func:`kernel_cholesky`
calls the machine-code kernel's LLVM functions through their C entry points
(:func:`pfaff.numeric.machineloop.entry_point`), writes M's upper triangle from the kernel's
outputs, and solves M q̈ = Q − h by the Cholesky factorization M = UᵀU in compiled loops: no
return to Python between the kernel, the factorization and the two triangular solves.

Why not LAPACK: at these sizes SciPy's ``dppsv`` is the factorization's level-2 BLAS calls, one
per column, behind the wrapper's argument checks; the loops here, their indices unsigned so
that LLVM vectorizes the row updates, write M from the outputs, factor and solve it in 5.6 µs
at 33 unknowns against 7.6 µs for ``dppsv`` on the packed outputs (49: 11.5 against 14.7 µs;
65: 21.7 against 25.5 µs; CPU medians, interleaved, on this project's machine at load 7). The
whole right-hand side of the 32-link chain on a cart went from 19.4–29.6 to 14.3–15.4 µs
(``benchmarks/engines.py``, two runs each at load 7: about 1.0× Pinocchio's ``aba`` instead of
1.3–1.65×), below the 31-link chain's fused machine code (18.8 µs timed together: the step at
the fused limit is ×0.73 instead of ×1.08). The algorithm is LAPACK's unblocked ``dpotf2``
(right-looking, the pivot's reciprocal scaling its row), in IEEE arithmetic (no fast-math):
the results agree with the LAPACK path to rounding. The price is numba's import and start,
once per process (about 0.35 s CPU; the function itself loads from numba's cache in 8 ms,
and compiles in about 1.5 s the first time on a machine).

The plan (``int64``) is [n, parts, entries, outputs, (address, data, offset) per LLVM function,
the flat index i·n + j (i ≤ j) of each M entry in output order]; the work array (float64) is
[the kernel's outputs | W: n × n | q̇, q̈].
"""

from __future__ import annotations

import math

import numpy as np
from numba import uint64

from pfaff.numeric.numbacode import cached, call_entry, helper

HEAD = 4  # the plan's leading integers: n, parts, entries, outputs


@helper
def cholesky_solve(w, b, n):
    """W x = b in place (x in ``b``) for W (flat, row-major, its upper triangle read) symmetric
    positive definite; 0, or k + 1 where the k-th pivot is not positive (W's upper triangle
    then holds a partial factor)."""
    one = uint64(1)
    for k in range(n):
        kn = k * n
        d = w[kn + k]
        if not d > 0.0:
            return k + one
        d = math.sqrt(d)
        w[kn + k] = d
        r = 1.0 / d
        for j in range(k + one, n):
            w[kn + j] *= r
        for i in range(k + one, n):
            s = w[kn + i]
            i_n = i * n
            for j in range(i, n):
                w[i_n + j] -= s * w[kn + j]
    for k in range(n):  # Uᵀ z = b
        kn = k * n
        z = b[k] / w[kn + k]
        b[k] = z
        for j in range(k + one, n):
            b[j] -= w[kn + j] * z
    for kk in range(n):  # U x = z
        k = n - one - kk
        kn = k * n
        s = b[k]
        for j in range(k + one, n):
            s -= w[kn + j] * b[j]
        b[k] = s / w[kn + k]
    return uint64(0)


@cached
def kernel_cholesky(plan, x, work):
    """The kernel's outputs of ``x`` = [t, q, q̇, …] into ``work``, then [q̇, q̈] at its end;
    0, a pivot's position (M not positive definite), or −1 (q̈ not finite)."""
    n, one = uint64(plan[0]), uint64(1)
    parts, entries, size = plan[1], uint64(plan[2]), uint64(plan[3])
    out = work[:size]
    for p in range(parts):
        a = HEAD + 3 * p
        call_entry(plan[a], out[plan[a + 2] :], x, plan[a + 1])
    w = work[size : size + n * n]
    res = work[size + n * n : size + n * n + n + n]
    w[:] = 0.0
    first = HEAD + 3 * parts
    for e in range(entries):
        w[plan[first + e]] = out[e]
    b = res[n:]
    for i in range(n):
        b[i] = out[entries + i]
    info = cholesky_solve(w, b, n)
    if info:
        return np.int64(info)
    total = 0.0
    for i in range(n):
        res[i] = x[one + n + i]
        total += b[i]
    return np.int64(0) if math.isfinite(total) else np.int64(-1)


def warm() -> None:
    """Compile :func:`kernel_cholesky` now (or load it from numba's cache): a 1 × 1 system of
    no LLVM function, M = [2], Q − h = [3]."""
    plan, work = plan_of([], np.zeros(1, dtype=np.int64), 1, 2)
    work[:2] = 2.0, 3.0
    kernel_cholesky(plan, np.zeros(3), work)


def plan_of(functions: list[tuple[int, int, int]], upper: np.ndarray, n: int, size: int):
    """(plan, work) of :func:`kernel_cholesky`: ``functions`` the (address, data, offset) of
    each LLVM function, ``upper`` the flat index i·n + j of each M entry among the kernel's
    first outputs, ``size`` the kernel's outputs."""
    plan = [n, len(functions), len(upper), size]
    for f in functions:
        plan.extend(f)
    plan.extend(np.asarray(upper).tolist())
    return np.array(plan, dtype=np.int64), np.zeros(size + n * n + 2 * n)
