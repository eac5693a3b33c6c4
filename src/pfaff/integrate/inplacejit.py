"""Integrate stage: DOP853's sums over the stages of a long state, each in one compiled pass.

:class:`pfaff.integrate.inplace.InPlaceDOP853` would form a stage state as ``np.dot(h a, K[:u])``
(BLAS) and then ``stage += y``, the solution and the error estimates in two more products over K,
and a dense-output value in six passes: every pass streams its 2n-long operands through memory
again. Here each of those sums is one loop over blocks of :data:`BLOCK` components (a block of
the result stays in L1 while the rows of K are added to it, four rows a pass; the inner loops
vectorize), so that every operand is read once and the result written once:

* :func:`combine`: out = Σ_i w_i K_i + Σ_j v_j E_j + a₀ y₀ + a₁ y₁ + a₂ y₂ (a stage state, an
  extra stage of the dense output, a dense-output value);
* :func:`solution_and_error`: y_new = y + Σ b_i K_i and the sums of squares of both error
  estimates scaled by atol + rtol max(|y|, |y_new|), in the same pass.

Both work on one span [lo, hi) of the components, so that the caller can hand the spans to the
kernel threads (:func:`pfaff.numeric.streams.in_spans`: a stage sum of 2^21 components takes
about 7 ms on two threads instead of 12 ms on one, the memory's pace of one core). A component's
value is computed the same way whatever the spans: the results do not depend on the thread count,
and the sums of squares are added span by span in the spans' order (:func:`span_norms`).

Zero coefficients are skipped (their rows not read). The sums run in another order than BLAS's:
results agree to rounding (``tests/integrate/test_inplace.py``). Compiled on first use through
:func:`pfaff.numeric.jit.compiled`; None without numba.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pfaff.numeric import jit

BLOCK = 2048  # components per block: 16 KiB of the result (and of the error sums) in L1


def combine(w, K, v, E, a, y0, y1, y2, out, lo, hi):  # type: ignore[no-untyped-def]
    """out[lo:hi] = (a₀ y₀ + a₁ y₁ + a₂ y₂ + Σ_i w_i K_i + Σ_j v_j E_j)[lo:hi] (rows of K and E
    up to the lengths of w and v; zero coefficients skipped: their rows not read)."""
    kw, ke = np.flatnonzero(w), np.flatnonzero(v)
    for b0 in range(lo, hi, BLOCK):
        b1 = min(b0 + BLOCK, hi)
        o, m = out[b0:b1], b1 - b0
        first = True
        for k in range(3):
            c = a[k]
            if c != 0.0:
                x = y0[b0:b1] if k == 0 else (y1[b0:b1] if k == 1 else y2[b0:b1])
                if first:
                    for j in range(m):
                        o[j] = c * x[j]
                    first = False
                else:
                    for j in range(m):
                        o[j] += c * x[j]
        if first:
            o[:] = 0.0
        for src in range(2):
            rows, coef, M = (kw, w, K) if src == 0 else (ke, v, E)
            i = 0
            while i + 4 <= rows.shape[0]:  # four rows a pass over the block
                r0, r1, r2, r3 = rows[i], rows[i + 1], rows[i + 2], rows[i + 3]
                c0, c1, c2, c3 = coef[r0], coef[r1], coef[r2], coef[r3]
                x0, x1, x2, x3 = M[r0, b0:b1], M[r1, b0:b1], M[r2, b0:b1], M[r3, b0:b1]
                for j in range(m):
                    o[j] += (c0 * x0[j] + c1 * x1[j]) + (c2 * x2[j] + c3 * x3[j])
                i += 4
            while i < rows.shape[0]:
                c0, x0 = coef[rows[i]], M[rows[i], b0:b1]
                for j in range(m):
                    o[j] += c0 * x0[j]
                i += 1


def solution_and_error(b, e, K, y, y_new, atol, rtol, lo, hi):  # type: ignore[no-untyped-def]
    """y_new[lo:hi] = (y + Σ_i b_i K_i)[lo:hi]; returns (Σ (ε₅/s)², Σ (ε₃/s)²) over [lo, hi)
    with ε = Σ_i e_{·i} K_i (e's two rows: the fifth- and third-order estimates),
    s = atol + rtol max(|y|, |y_new|) (atol of length 1 or n)."""
    work = np.zeros((4, BLOCK))  # the block's estimates, then the per-lane sums of squares
    s5, s3 = work[2], work[3]
    per = atol.shape[0] > 1
    for b0 in range(lo, hi, BLOCK):
        b1 = min(b0 + BLOCK, hi)
        m = b1 - b0
        yn, e5, e3 = y_new[b0:b1], work[0, :m], work[1, :m]
        yn[:] = 0.0
        e5[:] = 0.0
        e3[:] = 0.0
        for i in range(b.shape[0]):
            k, c, c5, c3 = K[i, b0:b1], b[i], e[0, i], e[1, i]
            if c != 0.0:
                for j in range(m):
                    yn[j] += c * k[j]
            if c5 != 0.0 or c3 != 0.0:
                for j in range(m):
                    e5[j] += c5 * k[j]
                    e3[j] += c3 * k[j]
        yy = y[b0:b1]
        at = atol[b0:b1] if per else atol
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
    >>> a = np.array([0.5, 0.0, 0.0])
    >>> f(np.array([1.0, 0.0, 3.0]), K, np.zeros(0), K, a, y, y, y, out, 0, 5)
    >>> out.tolist()
    [5.0, 5.0, 5.0, 5.0, 5.0]
    """
    x, X, a = np.zeros(1), np.zeros((1, 1)), np.zeros(3)
    c = jit.compiled(combine, (x, X, x, X, a, x, x, x, x, 0, 1))
    e = jit.compiled(solution_and_error, (x, X, np.zeros((2, 1)), x, x, x, 1.0, 0, 1))
    return None if c is None or e is None else (c, e)
