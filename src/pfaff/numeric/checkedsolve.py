"""The fast path of a checked ``accelerations()``: the inertia check and the solve share one factor.

A checked call of a dense model used to run the inertia test (a Cholesky factorization of the
Jacobi-scaled M, :func:`pfaff.numeric.inertia.inertia_test`), then the floored range-space solve
(another factorization of M, :func:`pfaff.numeric.kkt.solve_floored`), then a consistency check
of A q̈ = c: three passes of NumPy calls around small LAPACK ones, 4–30× a right-hand side of the
same model (issue 25). :func:`checked_solve` does it in one pass: the scaled factor that passes
the inertia test's criterion solves the system, and the Schur complement's own factor says
whether the floor or the consistency check could matter. Where any of them could (M not safely
definite, a Schur pivot below the floor, rows of very different sizes), it returns None and the
model takes the full path, which names the problem. Where the machine code has solved the state
already (``evaluator="machine"``), the model keeps the full path's checks and that solution: the
checks alone cost about what this pass does.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from pfaff.numeric.inertia import M_PIVOT
from pfaff.numeric.kkt import STATE_FLOOR

_potrf = scipy.linalg.lapack.dpotrf
_potrs = scipy.linalg.lapack.dpotrs
_trtrs = scipy.linalg.lapack.dtrtrs
CLEAR = 1e-8  # a Schur pivot (unit diagonal) above this: no floor, no inconsistency to find


def checked_solve(
    K: np.ndarray, forcing: np.ndarray, c: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """q̈, λ of [[M, Aᵀ], [A, 0]] [q̈; −λ] = [Q − h; c] when every check passes on the way.

    Parameters
    ----------
    K : ndarray, shape (n + m, n + m)
    forcing : ndarray, shape (n,)
    c : ndarray, shape (m,)
    n : int

    Returns
    -------
    (qdd, lam) or None
        None where the inertia test's fast criterion fails (the Jacobi-scaled M has a Cholesky
        pivot at or below ``M_PIVOT``) or the Schur complement A M⁻¹ Aᵀ, scaled to a unit
        diagonal, has a pivot at or below :data:`CLEAR` or rows of sizes 1e8 apart: the
        full path decides.

    Examples
    --------
    A point mass on the line y = x under gravity: q̈ = (−g/2, −g/2), λ = g/2.

    >>> K = np.array([[1.0, 0.0, -1.0], [0.0, 1.0, 1.0], [-1.0, 1.0, 0.0]])
    >>> qdd, lam = checked_solve(K, np.array([0.0, -9.81]), np.array([0.0]), 2)
    >>> qdd.round(3).tolist(), lam.round(3).tolist()
    ([-4.905, -4.905], [4.905])
    """
    M, A = K[:n, :n], K[n:, :n]
    diag = M.diagonal()
    if not diag.min() > 0.0:
        return None
    s = 1.0 / np.sqrt(diag)
    L, info = _potrf(M * s[:, None] * s, lower=1)  # unit diagonal: max diag = 1
    if info != 0 or not (L.diagonal() ** 2).min() > M_PIVOT:
        return None
    y = s * _potrs(L, s * forcing, lower=1)[0]  # M⁻¹ (Q − h)
    if A.shape[0] == 0:
        return (y, np.zeros(0)) if np.isfinite(y.sum()) else None
    W = _trtrs(L, (A * s).T, lower=1)[0]  # L⁻¹ (A S)ᵀ: S = WᵀW = A M⁻¹ Aᵀ
    S = W.T @ W
    d = S.diagonal()
    if not d.min() > 1e-8 * d.max():  # rows of very different sizes: the floor's own scaling
        return None
    r = 1.0 / np.sqrt(d)
    C, info = _potrf(S * r[:, None] * r, lower=1)
    if info != 0 or not (C.diagonal() ** 2).min() > max(CLEAR, STATE_FLOOR):
        return None
    lam = r * _potrs(C, r * (c - A @ y), lower=1)[0]
    qdd = y + s * _potrs(L, s * (A.T @ lam), lower=1)[0]
    return (qdd, lam) if np.isfinite(qdd.sum() + lam.sum()) else None
