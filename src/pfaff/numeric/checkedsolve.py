"""The fast paths of a checked ``accelerations()``: the checks read the pivots of the solve itself.

A checked call used to assemble the augmented matrix and run the inertia test (a Cholesky
factorization of the Jacobi-scaled M, :func:`pfaff.numeric.inertia.inertia_test`), the
redundancy test and the floored range-space solve: three passes of NumPy calls around small
LAPACK ones, 4–34× a right-hand side of the same model (issue 25). Two shorter paths:

- :func:`fused_accelerations`, a small model with a generated solve: one call of its machine
  code returns q̈, λ and the pivots that solved them
  (:func:`pfaff.numeric.smallsolve.schur_source`), and the generated Python
  ``FusedKernel.afn`` tests the same pivots itself (against :data:`PASS`); where
  :func:`passes` holds, none of the checks could find anything, and the call is about a
  right-hand side
  (``benchmarks/accelerations.py``);
- :func:`checked_solve`, any dense model: the scaled factor that passes the inertia test's
  criterion solves the system, and the Schur complement's own factor says whether the floor
  or the consistency check could matter.

Where any of them could (M not safely definite, a Schur pivot below the floor, rows of very
different sizes), both return None and the model takes the full path, which names the problem.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from pfaff.numeric.evaluator import preallocated
from pfaff.numeric.inertia import M_PIVOT
from pfaff.numeric.kkt import STATE_FLOOR

if TYPE_CHECKING:
    from collections.abc import Callable

    from pfaff.numeric.model import NumericModel

_potrf = scipy.linalg.lapack.dpotrf
_potrs = scipy.linalg.lapack.dpotrs
_trtrs = scipy.linalg.lapack.dtrtrs
CLEAR = 1e-8  # a Schur pivot (unit diagonal) above this: no floor, no inconsistency to find
SPREAD = 1e-8  # diagonal entries of S this far apart: the floor's own row scaling decides
_SCHUR = max(CLEAR, STATE_FLOOR)
PASS = (M_PIVOT, _SCHUR, SPREAD)  # the bounds of passes(), as the generated afn tests them


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


def passes(m_pivot: float, s_pivot: float, spread: float) -> bool:
    """Whether a solve's pivots clear every check a state's full path makes.

    ``m_pivot``: the smallest Cholesky pivot of M over its diagonal entry (the pivot of the
    Jacobi-scaled M, whose test is :func:`pfaff.numeric.inertia.inertia_test`'s fast
    criterion); ``s_pivot``: the same of S = A M⁻¹ Aᵀ (above :data:`CLEAR`, A has full rank
    and A q̈ = c has a solution: no redundant row, no inconsistency, no floor); ``spread``: the
    smallest diagonal entry of S over the largest. NaN fails.

    Examples
    --------
    >>> passes(0.5, 1.0, 1.0), passes(1e-14, 1.0, 1.0), passes(0.5, float("nan"), 1.0)
    (True, False, False)
    """
    return m_pivot > M_PIVOT and s_pivot > _SCHUR and spread > SPREAD


def fused_accelerations(
    model: NumericModel, t: object, q: object, qd: object
) -> tuple[np.ndarray, np.ndarray] | None:
    """q̈ and λ at a state from the generated solve of a small model, or None.

    One call of the model's machine code (its outputs end with the pivot checks) or, with the
    generated Python as evaluator, of ``FusedKernel.afn``: q̈, λ and the pivots of the
    factorizations that solved them. Where the pivots pass (:func:`passes`) and the results
    are finite, the checks of the full path could find nothing (M safely definite, A of full
    rank); else None, and the model takes the full path, which names the problem. The
    inertia check then costs three comparisons instead of its own factorizations
    (issue 25: ``accelerations()`` was 7–34× a right-hand side, ``benchmarks/accelerations.py``).
    Only a plain state is taken here (a finite float t, finite float64 arrays of shape (n,));
    anything else is None too: the full path's :func:`pfaff.numeric.checks.check_state` then
    accepts it or names what is wrong. The function that answers is made once per model
    (:func:`fast_accelerations`) and kept in its run state.
    """
    run = model._run_state
    fast = run.get("fast")
    if fast is None:
        run["fast"] = fast = fast_accelerations(model) or False
    return fast(t, q, qd) if fast else None


def fast_accelerations(model: NumericModel) -> Callable | None:
    """``fast(t, q, q̇) -> (q̈, λ) or None`` of :func:`fused_accelerations` for ``model`` (its
    evaluator as it is now: a model that changes it drops the one kept), or None where it has
    no generated solve."""
    fk = model._fused
    if fk is None:
        return None
    shape = (model.n,)  # (an unpickled array's float64 dtype is equal to numpy's, not the same)
    machine = model.evaluator == "machine"
    acc = None
    if machine:
        if fk.checks != 3 or not fk.solves:  # (machine code made before its pivot checks were)
            return None
    else:
        if fk.rfn is None:  # (the generated solve disagreed with the array solve when checked)
            return None
        make = getattr(fk.afn, "function", None)
        acc = make() if make is not None else fk.afn
        if acc is None:
            return None

    def fast(t: object, q: object, qd: object) -> tuple[np.ndarray, np.ndarray] | None:
        if not (
            isinstance(t, float) and type(q) is _ARRAY and type(qd) is _ARRAY
            and q.dtype == qd.dtype == _FLOAT and q.shape == qd.shape == shape
        ):  # fmt: skip
            return None
        if machine:
            return _machine_accelerations(model, t, q, qd)
        # checks, finiteness (of t, q, q̇, q̈ and λ) and domain errors are the generated code's
        r = acc(float(t), q.tolist(), qd.tolist(), model._p)  # (a NumPy float's t too)
        return None if r is None else (_array(r[0]), _array(r[1]))

    return fast


def _machine_accelerations(
    model: NumericModel, t: float, q: np.ndarray, qd: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`fused_accelerations` by the machine code (the evaluator): one call on the run's
    input buffer, through its unchecked entry point into an output array of the run
    (:func:`pfaff.numeric.evaluator.preallocated`, as the right-hand side calls it)."""
    if not _isfinite(t + sum(q.tolist()) + sum(qd.tolist())):
        return None
    machine = model._machine()
    if machine is None:
        return None
    n, p, run = model.n, model._p, model._run_state
    buf = run["buf"]
    buf[0], buf[1 : 1 + n], buf[1 + n : 1 + 2 * n] = t, q, qd
    if type(p) is not tuple or run.get("p") is not p:  # (a run's inputs change a list)
        buf[1 + 2 * n : 1 + 2 * n + len(p)] = p
        run["p"] = p
    call = run.get("acc_call")
    if call is None or call[0] is not machine:
        run["acc_call"] = call = (machine, preallocated(machine, buf))
    out = call[1]()
    run["last"] = None  # (the full path's cache of a machine solve: not this call's)
    if not passes(*out[-3:].tolist()):
        return None
    res = out[n : 2 * n + model.m].copy()  # (q̈ and λ after q̇)
    if not _isfinite(sum(res.tolist())):
        return None
    return res[:n], res[n:]


_FLOAT = np.dtype(float)
_ARRAY, _array, _isfinite = np.ndarray, np.array, math.isfinite
