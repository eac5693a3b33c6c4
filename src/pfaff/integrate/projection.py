"""Coordinate projection onto the constraint manifold f(q, t) = 0, A(q, t) q̇ + b = 0.

A state off the manifold is moved to the nearest state on it in the metric of the mass matrix
(a mass-orthogonal projection: the velocity correction is the impulse the constraints would apply,
and it removes kinetic energy only from the forbidden directions):

    position:  Δq = −W⁻¹Aᵀ (A W⁻¹Aᵀ + δ²I)⁻¹ f,   Newton-iterated until |f| <= tol
    velocity:  Δq̇ = −W⁻¹Aᵀ (A W⁻¹Aᵀ + δ²I)⁻¹ (A q̇ + b)

with W = M. A singular M (a coordinate without inertia) is replaced by M + κAᵀA, which gives the
same projection when M is definite on the admissible motions; large sparse models use the
diagonal of M. The damping δ = 1e-7 σ_max (Tikhonov) matters only where the constraint Jacobian
loses rank — a linkage folded flat: there the correction along the collapsing direction stays
bounded, and once the linkage has passed the fold the mass-orthogonal projection restores the
constraint impulse that the floored acceleration solve (:mod:`pfaff.numeric.kkt`) softened. Dense
matrices go to LAPACK, sparse ones to SuperLU. A model may supply its own
``project(t, q, qd, tol=, max_iter=)`` (structured O(N) solvers do).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse as sps
import scipy.sparse.linalg as spla

DAMPING = 1e-7  # δ / σ_max
SHRUNK = 1e-4  # smallest relative row norm that tightens a row's residual test
q_arr = np.array
_gesv = scipy.linalg.lapack.dgesv


def _damped_solve(G: np.ndarray, r: np.ndarray) -> np.ndarray:
    G = G.copy()
    G.flat[:: G.shape[0] + 1] += DAMPING**2 * max(G.trace(), 1e-300)
    y, info = _gesv(G, r)[2:]
    if info != 0:
        y = np.linalg.lstsq(G, r, rcond=None)[0]
    return y


def _correction(A: np.ndarray | sps.spmatrix, W: Any, r: np.ndarray) -> np.ndarray:
    """W⁻¹Aᵀ (A W⁻¹ Aᵀ + δ²I)⁻¹ r: the damped minimum-W-norm Δ with A Δ ≈ r.

    ``W`` is a 1-D diagonal (sparse A) or a Cholesky factor from :func:`_metric` (dense A).
    """
    if sps.issparse(A):
        A = sps.csr_matrix(A)
        Ad = A @ sps.diags(1.0 / W)
        G = (Ad @ A.T).tocsc()
        delta2 = DAMPING**2 * max(G.diagonal().max(initial=0.0), 1e-300)
        lu = spla.splu((G + delta2 * sps.identity(G.shape[0], format="csc")).tocsc())
        return Ad.T @ lu.solve(r)
    Z = scipy.linalg.cho_solve(W, A.T)
    return Z @ _damped_solve(A @ Z, r)


def diagonal_weights(M: Any) -> np.ndarray:
    """The diagonal of a (dense or sparse) M, with unit weight for a coordinate without inertia.

    Examples
    --------
    >>> diagonal_weights(np.diag([2.0, 0.0])).tolist()
    [2.0, 1.0]
    """
    d = np.array(M.diagonal(), dtype=float)
    d[~(d > 0)] = 1.0
    return d


def _metric(M: Any, A: np.ndarray | sps.spmatrix) -> Any:
    """Cholesky factor of the projection metric: M, or M + κAᵀA if M is singular, or diag.

    A sparse model's diagonal (1-D ``M``) is its own metric.
    """
    if np.ndim(M) == 1:
        return M
    try:
        return scipy.linalg.cho_factor(M)
    except np.linalg.LinAlgError:
        pass
    kappa = max(np.trace(M), 1.0) / max(float(np.sum(A * A)), 1e-300)
    try:
        return scipy.linalg.cho_factor(M + kappa * A.T @ A)
    except np.linalg.LinAlgError:
        return scipy.linalg.cho_factor(np.diag(diagonal_weights(M)))


def residuals(model: Any, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(f, A q̇ + b) of any numeric model: its unchecked ``_residual`` when it has one."""
    fn = getattr(model, "_residual", None)
    return fn(t, q, qd) if fn is not None else model.constraint_residual(t, q, qd)


class Projector:
    """Project states onto the constraint manifold of a numeric model.

    Parameters
    ----------
    model : NumericModel
        Or any model with ``_kkt`` / ``_residual`` (or its own ``project``).
    tol : float
        Target max |f| and max |A q̇ + b|.
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

    def __init__(self, model: Any, *, tol: float = 1e-12, max_iter: int = 8) -> None:
        self.model, self.tol, self.max_iter = model, tol, max_iter
        self.custom = getattr(model, "project", None)
        self.holonomic = np.asarray(model.holonomic, dtype=bool)
        self.stats = {"projections": 0, "projection_iterations": 0}

    def _matrices(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """A, M (dense) or diag M (sparse), f (holonomic rows) and g at a state."""
        K, _, _, _, f, g = self.model._kkt(t, q, qd)
        n = self.model.n
        if sps.issparse(K):
            K = sps.csr_matrix(K)
            A, M = K[n:, :n], diagonal_weights(K[:n, :n])
        else:
            A, M = K[n:, :n], K[:n, :n]
        return A, M, np.where(self.holonomic, f, 0.0), g

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """The projected (q, qd) and whether anything changed.

        The test is per row: |f_i| and |g_i| at most tol·w_i, w_i = clip(|A_i| / max_j |A_j|,
        1e-4, 1). A row that has shrunk (a linkage close to a fold) is held tighter, since the
        same residual there stands for a larger step off the branch.
        """
        if self.model.m == 0:
            return q, qd, False
        if self.custom is not None:
            qn, qdn, it = self.custom(t, q, qd, tol=self.tol, max_iter=self.max_iter)
            self._count(it)
            return qn, qdn, it > 0
        fk = getattr(self.model, "_fused", None)
        if fk is not None:  # small systems: plain Python floats, no arrays
            out = self._small(fk, t, q.tolist(), qd.tolist())
            if out is not None:
                return out
        A, M, f, g = self._matrices(t, q, qd)
        thr = self._thresholds(A)
        if max(np.max(np.abs(f) / thr), np.max(np.abs(g) / thr)) <= 1.0:
            return q, qd, False
        q, qd = q.copy(), qd.copy()
        it, last = 0, np.inf
        while (err := np.max(np.abs(f) / thr)) > 1.0 and it < self.max_iter and err < last:
            q -= _correction(A, _metric(M, A), f)  # Newton, with the Jacobian at the current q
            it, last = it + 1, err
            A, M, f, g = self._matrices(t, q, qd)
        # g is linear in q̇: one correction is exact up to the damping, which can leave a row much
        # smaller than the largest short of its test; a few more passes finish it
        W, last = None, np.inf
        for _ in range(self.max_iter):
            err = np.max(np.abs(g) / thr)
            if err <= 1.0 or err >= last:
                break
            W = _metric(M, A) if W is None else W
            qd -= _correction(A, W, g)
            last = err
            g = residuals(self.model, t, q, qd)[1]
        self._count(max(it, 1))
        return q, qd, True

    def _thresholds(self, A: np.ndarray | sps.spmatrix) -> np.ndarray:
        """tol · clip(|A_i| / max_j |A_j|, 1e-4, 1) per row."""
        sq = np.asarray(A.multiply(A).sum(axis=1)).ravel() if sps.issparse(A) else (A * A).sum(1)
        norms = np.sqrt(sq)
        return self.tol * np.clip(norms / max(norms.max(), 1e-300), SHRUNK, 1.0)

    def _small(self, fk: Any, t: float, q: list, qd: list) -> tuple | None:
        """The projection of a fused small model; None to take the general path (M singular)."""
        n, m, p, tol = self.model.n, self.model.m, self.model._p, self.tol
        rows = fk.arows
        nMA = fk.offsets[0]  # qfn: M and A entries first, then f and g

        def excess(v: list) -> tuple[float, float]:
            sq = [0.0] * m
            for i, a in zip(rows, v[nMA - len(rows) : nMA], strict=True):
                sq[i] += a * a
            top = max(sq) or 1e-300
            thr = [tol * min(1.0, max(SHRUNK, math.sqrt(x / top))) for x in sq]
            f, g = v[nMA : nMA + m], v[nMA + m :]
            return (
                max(abs(a) / b for a, b in zip(f, thr, strict=True)),
                max(abs(a) / b for a, b in zip(g, thr, strict=True)),
            )

        v = fk.qfn(t, *q, *qd, *p)
        ef, eg = excess(v)
        if max(ef, eg) <= 1.0:
            return q_arr(q), q_arr(qd), False
        zeros = [0.0] * n
        shift = DAMPING**2
        it, last = 0, math.inf
        try:
            while ef > 1.0 and it < self.max_iter and ef < last:
                dq = fk.cfn(*v[:nMA], *zeros, *v[nMA : nMA + m], shift)
                q = [a - b for a, b in zip(q, dq, strict=True)]
                it, last = it + 1, ef
                v = fk.qfn(t, *q, *qd, *p)
                ef, eg = excess(v)
            last = math.inf
            for _ in range(self.max_iter):  # see the general path
                if eg <= 1.0 or eg >= last:
                    break
                dv = fk.cfn(*v[:nMA], *zeros, *v[nMA + m :], shift)
                qd = [a - b for a, b in zip(qd, dv, strict=True)]
                last = eg
                v = fk.qfn(t, *q, *qd, *p)
                ef, eg = excess(v)
        except (ValueError, ZeroDivisionError):
            return None
        self._count(max(it, 1))
        return q_arr(q), q_arr(qd), True

    def _count(self, it: int) -> None:
        if it:
            self.stats["projections"] += 1
            self.stats["projection_iterations"] += it

    def residual(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """max(|f|, |A q̇ + b|) at a state."""
        f, g = residuals(self.model, t, q, qd)
        return float(
            max(np.abs(np.where(self.holonomic, f, 0.0)).max(initial=0), np.abs(g).max(initial=0))
        )
