"""The KKT solve: one interface, four solvers, one rank-loss floor.

Every numeric model solves, at a state, the augmented (KKT) system

    M q̈ − Aᵀλ = F,   A q̈ = c          (F = Q − h, c = −(Ȧq̇ + ḃ) and Baumgarte terms)

through a :class:`KKTSolver` chosen once, when the model is built:

``range-space`` (:class:`RangeSpaceSolver`, dense general models)
    y = M⁻¹F, Z = M⁻¹Aᵀ, S = A Z, λ = S⁻¹(c − A y), q̈ = y + Zλ by Cholesky factorizations, with
    the pivots of S floored (below). Falls back to ``lu`` where M is not positive definite.
``lu`` (:class:`LUSolver`, dense)
    LAPACK ``gesv`` on the whole augmented matrix, least squares where it is singular. The mode of
    a model whose M is singular (quaternion coordinates): no factorization of M is needed.
``sparse`` (:class:`SparseSolver`, large general models and any family)
    SuperLU on the augmented matrix in CSC, with the fill-reducing column ordering (COLAMD) of
    the first factorization reused for every later one.
``triangular`` (:class:`pfaff.numeric.triangular.TriangularSolver`, families)
    O(N) null-space elimination through a square banded triangular block of A (the ring).

**The floor.** Where a linkage folds flat (a four-bar with all links collinear) a row of A
vanishes and S becomes singular; close to such a configuration an exact solve turns a tiny drift
off the constraint manifold into a huge acceleration across the branches, and the motion jumps
to another branch. So the j-th pivot d of the Cholesky factorization of S is floored,

    d  ->  d                   where d >= τ_j,
           τ_j/2 + d²/(2τ_j)   below (C¹, at least τ_j/2),

by :func:`floored`: here on arrays (:func:`cholesky_floored`) and in the generated straight-line
code of small systems (:mod:`pfaff.numeric.smallsolve`), the same function. A well-conditioned S
is solved exactly; only the collapsing direction is softened, and on the manifold its constraint
force a·sinθ·λ vanishes with the row anyway. Two thresholds are used:

- The integrators' right-hand side: τ_j = ``FLOOR`` · min(s_j, max diag S) per constraint row,
  where s_j is the row's own size A_j M⁻¹ A_jᵀ at the initial state (:func:`row_scales`; raised
  as a running maximum while a row starts collapsed, see :class:`pfaff.numeric.model.AccelerationField`).
  A row is softened only when it has shrunk against itself while another row has not — not because
  it belongs to a heavy body, a short link or carries a small constant factor, and not when all
  rows shrink together (a one-row system is never floored). Runge–Kutta stages lie off the manifold and
  a small floor lets their drift through amplified: on the four-bar of
  ``tests/integrate/test_simulate_fourbar.py`` at rtol = 5e-13 … 5e-12, FLOOR = 1e-5 kept the angle to
  4e-12 … 3e-11 through four folds, 1e-6 to 4e-12 … 2e-8, 1e-8 to 7e-9 … 1e-6. The
  mass-orthogonal projection after each step (:mod:`pfaff.numeric.projection`) restores the constraint
  impulse the softened row missed.
- A single state asked for by a user (``accelerations``, the values a trajectory reports):
  τ = ``STATE_FLOOR`` · max diag S at the level of rounding, where the exact solve is as accurate
  as double precision allows (an error of about ε·|q̇|²/|row| in q̈ where a row has shrunk).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.linalg
import scipy.sparse as sps
import scipy.sparse.linalg as spla

FLOOR = 1e-5  # τ_j / s_j in the integrators' right-hand side
ZERO_ROW = 1e-12  # a row's reference size is at least this fraction of the largest
RESCALE_BELOW = 1e-3  # rows this much smaller than the largest get their reference refreshed
STATE_FLOOR = 1e-15  # τ / max diag S for a single state
_potrf = scipy.linalg.lapack.dpotrf
_potrs = scipy.linalg.lapack.dpotrs
_trtrs = scipy.linalg.lapack.dtrtrs
_gesv = scipy.linalg.lapack.dgesv


def floored(d: float, tau: float) -> float:
    """The pivot floor: d where d >= τ, else τ/2 + d²/(2τ) (C¹, at least τ/2; d < 0 counts as 0).

    Examples
    --------
    >>> floored(3.0, 1.0), floored(0.0, 1.0), floored(-5.0, 1.0)
    (3.0, 0.5, 0.5)
    """
    if d >= tau:
        return d
    d = max(d, 0.0)
    return 0.5 * tau + d * d / (2.0 * tau)


def floored_array(d: np.ndarray, tau: np.ndarray | float) -> np.ndarray:
    """:func:`floored`, elementwise.

    Examples
    --------
    >>> floored_array(np.array([3.0, 0.0, -5.0]), 1.0).tolist()
    [3.0, 0.5, 0.5]
    """
    tau = np.asarray(tau, dtype=float)
    low = np.maximum(d, 0.0)
    return np.where(d >= tau, d, 0.5 * tau + low * low / (2.0 * np.where(tau > 0, tau, 1.0)))


def augmentation_weight(M: np.ndarray, A: np.ndarray) -> float:
    """ρ of the augmented Lagrangian M + ρAᵀA (a singular M, as quaternions make it): the size
    of M's diagonal against AᵀA's, so that neither term swamps the other.

    Examples
    --------
    >>> augmentation_weight(np.diag([0.0, 4.0]), np.array([[2.0, 0.0]]))
    1.0
    """
    return float(np.abs(np.diag(M)).max() / max((A * A).sum(axis=0).max(), 1e-300))


def row_scales(M: np.ndarray, A: np.ndarray) -> np.ndarray:
    """Sizes s_i = A_i M⁻¹ A_iᵀ of the constraint rows (at least 1e-12 of the largest).

    Examples
    --------
    >>> row_scales(np.eye(2), np.array([[3.0, 4.0], [0.0, 1e-3]])).tolist()
    [25.0, 1e-06]
    """
    d = np.einsum("ij,ji->i", A, np.linalg.solve(M, A.T)) if A.shape[0] else np.zeros(0)
    return np.maximum(d, ZERO_ROW * d.max(initial=0.0))


def cholesky_floored(S: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of S with the j-th pivot floored at τ_j (:func:`floored`).

    Parameters
    ----------
    S : ndarray, shape (..., m, m)
        Symmetric positive semidefinite.
    tau : ndarray, shape (..., m)

    Examples
    --------
    A rank-one S: the second pivot is 0 and floored to τ/2.

    >>> L = cholesky_floored(np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([0.02, 0.02]))
    >>> np.round(L, 12).tolist()
    [[1.0, 0.0], [1.0, 0.1]]
    """
    m = S.shape[-1]
    L = np.zeros_like(S)
    for j in range(m):
        lj = L[..., j, :j]
        d = S[..., j, j] - np.einsum("...k,...k->...", lj, lj)
        # a zero threshold (S = 0: no constraint has a gradient) leaves a zero pivot: λ is then
        # not finite, which the models report as a singular system
        L[..., j, j] = np.sqrt(floored_array(d, tau[..., j]))
        if j + 1 < m:
            below = S[..., j + 1 :, j] - np.einsum("...ik,...k->...i", L[..., j + 1 :, :j], lj)
            L[..., j + 1 :, j] = below / L[..., j, j, None]
    return L


def _cholesky_solve(L: np.ndarray, r: np.ndarray) -> np.ndarray:
    """(L Lᵀ)⁻¹ r for lower L of shape (..., m, m), r (..., m)."""
    m = L.shape[-1]
    z = np.zeros_like(r)
    for i in range(m):
        z[..., i] = (r[..., i] - np.einsum("...k,...k->...", L[..., i, :i], z[..., :i])) / L[
            ..., i, i
        ]
    x = np.zeros_like(r)
    for i in reversed(range(m)):
        acc = np.einsum("...k,...k->...", L[..., i + 1 :, i], x[..., i + 1 :])
        x[..., i] = (z[..., i] - acc) / L[..., i, i]
    return x


def _floored_lambda(S: np.ndarray, r: np.ndarray, floor: float, scales) -> np.ndarray:
    """λ = S⁻¹ r with the pivots of S (row-scaled by ``scales``) floored."""
    if scales is not None:  # τ_j = floor · min(s_j, max diag S): rows shrinking together stay exact
        top = np.max(np.diagonal(S, axis1=-2, axis2=-1), axis=-1)
        w = 1.0 / np.sqrt(np.minimum(scales, np.maximum(top, 1e-300)))
        S = S * w[:, None] * w[None, :]
        r = r * w
        tau = np.full(S.shape[:-1], float(floor))
    else:
        w = None
        top = np.max(np.diagonal(S, axis1=-2, axis2=-1), axis=-1)
        tau = np.broadcast_to((floor * top)[..., None], S.shape[:-1])
    lam: np.ndarray | None = None
    if S.ndim == 2:  # LAPACK first: when no pivot is below its τ this is the floored solve
        chol, info = _potrf(S, lower=1)
        if info == 0 and (np.diagonal(chol) ** 2 >= tau).all():
            lam = _potrs(chol, r, lower=1)[0]
    if lam is None:
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = _cholesky_solve(cholesky_floored(S, tau), r)
    return lam * w if w is not None else lam


def solve_floored(
    M: np.ndarray,
    A: np.ndarray,
    F: np.ndarray,
    c: np.ndarray,
    floor: float = STATE_FLOOR,
    scales: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """q̈ and λ of M q̈ = F + Aᵀλ, A q̈ = c by the range-space method with the floor.

    Parameters
    ----------
    M : ndarray, shape (..., n, n)
        Positive definite mass matrices.
    A : ndarray, shape (..., m, n)
    F : ndarray, shape (..., n)
        Q − h.
    c : ndarray, shape (..., m)
        The constraint rows' right-hand side, −(Ȧq̇ + ḃ) (and Baumgarte terms).
    floor : float
        Without ``scales``: τ / max diag S. With them: the floor of diag(s)^(-1/2) S diag(s)^(-1/2).
    scales : ndarray, shape (m,), optional
        Reference row sizes (:func:`row_scales`).

    Returns
    -------
    qdd : ndarray, shape (..., n)
    lam : ndarray, shape (..., m)

    Raises
    ------
    numpy.linalg.LinAlgError
        M is singular (a coordinate without inertia): use the full augmented matrix instead.

    Examples
    --------
    A pendulum rod along (0.6, -0.8) and a folded one whose row vanishes:

    >>> M = np.eye(2)
    >>> qdd, lam = solve_floored(M, np.array([[0.6, -0.8]]), np.array([0.0, -9.81]), np.array([-1.0]))
    >>> [round(float(v), 4) for v in qdd], round(float(lam[0]), 4)
    ([-5.3088, -2.7316], -8.848)
    >>> qdd, lam = solve_floored(M, np.array([[1.0, 0.0], [0.0, 0.0]]), np.zeros(2), np.zeros(2))
    >>> qdd.tolist(), lam.tolist()
    ([0.0, 0.0], [0.0, 0.0])
    """
    m = A.shape[-2]
    if M.ndim == 2:  # one state, LAPACK straight: M = L Lᵀ, W = L⁻¹Aᵀ, S = WᵀW
        L, info = _potrf(M, lower=1)
        if info != 0:
            raise np.linalg.LinAlgError("the mass matrix is not positive definite")
        y = _trtrs(L, _trtrs(L, F, lower=1)[0], lower=1, trans=1)[0]
        if m == 0:
            return y, np.zeros(0)
        W = _trtrs(L, A.T, lower=1)[0]
        lam = _floored_lambda(W.T @ W, c - A @ y, floor, scales)
        return y + _trtrs(L, W @ lam, lower=1, trans=1)[0], lam
    At = np.swapaxes(A, -1, -2)
    Y = np.linalg.solve(M, np.concatenate([F[..., None], At], axis=-1))
    y, Z = Y[..., 0], Y[..., 1:]
    if m == 0:
        return y, np.zeros((*F.shape[:-1], 0))
    S = A @ Z
    S = 0.5 * (S + np.swapaxes(S, -1, -2))
    lam = _floored_lambda(S, c - np.einsum("...ij,...j->...i", A, y), floor, scales)
    return y + np.einsum("...ij,...j->...i", Z, lam), lam


# ---------------------------------------------------------------------- the interface
class SingularKKT(np.linalg.LinAlgError):
    """The augmented matrix is singular here; ``dead_rows`` are constraints with no gradient at
    all, ``inconsistent`` tells that no acceleration satisfies the constraints."""

    def __init__(self, detail: str = "", dead_rows: np.ndarray | None = None) -> None:
        super().__init__(detail)
        self.detail = detail
        self.dead_rows = np.zeros(0, dtype=np.int64) if dead_rows is None else dead_rows


@dataclass
class KKTSystem:
    """M q̈ − Aᵀλ = F, A q̈ = c at one state, in the form the model's solver takes.

    Attributes
    ----------
    F : ndarray, shape (n,)
    c : ndarray, shape (m,), or None for zero
    K : ndarray or scipy.sparse.csc_matrix, shape (n+m, n+m), optional
        The assembled symmetric augmented matrix [[M, Aᵀ], [A, 0]] (dense and sparse solvers).
    mvals, avals : list, optional
        Values of the mass and constraint entries per block of a family model (the triangular
        solver, which never assembles M or A).
    """

    F: np.ndarray
    c: np.ndarray | None
    K: np.ndarray | sps.csc_matrix | None = None
    mvals: list | None = None
    avals: list | None = None


class KKTSolver(ABC):
    """Solves a :class:`KKTSystem` for q̈ and λ. Subclasses: one per idea (module docstring)."""

    name: ClassVar[str]

    @abstractmethod
    def solve(
        self,
        system: KKTSystem,
        *,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
        out: np.ndarray | None = None,
        multipliers: bool = True,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """q̈ (n,) and λ (m,; None unless ``multipliers``); q̈ written to ``out`` when given.

        ``floor`` and ``scales`` are the rank-loss floor's (module docstring), used by the
        solvers that have one. Raises :class:`SingularKKT` where the system has no unique q̈.
        """

    @staticmethod
    def _rhs(system: KKTSystem, m: int) -> np.ndarray:
        return np.concatenate([system.F, np.zeros(m) if system.c is None else system.c])

    @staticmethod
    def _split(sol: np.ndarray, n: int, out, multipliers: bool) -> tuple:
        qdd = sol[:n]
        if out is not None:
            out[:] = qdd
            qdd = out
        return qdd, -sol[n:] if multipliers else None


class LUSolver(KKTSolver):
    """LAPACK ``gesv`` on the dense augmented matrix; least squares where it is singular.

    ``gesv`` straight, not ``numpy.linalg.solve``, whose checks cost four times the solve of a
    3×3 system.
    """

    name = "lu"

    def __init__(self, n: int, m: int) -> None:
        self.n, self.m = n, m

    def solve(self, system, *, floor=STATE_FLOOR, scales=None, out=None, multipliers=True):
        K, rhs = system.K, self._rhs(system, self.m)
        sol, info = _gesv(K, rhs)[2:]
        if info != 0:
            sol = self._least_squares(K, rhs)
        return self._split(sol, self.n, out, multipliers)

    def _least_squares(self, K: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """Redundant constraints at this configuration (a linkage folded flat): if the equations
        are consistent, the minimum-norm solution keeps the unique q̈ and the minimum-norm λ."""
        A = K[self.n :, : self.n]
        dead = np.flatnonzero(np.abs(A).max(axis=1, initial=0.0) == 0.0)
        if dead.size:
            raise SingularKKT("a constraint has a zero gradient here", dead)
        sol = np.linalg.lstsq(K, rhs, rcond=1e-12)[0]
        if np.linalg.norm(K @ sol - rhs) > 1e-8 * (1.0 + np.linalg.norm(rhs)):
            raise SingularKKT("inconsistent equations")
        return sol


class RangeSpaceSolver(KKTSolver):
    """The range-space method with the floor (:func:`solve_floored`); ``lu`` where M is not
    positive definite.

    Why it is here: it passes configurations where A loses rank (the floor), which LU cannot.
    Small systems run the same algorithm as generated straight-line code
    (:mod:`pfaff.numeric.smallsolve`).
    """

    name = "range-space"

    def __init__(self, n: int, m: int) -> None:
        self.n, self.m = n, m
        self.lu = LUSolver(n, m)

    def solve(self, system, *, floor=STATE_FLOOR, scales=None, out=None, multipliers=True):
        K, n = system.K, self.n
        c = np.zeros(self.m) if system.c is None else system.c
        try:
            qdd, lam = solve_floored(K[:n, :n], K[n:, :n], system.F, c, floor, scales)
        except np.linalg.LinAlgError:
            return self.lu.solve(system, out=out, multipliers=multipliers)
        if out is not None:
            out[:] = qdd
            qdd = out
        return qdd, lam if multipliers else None


class SparseSolver(KKTSolver):
    """SuperLU on the augmented matrix in CSC (a pattern fixed when the model is built).

    The first solve orders the columns by COLAMD; later solves factor K Pc, its columns already
    in that order, with the natural ordering: the fill stays the first factorization's (at
    N = 4096 on the ring, 45,051 entries for every factorization, against 4,241,406 from the
    second on when the ordering was applied inverted). CHOLMOD (scikit-sparse) or QDLDL would need a
    compiled dependency for a path that is not the fast one, so they are not used.

    Attributes
    ----------
    fill : int or None
        Entries SuperLU stores for L and U of the last factorization (``SuperLU.nnz``); None
        before the first solve.
    """

    name = "sparse"

    def __init__(self, n: int, m: int) -> None:
        self.n, self.m = n, m
        self.perm: np.ndarray | None = None
        self.iperm: np.ndarray | None = None
        self.fill: int | None = None

    def solve(self, system, *, floor=STATE_FLOOR, scales=None, out=None, multipliers=True):
        K, rhs = system.K, self._rhs(system, self.m)
        try:
            if self.perm is None:
                lu = spla.splu(K, permc_spec="COLAMD")
                self.perm = lu.perm_c.copy()
                self.iperm = np.argsort(self.perm)
                sol = lu.solve(rhs)
            else:  # K Pc = K[:, argsort(perm)]; x = Pc y: x_i = y[perm_i]
                lu = spla.splu(K[:, self.iperm], permc_spec="NATURAL")
                sol = lu.solve(rhs)[self.perm]
        except RuntimeError as e:  # "Factor is exactly singular"
            raise SingularKKT(str(e)) from None
        self.fill = int(lu.nnz)
        if not math.isfinite(float(sol.sum())):
            raise SingularKKT("the factorization gave a non-finite solution")
        return self._split(sol, self.n, out, multipliers)
