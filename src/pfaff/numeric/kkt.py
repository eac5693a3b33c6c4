"""Solve stage: the augmented system through configurations where the constraint Jacobian loses rank.

    M q̈ = F + Aᵀλ,   A q̈ = c

is solved by the range-space method: y = M⁻¹F, Z = M⁻¹Aᵀ, S = A Z, λ = S⁻¹(c − A y),
q̈ = y + Zλ. Where a linkage folds flat (a four-bar with all links collinear) a row of A
vanishes and S becomes singular; close to such a configuration an exact solve turns a tiny drift
off the constraint manifold into a huge acceleration across the branches, and the motion jumps
to another branch. So the eigenvalues (or Cholesky pivots) e of S are floored:

    e  ->  e                   where e >= τ,
           τ/2 + e²/(2τ)       below (C¹, at least τ/2).

A well-conditioned S is solved exactly; only the collapsing direction is softened, and on the
manifold its constraint force a·sinθ·λ vanishes with the row anyway.

Two floors are used.

- The integrators' right-hand side: τ_i = ``FLOOR`` · min(s_i, max diag S) per constraint row,
  where s_i is the row's own size A_i M⁻¹ A_iᵀ at the initial state (:func:`row_scales`; raised
  as a running maximum while a row starts collapsed, see :class:`pfaff.integrate.integrators.RowReference`).
  A row is softened only when it has shrunk against itself while another row has not — not because
  it belongs to a heavy body, a short link or carries a small constant factor, and not when all
  rows shrink together (a one-row system is never floored). Runge–Kutta stages lie off the manifold and
  a small floor lets their drift through amplified: on the four-bar of
  ``tests/test_simulate_fourbar.py`` at rtol = 5e-13 … 5e-12, FLOOR = 1e-5 kept the angle to
  4e-12 … 3e-11 through four folds, 1e-6 to 4e-12 … 2e-8, 1e-8 to 7e-9 … 1e-6. The
  mass-orthogonal projection after each step (:mod:`pfaff.integrate.projection`) restores the constraint
  impulse the softened row missed.
- A single state asked for by a user (``accelerations``, the values a trajectory reports):
  τ = ``STATE_FLOOR`` · max diag S at the level of rounding, where the exact solve is as accurate
  as double precision allows (an error of about ε·|q̇|²/|row| in q̈ where a row has shrunk).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

FLOOR = 1e-5  # τ_i / s_i in the integrators' right-hand side
ZERO_ROW = 1e-12  # a row's reference size is at least this fraction of the largest
RESCALE_BELOW = 1e-3  # rows this much smaller than the largest get their reference refreshed
STATE_FLOOR = 1e-15  # τ / max diag S for a single state
_potrf = scipy.linalg.lapack.dpotrf
_potrs = scipy.linalg.lapack.dpotrs
_trtrs = scipy.linalg.lapack.dtrtrs


def floored_array(e: np.ndarray, tau: np.ndarray | float) -> np.ndarray:
    """The floor of :func:`pfaff.numeric.smallsolve.floored`, elementwise.

    Examples
    --------
    >>> floored_array(np.array([3.0, 0.0, -5.0]), 1.0).tolist()
    [3.0, 0.5, 0.5]
    """
    tau = np.asarray(tau, dtype=float)
    low = np.maximum(e, 0.0)
    return np.where(e >= tau, e, 0.5 * tau + low * low / (2.0 * np.where(tau > 0, tau, 1.0)))


def row_scales(M: np.ndarray, A: np.ndarray) -> np.ndarray:
    """Sizes s_i = A_i M⁻¹ A_iᵀ of the constraint rows (at least 1e-12 of the largest).

    Examples
    --------
    >>> row_scales(np.eye(2), np.array([[3.0, 4.0], [0.0, 1e-3]])).tolist()
    [25.0, 1e-06]
    """
    d = np.einsum("ij,ji->i", A, np.linalg.solve(M, A.T)) if A.shape[0] else np.zeros(0)
    return np.maximum(d, ZERO_ROW * d.max(initial=0.0))


def solve_floored(
    M: np.ndarray,
    A: np.ndarray,
    F: np.ndarray,
    c: np.ndarray,
    floor: float = STATE_FLOOR,
    scales: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """q̈ and λ of M q̈ = F + Aᵀλ, A q̈ = c with the eigenvalues of A M⁻¹Aᵀ floored.

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
    if M.ndim == 2:
        return _solve_one(M, A, F, c, floor, scales)
    At = np.swapaxes(A, -1, -2)
    Y = np.linalg.solve(M, np.concatenate([F[..., None], At], axis=-1))
    y, Z = Y[..., 0], Y[..., 1:]
    if m == 0:
        return y, np.zeros((*F.shape[:-1], 0))
    S = A @ Z
    S = 0.5 * (S + np.swapaxes(S, -1, -2))
    r = c - np.einsum("...ij,...j->...i", A, y)
    lam = _floored_lambda(S, r, floor, scales)
    return y + np.einsum("...ij,...j->...i", Z, lam), lam


def _solve_one(M, A, F, c, floor, scales) -> tuple[np.ndarray, np.ndarray]:
    """One state with LAPACK straight: M = L Lᵀ, W = L⁻¹Aᵀ, S = WᵀW (half the work of M⁻¹Aᵀ)."""
    L, info = _potrf(M, lower=1)
    if info != 0:
        raise np.linalg.LinAlgError("the mass matrix is not positive definite")
    u = _trtrs(L, F, lower=1)[0]
    y = _trtrs(L, u, lower=1, trans=1)[0]
    if A.shape[0] == 0:
        return y, np.zeros(0)
    W = _trtrs(L, A.T, lower=1)[0]
    S = W.T @ W
    lam = _floored_lambda(S, c - A @ y, floor, scales)
    return y + _trtrs(L, W @ lam, lower=1, trans=1)[0], lam


def _floored_lambda(S: np.ndarray, r: np.ndarray, floor: float, scales) -> np.ndarray:
    """λ = S⁻¹ r with the eigenvalues of S (row-scaled by ``scales``) floored."""
    if scales is not None:  # τ_i = floor · min(s_i, max diag S): rows shrinking together stay exact
        top = np.max(np.diagonal(S, axis1=-2, axis2=-1), axis=-1)
        w = 1.0 / np.sqrt(np.minimum(scales, np.maximum(top, 1e-300)))
        S = S * w[:, None] * w[None, :]
        r = r * w
        tau = np.full(S.shape[:-2], float(floor))
    else:
        w = None
        tau = floor * np.max(np.diagonal(S, axis1=-2, axis2=-1), axis=-1)
    lam: np.ndarray | None = None
    if S.ndim == 2:
        chol, info = _potrf(S, lower=1)
        # all pivots well above τ: S is far from singular and is solved exactly
        if info == 0 and np.diagonal(chol).min() ** 2 >= 100.0 * tau:
            lam = _potrs(chol, r, lower=1)[0]
    if lam is None:
        e, V = np.linalg.eigh(S)
        with np.errstate(divide="ignore", invalid="ignore"):  # S = 0: no constraint acts
            u = np.einsum("...ji,...j->...i", V, r) / floored_array(e, tau[..., None])
        lam = np.einsum("...ij,...j->...i", V, u)
    return lam * w if w is not None else lam
