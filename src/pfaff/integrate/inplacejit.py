"""Integrate stage: DOP853's sums over the stages of a long state, each in one compiled pass.

:class:`pfaff.integrate.inplace.InPlaceDOP853` forms a stage state as ``np.dot(h a, K[:u])``
(BLAS) and then ``stage += y``, the solution and the error estimates in two more products over K,
and a dense-output value in six passes: every pass streams its 2n-long operands through memory
again. Here each of those sums is one loop over blocks of :data:`BLOCK` components (a block of
the result stays in L1 while the rows of K are added to it; the inner loops vectorize), so that
every operand is read once and the result written once:

* :func:`combine`: out = Σ_i w_i K_i + Σ_j v_j E_j + a₀ y₀ + a₁ y₁ + a₂ y₂ (a stage state, an
  extra stage of the dense output, a dense-output value);
* :func:`solution_and_error`: y_new = y + Σ b_i K_i and the sums of squares of both error
  estimates scaled by atol + rtol max(|y|, |y_new|), in the same pass.

Zero coefficients are skipped (their rows not read). The sums run in another order than BLAS's:
results agree to rounding (``tests/integrate/test_inplace.py``). Compiled on first use through
:func:`pfaff.numeric.jit.compiled`; None without numba.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pfaff.numeric import jit

BLOCK = 2048  # components per block: 16 KiB of the result (and of the error sums) in L1


def combine(w, K, v, E, a, y0, y1, y2, out):  # type: ignore[no-untyped-def]
    """out = Σ_i w_i K_i + Σ_j v_j E_j + a₀ y₀ + a₁ y₁ + a₂ y₂ (rows of K and E up to the
    lengths of w and v; zero coefficients skipped: their rows not read)."""
    n = out.shape[0]
    for lo in range(0, n, BLOCK):
        hi = min(lo + BLOCK, n)
        o = out[lo:hi]
        o[:] = 0.0
        for r in range(w.shape[0] + v.shape[0] + 3):
            if r < w.shape[0]:
                c, x = w[r], K[r, lo:hi]
            elif r < w.shape[0] + v.shape[0]:
                c, x = v[r - w.shape[0]], E[r - w.shape[0], lo:hi]
            else:
                k = r - w.shape[0] - v.shape[0]
                c = a[k]
                x = y0[lo:hi] if k == 0 else (y1[lo:hi] if k == 1 else y2[lo:hi])
            if c != 0.0:
                for j in range(o.shape[0]):
                    o[j] += c * x[j]


def solution_and_error(b, e, K, y, y_new, atol, rtol, work):  # type: ignore[no-untyped-def]
    """y_new = y + Σ_i b_i K_i; returns (Σ (ε₅/s)², Σ (ε₃/s)²) with ε = Σ_i e_{·i} K_i (e's two
    rows: the fifth- and third-order estimates), s = atol + rtol max(|y|, |y_new|) (atol of
    length 1 or n). ``work``: scratch (4, BLOCK)."""
    n = y.shape[0]
    work[2:] = 0.0  # the per-lane sums of squares
    s5, s3 = work[2], work[3]
    per = atol.shape[0] > 1
    for lo in range(0, n, BLOCK):
        hi = min(lo + BLOCK, n)
        m = hi - lo
        yn, e5, e3 = y_new[lo:hi], work[0, :m], work[1, :m]
        yn[:] = 0.0
        e5[:] = 0.0
        e3[:] = 0.0
        for i in range(b.shape[0]):
            k, c, c5, c3 = K[i, lo:hi], b[i], e[0, i], e[1, i]
            if c != 0.0:
                for j in range(m):
                    yn[j] += c * k[j]
            if c5 != 0.0 or c3 != 0.0:
                for j in range(m):
                    e5[j] += c5 * k[j]
                    e3[j] += c3 * k[j]
        yy = y[lo:hi]
        at = atol[lo:hi] if per else atol
        for j in range(m):
            z = yy[j] + yn[j]
            yn[j] = z
            u, v = abs(yy[j]), abs(z)
            scale = (u if u >= v else v) * rtol + at[j if per else 0]
            r5, r3 = e5[j] / scale, e3[j] / scale
            s5[j] += r5 * r5
            s3[j] += r3 * r3
    return s5.sum(), s3.sum()


def kernels() -> tuple[Callable, Callable] | None:
    """(combine, solution_and_error) compiled, or None (:func:`pfaff.numeric.jit.compiled`).

    Examples
    --------
    >>> import numpy as np
    >>> ks = kernels()
    >>> K, y, out = np.ones((3, 5)), np.full(5, 2.0), np.empty(5)
    >>> f = combine if ks is None else ks[0]
    >>> f(np.array([1.0, 0.0, 3.0]), K, np.zeros(0), K, np.array([0.5, 0.0, 0.0]), y, y, y, out)
    >>> out.tolist()
    [5.0, 5.0, 5.0, 5.0, 5.0]
    """
    x, X, a = np.zeros(1), np.zeros((1, 1)), np.zeros(3)
    c = jit.compiled(combine, (x, X, x, X, a, x, x, x, x))
    e = jit.compiled(
        solution_and_error, (x, X, np.zeros((2, 1)), x, x, x, 1.0, np.zeros((4, BLOCK)))
    )
    return None if c is None or e is None else (c, e)
