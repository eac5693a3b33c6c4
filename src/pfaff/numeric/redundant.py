"""Redundant constraints at a state: which rows to keep, the minimum-norm multipliers, the report.

Rows of A that depend on the others carry no information about the motion: q̈ is unique whenever M
is positive definite on the admissible motions, but λ is determined only up to the null space of
Aᵀ (on those rows only Aᵀλ is). pfaff keeps a maximal independent set of rows, chosen by QR with
column pivoting of Aᵀ (rows scaled to unit length for the decision only, so that units do not
decide), solves the motion with them, and reports the minimum Euclidean-norm λ over all rows as the
user wrote them (no row scaling): the least-squares solution of Aᵀλ = Aᵀ_I λ_I.

A run tells *persistent* redundancy (the ring closed by all N spacing rows, two wheels both
forbidding side-slip, the Bricard linkage) from an *isolated* rank loss (a four-bar folding flat)
by :func:`persistent`: the rank deficiency at the first consistent state must also be found at two
nearby consistent states, reached along admissible directions; a fold regains its rank there and
keeps the floored branch-following of :mod:`pfaff.numeric.kkt`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import numpy as np
import scipy.linalg
import scipy.sparse as sps

from pfaff.core.errors import ConstraintError, RedundancyWarning
from pfaff.core.stack import outside_pfaff
from pfaff.numeric.rank import null_basis, redundant_sets

_geqp3 = scipy.linalg.lapack.dgeqp3  # pivoted QR without scipy.linalg.qr's checks (µs per call)
REDUNDANT_DENSE = 4000  # unknowns n + m up to which a sparse model's redundant rows are found
RANK_TOL = 1e-9  # a pivot of QR(Aᵀ) (unit rows) below this times the largest: a dependent row
PROBE = 1e-3  # the step to the nearby states of the persistence test (times 1 + |q|)


def independent_rows(A: np.ndarray, tol: float = RANK_TOL) -> np.ndarray | None:
    """A maximal set of independent rows of A (ascending), or None when all rows are.

    Examples
    --------
    >>> independent_rows(np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0]])).tolist()
    [0, 2]
    >>> independent_rows(np.eye(2)) is None
    True
    """
    m = A.shape[0]
    if m == 0:
        return None
    norms = np.sqrt(np.einsum("ij,ij->i", A, A))
    top = norms.max()
    if not top > 0 or norms.min() <= 1e-12 * top:
        return None  # a row with a zero gradient is singular, not redundant: the solve names it
    if m == 1:
        return None
    R, piv, _, _, info = _geqp3((A / norms[:, None]).T)
    if info != 0:  # (LAPACK's own argument check: not reached for a finite matrix)
        R, piv = scipy.linalg.qr((A / norms[:, None]).T, mode="r", pivoting=True)
    else:
        piv = piv - 1  # LAPACK's pivots count from 1
    d = np.abs(R.diagonal())
    rank = int(np.count_nonzero(d > tol * d[0])) if d[0] > 0 else 0
    if rank == m:
        return None
    return np.sort(piv[:rank])


def min_norm_multipliers(A: np.ndarray, rows: np.ndarray, lam_rows: np.ndarray) -> np.ndarray:
    """The minimum-norm λ over all rows with Aᵀλ = A_Iᵀ λ_I, shape (m,).

    Examples
    --------
    >>> A = np.array([[1.0, 0.0], [1.0, 0.0]])
    >>> np.round(min_norm_multipliers(A, np.array([0]), np.array([2.0])), 12).tolist()
    [1.0, 1.0]
    """
    force = A[rows].T @ lam_rows
    return scipy.linalg.lstsq(A.T, force, cond=RANK_TOL)[0]


NAMES_SHOWN = 8


def dependency_names(names: Sequence[str], rows: np.ndarray) -> str:
    """The first few constraint names of ``rows`` in backticks, and a count of the rest.

    Examples
    --------
    >>> dependency_names(["a", "b", "c"], np.array([0, 2]))
    '`a`, `c`'
    """
    shown = ", ".join(f"`{names[int(i)]}`" for i in rows[:NAMES_SHOWN])
    more = rows.size - NAMES_SHOWN
    return shown + (f" and {more} more" if more > 0 else "")


def describe(names: Sequence[str], A: np.ndarray) -> str:
    """The sets of rows that depend on one another at A, by name (for messages)."""
    return "; ".join(dependency_names(names, np.asarray(s)) for s in redundant_sets(A))


def warn(names: Sequence[str], A: np.ndarray, where: str) -> None:
    """A :class:`pfaff.RedundancyWarning` naming the dependent sets of A."""
    m, k = A.shape[0], null_basis(A).shape[1]
    warnings.warn(
        f"redundant constraints {where}: rank {m - k} < {m}; {describe(names, A)} depend on one "
        "another. The motion is determined; on these rows only Aᵀλ is, and pfaff reports the "
        "minimum-norm multipliers (model.redundancy names the indeterminate directions)",
        RedundancyWarning,
        stacklevel=outside_pfaff(),
    )


def persistent(
    A0: np.ndarray,
    rows: np.ndarray,
    q0: np.ndarray,
    matrix: Callable[[np.ndarray], np.ndarray],
    residual: Callable[[np.ndarray], np.ndarray],
    holonomic: np.ndarray,
) -> bool:
    """Whether the rank deficiency of A0 at q0 persists at two nearby consistent states.

    The states: q0 ± PROBE (1 + |q0|) v along a fixed admissible direction v (a unit vector of
    null(A_I)), brought back onto the position rows by :func:`onto_positions`. ``matrix(q)``
    gives A, ``residual(q)`` f at q.
    """
    k0 = A0.shape[0] - rows.size
    Z = scipy.linalg.null_space(A0[rows])
    if Z.shape[1] == 0:  # no admissible motion: nothing moves, the deficiency is what it is
        return True
    v = Z @ np.linspace(1.0, 2.0, Z.shape[1])
    v /= np.linalg.norm(v)
    h = PROBE * (1.0 + np.abs(q0).max())
    for sign in (1.0, -1.0):
        q = onto_positions(q0 + sign * h * v, matrix, residual, holonomic, 20, 1e-13, RANK_TOL)
        if q is None:
            return False
        found = independent_rows(matrix(q))
        if found is None or A0.shape[0] - found.size != k0:
            return False
    return True


def onto_positions(
    q: np.ndarray,
    matrix: Callable[[np.ndarray], np.ndarray],
    residual: Callable[[np.ndarray], np.ndarray],
    holonomic: np.ndarray,
    iterations: int,
    stop: float,
    cond: float,
) -> np.ndarray | None:
    """q brought onto the position rows f = 0 by Gauss–Newton with minimum-norm steps (least
    squares with the singular-value cutoff ``cond``: dependent rows allowed), until max |f| <
    ``stop`` (1 + max |q|) or ``iterations`` steps; None where A or f is not finite.

    Examples
    --------
    >>> q = onto_positions(np.array([0.3, 0.4]), lambda q: 2 * q[None, :],
    ...                    lambda q: np.array([q @ q - 1.0]), np.array([True]), 20, 1e-14, 1e-10)
    >>> round(float(q @ q), 12)
    1.0
    """
    for _ in range(iterations):
        A = matrix(q)
        f = np.where(holonomic, residual(q), 0.0)
        if not (np.isfinite(A).all() and np.isfinite(f).all()):
            return None
        if not holonomic.any() or np.abs(f).max() < stop * (1.0 + np.abs(q).max()):
            break
        q = q - scipy.linalg.lstsq(A[holonomic], f[holonomic], cond=cond, lapack_driver="gelsy")[0]
    return q


def dense_rows(K: object, n: int, t: float) -> np.ndarray:
    """A of an augmented matrix K (dense or sparse) as a dense array, for the redundancy test;
    a sparse model above :data:`REDUNDANT_DENSE` unknowns is refused (its rows are not
    searched)."""
    if not sps.issparse(K):
        return np.asarray(K)[n:, :n]
    if K.shape[0] > REDUNDANT_DENSE:  # type: ignore[attr-defined]
        raise ConstraintError(
            f"the augmented matrix is singular at t = {t:g} and the model is too large "
            f"({K.shape[0]} unknowns) to search its constraints for redundant rows: remove the "  # type: ignore[attr-defined]
            "dependent constraints (equations() names those that depend on one another everywhere)"
        )
    return sps.csr_matrix(K)[n:, :n].toarray()
