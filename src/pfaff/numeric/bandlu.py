"""LU of a banded matrix with partial pivoting and its solves, compiled by numba.

The algorithm and the storage are LAPACK's ``dgbtf2`` / ``dgbtrs``: column j of the matrix is
row j of ``ab`` (shape (n, 2 kl + ku + 1)), entry (i, j) at ``ab[j, kl + ku + i − j]``, the
first kl places of each row kept for the fill-in of the row interchanges; pivots 0-based. A
band a few entries wide (the ring's GGL matrix: kl = ku = 4) makes LAPACK call BLAS once or
twice per column, which is most of its time; these loops run inside one call. Imported on
first use by :mod:`pfaff.numeric.bordered` (numba then loads, from its on-disk cache after the
first time).

A band at most ``NARROW_L`` = 4 wide below and ``NARROW_K`` = 4 above is stored at exactly
those widths (its extra places zero) and takes the narrow path: :func:`narrow_factor` (the
loops' trip counts fixed, so unrolled, and the solve's compact factors written as it goes) and
:func:`narrow_solve` (the rows still open kept in registers, the right side gathered inside it).
Both do the general routines' operations in their order, so the same factors and solutions to
the last bit (a zero's sign aside: an added zero product can turn −0 into +0), in about half
the time or less (the ring's GGL matrix at 2^16 members: see the two functions).

Examples
--------
>>> import numpy as np
>>> n, kl, ku = 6, 1, 1
>>> A = np.diag(np.full(n, 1.0)) + np.diag(np.full(n - 1, 3.0), -1) + np.diag(np.full(n - 1, 2.0), 1)
>>> ab = np.zeros((n, 2 * kl + ku + 1))
>>> for i, j in zip(*np.nonzero(A)):
...     ab[j, kl + ku + i - j] = A[i, j]
>>> piv = np.zeros(n, dtype=np.int64)
>>> band_factor(ab, kl, ku, piv)
0
>>> ue = ku + int((piv - np.arange(n)).max())  # U's upper bandwidth
>>> lower, upper = np.empty((n, kl)), np.empty((n, ue + 1))
>>> band_split(ab, kl, ku, lower, upper)
>>> b = np.arange(1.0, n + 1)[None, :]
>>> band_solve(lower, upper, piv, b)
>>> bool(np.allclose(A @ b[0], np.arange(1.0, n + 1)))
True
>>> out, slots = np.zeros(3), np.array([0, 2, 0])
>>> sum_into(out, slots, np.array([1.0, 2.0, 3.0]))
>>> gather(out, out.copy(), np.array([2, 1, 0]))
>>> out.tolist()
[2.0, 0.0, 4.0]
>>> z = np.zeros(3)  # z[order] = y - Xᵀ zs over the live rows, z[border] = zs
>>> scatter_border(z, np.ones(2), np.array([[1.0, 2.0]]), np.array([0.5]), np.array([0, 2]),
...                np.array([1]), np.array([0]))
>>> z.tolist()
[0.5, 0.5, 0.0]
"""

from __future__ import annotations

import numpy as np

from pfaff.numeric.numbacode import cached, helper


@cached
def band_factor(ab: np.ndarray, kl: int, ku: int, piv: np.ndarray) -> int:  # pragma: no cover
    """LU in place (``dgbtf2``); returns 0, or j + 1 where column j has no pivot whose
    reciprocal is finite (zero or subnormal)."""
    n = ab.shape[0]
    kv = kl + ku
    ju = 0
    for j in range(n):
        km = min(kl, n - 1 - j)
        jp, big = 0, abs(ab[j, kv])
        for p in range(1, km + 1):
            if abs(ab[j, kv + p]) > big:
                jp, big = p, abs(ab[j, kv + p])
        piv[j] = j + jp
        if not 1.0 / big < np.inf:  # zero, or too small for its reciprocal (band_split's)
            return j + 1
        ju = max(ju, min(j + ku + jp, n - 1))
        if jp != 0:  # interchange rows j and j + jp in columns j … ju
            for c in range(j, ju + 1):
                a, b = kv + j - c, kv + j + jp - c
                ab[c, a], ab[c, b] = ab[c, b], ab[c, a]
        if km > 0:
            r = 1.0 / ab[j, kv]
            for p in range(1, km + 1):
                ab[j, kv + p] *= r
            for c in range(j + 1, ju + 1):
                u = ab[c, kv + j - c]
                if u != 0.0:
                    for p in range(1, km + 1):
                        ab[c, kv + j + p - c] -= ab[j, kv + p] * u
    return 0


@cached
def band_split(
    ab: np.ndarray, kl: int, ku: int, lower: np.ndarray, upper: np.ndarray
) -> None:  # pragma: no cover
    """The factors of :func:`band_factor` in two compact arrays for the solves: ``lower[j, i]``
    the multiplier of row j + i + 1 by row j, ``upper[j, 0]`` the reciprocal of U's diagonal
    (a multiplication in the solves' chain of dependent updates, not a division) and ``upper[j, i]``
    U[j − i, j], i up to ``upper.shape[1] − 1``, U's actual upper bandwidth (ku without row
    interchanges: most of ab's 2 kl + ku + 1 places are then never read)."""
    n = ab.shape[0]
    kv = kl + ku
    for j in range(n):
        for i in range(kl):
            lower[j, i] = ab[j, kv + 1 + i]
        upper[j, 0] = 1.0 / ab[j, kv]
        for i in range(1, upper.shape[1]):
            upper[j, i] = ab[j, kv - i]


def _solve_one(lower: np.ndarray, upper: np.ndarray, piv: np.ndarray, x: np.ndarray) -> None:
    """x ← A⁻¹ x for one right side (a vector: about 13 % faster than the rows' loop)."""
    n = x.size
    kl, ue = lower.shape[1], upper.shape[1] - 1
    for j in range(n - 1):  # L, with the interchanges
        p = piv[j]
        xj = x[p]
        if p != j:
            x[p] = x[j]
            x[j] = xj
        for i in range(min(kl, n - 1 - j)):
            x[j + 1 + i] -= lower[j, i] * xj
    for j in range(n - 1, -1, -1):  # U
        xj = x[j] * upper[j, 0]
        x[j] = xj
        for i in range(1, min(ue, j) + 1):
            x[j - i] -= upper[j, i] * xj


_one = helper(_solve_one)


@cached
def band_solve(
    lower: np.ndarray, upper: np.ndarray, piv: np.ndarray, b: np.ndarray
) -> None:  # pragma: no cover
    """b ← A⁻¹ b in place with the factors of :func:`band_split`, b of shape (k, n): k right
    sides as rows, solved in one pass over the factors."""
    k, n = b.shape
    if k == 1:
        _one(lower, upper, piv, b[0])
        return
    kl, ue = lower.shape[1], upper.shape[1] - 1
    for j in range(n - 1):  # L, with the interchanges
        lm = min(kl, n - 1 - j)
        p = piv[j]
        for c in range(k):
            if p != j:
                b[c, p], b[c, j] = b[c, j], b[c, p]
            bj = b[c, j]
            for i in range(lm):
                b[c, j + 1 + i] -= lower[j, i] * bj
    for j in range(n - 1, -1, -1):  # U
        r = upper[j, 0]
        top = min(ue, j)
        for c in range(k):
            bj = b[c, j] * r
            b[c, j] = bj
            for i in range(1, top + 1):
                b[c, j - i] -= upper[j, i] * bj


NARROW_L, NARROW_K = 4, 4  # the narrow factorization's fixed kl and ku
NARROW_U = NARROW_L + NARROW_K  # U's width at most, with the row interchanges


@cached
def narrow_factor(
    ab: np.ndarray, lower: np.ndarray, off: np.ndarray, upper: np.ndarray
) -> int:  # pragma: no cover
    """:func:`band_factor` with kl = ``NARROW_L`` and ku = ``NARROW_K`` fixed (a narrower band
    stored as this one, its extra places zero), which also writes the factors for
    :func:`narrow_solve` as it goes (row j of U is final once column j is done): ``off[j]``
    = piv[j] − j, ``lower[j, i]`` the multiplier of row j + i + 1 by row j (shape
    (n, NARROW_L)), ``upper[j, 0]`` = 1 / U[j, j] and ``upper[j, i]`` = U[j, j + i] (shape
    (n, NARROW_U + 1), U by rows); zero past the matrix. The same operations on the same values
    as :func:`band_factor` and :func:`band_split` (the zeros past the matrix's last row are
    never a pivot, and multiply as zeros), so the same factors to the last bit (up to a zero's
    sign); the ring's GGL matrix at 2^16 members from a cold cache in 11–12 ms, against
    15.5–17.6 for these loops followed by a separate compacting pass (and 24 + 7 ms, warm, for
    :func:`band_factor` and :func:`band_split`). Returns 0, or j + 1 where column j has no
    pivot whose reciprocal is finite."""
    n = ab.shape[0]
    kv = NARROW_L + NARROW_K
    ju = 0
    for j in range(n):
        jp, big = 0, abs(ab[j, kv])
        for p in range(1, NARROW_L + 1):
            a = abs(ab[j, kv + p])
            if a > big:
                jp, big = p, a
        off[j] = jp
        if not 1.0 / big < np.inf:
            return j + 1
        ju = max(ju, min(j + NARROW_K + jp, n - 1))
        if jp != 0:
            for c in range(j, ju + 1):
                a, b = kv + j - c, kv + j + jp - c
                ab[c, a], ab[c, b] = ab[c, b], ab[c, a]
        r = 1.0 / ab[j, kv]
        for p in range(1, NARROW_L + 1):
            ab[j, kv + p] *= r
            lower[j, p - 1] = ab[j, kv + p]
        for c in range(j + 1, ju + 1):
            u = ab[c, kv + j - c]
            if u != 0.0:
                for p in range(1, NARROW_L + 1):
                    ab[c, kv + j + p - c] -= ab[j, kv + p] * u
        upper[j, 0] = r
        for i in range(1, NARROW_U + 1):
            upper[j, i] = ab[j + i, kv - i] if j + i < n else 0.0
    return 0


@cached
def narrow_solve(
    lower: np.ndarray,
    off: np.ndarray,
    upper: np.ndarray,
    r: np.ndarray,
    order: np.ndarray,
    x: np.ndarray,
) -> None:  # pragma: no cover
    """x = A⁻¹ r[order] with the factors of :func:`narrow_factor`; x of shape (n,), r itself
    where ``order`` is the identity (r[order[j]] is read before x[j] is written).

    The same operations in the same order as :func:`band_solve`'s on one right side, so the
    same result to the last bit (a zero's sign aside: x − 0·y turns a −0 into +0, where
    :func:`band_solve` skips the product), in about 40 % of its time (the ring's GGL matrix at
    2^16 members, warm: 2.0 ms against 5.2–5.8; 4.0 ms from a cold cache): the rows still open
    are kept in registers instead of memory, written out for ``NARROW_L`` = 4 and ``NARROW_U`` = 8 (the few zeros past a row's own width
    multiplied in). Forward, w0 … w4 are rows j … j + 4 of the partly eliminated right side
    (row j + 4 is first met at column j: it is gathered from r there), the interchange a
    choice among them. Backward, a1 … a8 are the unknowns j + 1 … j + 8 and U is read by rows:
    each unknown a sum of products in which the one just found comes last, so that rows
    overlap instead of waiting on one another."""
    n = off.size
    w0 = r[order[0]] if n > 0 else 0.0
    w1 = r[order[1]] if n > 1 else 0.0
    w2 = r[order[2]] if n > 2 else 0.0
    w3 = r[order[3]] if n > 3 else 0.0
    for j in range(n):  # L, with the interchanges
        w4 = r[order[j + 4]] if j + 4 < n else 0.0
        o = off[j]
        if o == 0:
            xj = w0
        elif o == 1:
            xj, w1 = w1, w0
        elif o == 2:
            xj, w2 = w2, w0
        elif o == 3:
            xj, w3 = w3, w0
        else:
            xj, w4 = w4, w0
        x[j] = xj
        w0 = w1 - lower[j, 0] * xj
        w1 = w2 - lower[j, 1] * xj
        w2 = w3 - lower[j, 2] * xj
        w3 = w4 - lower[j, 3] * xj
    a1 = a2 = a3 = a4 = a5 = a6 = a7 = a8 = 0.0
    for j in range(n - 1, -1, -1):  # U, the farthest column first (band_solve's order)
        u = upper[j]
        s = x[j] - u[8] * a8 - u[7] * a7 - u[6] * a6 - u[5] * a5 - u[4] * a4 - u[3] * a3
        s = s - u[2] * a2 - u[1] * a1
        a8, a7, a6, a5, a4, a3, a2 = a7, a6, a5, a4, a3, a2, a1
        a1 = s * u[0]
        x[j] = a1


@cached
def sum_into(out: np.ndarray, slots: np.ndarray, values: np.ndarray) -> None:  # pragma: no cover
    """out[slots[i]] += values[i] for every i (``np.bincount`` into an array kept between
    factorizations: no new pages to fault in)."""
    for i in range(slots.size):
        out[slots[i]] += values[i]


@cached
def gather(out: np.ndarray, r: np.ndarray, order: np.ndarray) -> None:  # pragma: no cover
    """out[p] = r[order[p]]."""
    for p in range(order.size):
        out[p] = r[order[p]]


@cached
def scatter_border(
    z: np.ndarray,
    y: np.ndarray,
    Xt: np.ndarray,
    zs: np.ndarray,
    order: np.ndarray,
    border: np.ndarray,
    live: np.ndarray,
) -> None:  # pragma: no cover
    """z[order[p]] = y[p] − Σ_c Xt[c, p] zs[c] over the ``live`` rows c of Xt (the others are
    zero), z[border] = zs: the bordered solve's end. Two live rows in the one pass over p (a
    loop over c inside it took 2.4 times as long on the ring's two), any others after it."""
    n = order.size
    first = live[0] if live.size > 0 else 0
    second = live[1] if live.size > 1 else first
    sa = zs[first] if live.size > 0 else 0.0
    sb = zs[second] if live.size > 1 else 0.0
    a, b = Xt[first], Xt[second]
    for p in range(n):
        z[order[p]] = y[p] - a[p] * sa - b[p] * sb
    for i in range(2, live.size):
        c = live[i]
        for p in range(n):
            z[order[p]] -= Xt[c, p] * zs[c]
    for c in range(zs.size):
        z[border[c]] = zs[c]
