"""The projection onto the constraint manifold f(q, t) = 0, A(q, t) q̇ + b = 0: one algorithm.

A state off the manifold is moved to the nearest state on it in a metric W (a model's: the mass
matrix, so that the velocity correction is the impulse the constraints would apply, and it removes
kinetic energy only from the forbidden directions):

    position:  Δq = −W⁻¹Aᵀ (A W⁻¹Aᵀ + δ²I)⁻¹ f,   Newton, the Jacobian at the current q
    velocity:  Δq̇ = −W⁻¹Aᵀ (A W⁻¹Aᵀ + δ²I)⁻¹ (A q̇ + b)

The iteration policy (:func:`newton_projection`), the same for every model and for completing a
state from independent coordinates (:func:`pfaff.integrate.initial.consistent_state`): a row
passes when |f_i| and |g_i| are at most tol·w_i, w_i = clip(|A_i| / max_j |A_j|, 1e-4, 1) (a
row that has shrunk, a linkage close to a fold, is held tighter, since the same residual there
stands for a larger step off the branch); Newton steps until every row passes, ``max_iter`` steps
were made, or the worst row stopped improving; then velocity corrections the same way (g is linear
in q̇: one is exact up to the damping, which can leave a row much smaller than the largest short
of its test).

The corrections come from the model (:meth:`pfaff.numeric.protocol.DynamicsModel.linearize_constraints`).
For dense matrices :func:`mass_metric_correction` is the one implementation (sparse and family
models use their KKT solve with zero forcing, the same Δ undamped): W = M, or M + κAᵀA
where M is singular (the same projection when M is definite on the admissible motions), damping
δ = 1e-7 σ_max (Tikhonov), which matters only where A loses rank: there the correction along the
collapsing direction stays bounded, and once a linkage has passed a fold the projection restores
the constraint impulse that the floored acceleration solve (:mod:`pfaff.numeric.kkt`) softened.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sps

from pfaff.numeric.protocol import ConstraintLinearization

if TYPE_CHECKING:
    from pfaff.numeric.protocol import DynamicsModel

DAMPING = 1e-7  # δ / σ_max
SHRUNK = 1e-4  # smallest relative row norm that tightens a row's residual test
_gesv = scipy.linalg.lapack.dgesv

Linearize = Callable[[np.ndarray, np.ndarray], ConstraintLinearization]
Correction = Callable[[np.ndarray], np.ndarray]


def thresholds(row_norms: np.ndarray, tol: float) -> np.ndarray:
    """tol · clip(|A_i| / max_j |A_j|, 1e-4, 1) per row.

    Examples
    --------
    >>> thresholds(np.array([2.0, 1.0, 0.0]), 1e-12).tolist()
    [1e-12, 5e-13, 1e-16]
    """
    return tol * np.clip(row_norms / max(float(row_norms.max(initial=0.0)), 1e-300), SHRUNK, 1.0)


class ArrayLinearization(ConstraintLinearization):
    """A :class:`ConstraintLinearization` on arrays.

    Parameters
    ----------
    f, g : ndarray, shape (m,)
        Position residuals (already 0 on velocity rows) and A q̇ + b.
    row_norms : ndarray, shape (m,), or None
        |A_i|; None when ``thr`` is given.
    tol : float
    correct_positions, correct_velocities : callable
        ``r -> Δ`` with A Δ = r (the position one takes the whole f, zeros on velocity rows).
    velocity_residual : callable
        ``q̇ -> g`` at the same q.
    thr : ndarray, shape (m,), optional
        :func:`thresholds` of the row norms and ``tol``, when the caller has them (a model
        whose A is constant keeps them for a run); not changed here.
    """

    def __init__(
        self,
        f: np.ndarray,
        g: np.ndarray,
        row_norms: np.ndarray | None,
        tol: float,
        correct_positions: Correction,
        correct_velocities: Correction,
        velocity_residual: Correction,
        *,
        thr: np.ndarray | None = None,
    ) -> None:
        if thr is None:
            assert row_norms is not None
            thr = thresholds(row_norms, tol)
        self.f, self.g, self.thr = f, g, thr
        self._cq, self._cv, self._g = correct_positions, correct_velocities, velocity_residual
        self.position_excess = float(np.max(np.abs(f) / self.thr, initial=0.0))
        self.velocity_excess = float(np.max(np.abs(g) / self.thr, initial=0.0))

    def corrected_positions(self, q: np.ndarray) -> np.ndarray:
        return q - self._cq(self.f)

    def corrected_velocities(self, qd: np.ndarray) -> np.ndarray:
        return qd - self._cv(self.g)

    def with_velocities(self, qd: np.ndarray) -> ArrayLinearization:
        self.g = self._g(qd)
        self.velocity_excess = float(np.max(np.abs(self.g) / self.thr, initial=0.0))
        return self


def newton_projection(
    linearize: Linearize, q: np.ndarray, qd: np.ndarray, *, max_iter: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """The projection's iteration policy (module docstring) on any linearization.

    Parameters
    ----------
    linearize : callable
        ``(q, q̇) -> ConstraintLinearization`` (its tolerance fixed by the caller).
    q, qd : ndarray, shape (n,)
    max_iter : int
        Newton steps at most, and velocity passes at most (at least one).

    Returns
    -------
    q, qd : ndarray, shape (n,)
        New arrays when anything changed, else the ones given.
    iterations : int
        Newton steps (at least 1 when only the velocities moved); 0: nothing changed.
    """
    lin = linearize(q, qd)
    if max(lin.position_excess, lin.velocity_excess) <= 1.0:
        return q, qd, 0
    it, last = 0, math.inf
    while (err := lin.position_excess) > 1.0 and it < max_iter and err < last:
        q = lin.corrected_positions(q)  # Newton, with the Jacobian at the current q
        it, last = it + 1, err
        lin = linearize(q, qd)
    last = math.inf
    for _ in range(max(max_iter, 1)):
        err = lin.velocity_excess
        if err <= 1.0 or err >= last:
            break
        qd = lin.corrected_velocities(qd)
        last = err
        lin = lin.with_velocities(qd)
    return q, qd, max(it, 1)


class Projector:
    """Project states of a numeric model onto its constraint manifold (:func:`newton_projection`).

    Parameters
    ----------
    model : DynamicsModel
    tol : float
        Target max |f| and max |A q̇ + b| (per row, see the module docstring).
    max_iter : int
        Newton iterations at most for the positions.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> q, qd, _ = Projector(model)(0.0, np.array([0.6, -0.9]), np.array([1.0, 1.0]))
    >>> bool(abs(q @ q - 1) < 1e-12 and abs(q @ qd) < 1e-12)
    True
    """

    def __init__(self, model: DynamicsModel, *, tol: float = 1e-12, max_iter: int = 8) -> None:
        self.model, self.tol, self.max_iter = model, tol, max_iter
        self.holonomic = np.asarray(model.holonomic, dtype=bool)
        self.stats = {"projections": 0, "projection_iterations": 0}

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """The projected (q, q̇) and whether anything changed."""
        if self.model.m == 0:
            return q, qd, False
        model, tol = self.model, self.tol
        q, qd, it = newton_projection(
            lambda q_, qd_: model.linearize_constraints(t, q_, qd_, tol),
            q,
            qd,
            max_iter=self.max_iter,
        )
        if it:
            self.stats["projections"] += 1
            self.stats["projection_iterations"] += it
        return q, qd, it > 0

    def residual(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """max(|f|, |A q̇ + b|) at a state."""
        f, g = self.model.residual(t, q, qd)
        return float(
            max(np.abs(np.where(self.holonomic, f, 0.0)).max(initial=0), np.abs(g).max(initial=0))
        )


def diagonal_weights(M: np.ndarray | sps.spmatrix) -> np.ndarray:
    """The diagonal of a (dense or sparse) M, with unit weight for a coordinate without inertia.

    Examples
    --------
    >>> diagonal_weights(np.diag([2.0, 0.0])).tolist()
    [2.0, 1.0]
    """
    d = np.array(M.diagonal(), dtype=float)
    d[~(d > 0)] = 1.0
    return d


def _damped_solve(G: np.ndarray, r: np.ndarray) -> np.ndarray:
    G = G.copy()
    G.flat[:: G.shape[0] + 1] += DAMPING**2 * max(G.trace(), 1e-300)
    y, info = _gesv(G, r)[2:]
    if info != 0:
        y = np.linalg.lstsq(G, r, rcond=None)[0]
    return y


def mass_metric_correction(M: np.ndarray, A: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``r -> W⁻¹Aᵀ (A W⁻¹Aᵀ + δ²I)⁻¹ r``, the damped least-W-norm Δ with A Δ ≈ r (dense).

    W = M (Cholesky), or M + κAᵀA where M is singular, or diag M as the last resort. (Sparse and
    family models correct by their KKT solve with zero forcing: the same Δ without damping.)

    Examples
    --------
    >>> correct = mass_metric_correction(np.diag([1.0, 3.0]), np.array([[1.0, 1.0]]))
    >>> np.round(correct(np.array([1.0])), 6).tolist()  # Δ ∝ M⁻¹Aᵀ with Δ_0 + Δ_1 = 1
    [0.75, 0.25]
    """
    try:
        W = scipy.linalg.cho_factor(M)
    except np.linalg.LinAlgError:
        kappa = max(np.trace(M), 1.0) / max(float(np.sum(A * A)), 1e-300)
        try:
            W = scipy.linalg.cho_factor(M + kappa * A.T @ A)
        except np.linalg.LinAlgError:
            W = scipy.linalg.cho_factor(np.diag(diagonal_weights(M)))
    Z = scipy.linalg.cho_solve(W, A.T)
    G = A @ Z
    return lambda r: Z @ _damped_solve(G, r)
