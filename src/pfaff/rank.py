"""Generic-rank test of the constraint matrix: redundant or inconsistent constraints are refused.

A is evaluated at a random configuration with random parameter values; linear dependence that holds
everywhere (a repeated, combined or contradictory constraint) shows there with probability one.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .errors import ConstraintError

if TYPE_CHECKING:
    from .equations import EquationsOfMotion

DENSE_RANK_LIMIT = 200


def check_constraint_rank(eom: EquationsOfMotion, seed: int = 20261122) -> None:
    """Raise :class:`ConstraintError` naming the constraints that depend on the others."""
    from .compiler import build_model

    n, m = eom.n, eom.m
    if m == 0:
        return
    if m > n:
        raise ConstraintError(
            f"{m} constraints on {n} coordinates: more constraints than coordinates"
        )
    rng = np.random.default_rng(seed)
    values = list(rng.uniform(0.7, 1.6, len(eom.parameters)))
    q = rng.uniform(-1.3, 1.3, n)
    tt = rng.uniform(0.1, 1.0)
    if eom.family:
        A = _family_matrix(eom, values, tt, q)
        if A is None:
            return
    else:
        model = build_model(eom, values, constraints_only=True)
        with np.errstate(all="ignore"):
            A = model.constraint_matrix(tt, q)
    A = A.toarray() if sps.issparse(A) and m <= DENSE_RANK_LIMIT else A
    if not sps.issparse(A):
        if not np.all(np.isfinite(A)):
            return  # a singular random point; the numeric solve will report real problems
        _, R, piv = scipy.linalg.qr(A.T, mode="economic", pivoting=True)
        d = np.abs(np.diag(R))
        tol = max(A.shape) * np.finfo(float).eps * (d[0] if d.size else 0.0) * 10
        rank = int(np.sum(d > tol))
        if rank < m:
            dependent = sorted(piv[rank:])
            names = ", ".join(f"`{eom.constraint_names[i]}`" for i in dependent[:8])
            raise ConstraintError(
                f"redundant or inconsistent constraints: the constraint matrix has rank {rank} < {m}; "
                f"{names}{' ...' if len(dependent) > 8 else ''} depend(s) on the others"
            )
        return
    G = sps.bmat([[sps.identity(n), A.T], [A, None]], format="csc")
    message = (
        f"redundant or inconsistent constraints: the {m}×{n} constraint matrix is rank deficient"
    )
    try:
        d = np.abs(spla.splu(G).U.diagonal())
    except RuntimeError as e:  # SuperLU: "Factor is exactly singular"
        raise ConstraintError(message) from e
    if d.min() < 1e-11 * d.max():
        raise ConstraintError(message)


def _family_matrix(eom: EquationsOfMotion, values: list, t: float, q: np.ndarray):
    """A of a family model at (t, q), or None when its triangular structure already proves rank m."""
    from .solvers import TriangularSolver, triangular_plan
    from .structured import StructuredModel

    model = StructuredModel(eom, values, solver="none")
    plan = triangular_plan(model)
    with np.errstate(all="ignore"):
        if plan is not None:
            avals, _ = model._accel_constraints(t, q, np.zeros(eom.n))
            TriangularSolver(model, plan)._current(avals)  # raises on a zero pivot
            return None
        return model.constraint_matrix(t, q)
