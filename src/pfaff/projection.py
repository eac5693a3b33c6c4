"""Coordinate projection onto the constraint manifold f(q, t) = 0, A(q, t) q̇ + b = 0.

A state off the manifold is moved to the nearest state on it in the metric of the mass matrix's
diagonal D (so that lengths and angles are weighed by their inertia):

    position:  Δq = −D⁻¹Aᵀ (A D⁻¹Aᵀ + δ²I)⁻¹ f,   Newton-iterated until |f| <= tol
    velocity:  Δq̇ = −D⁻¹Aᵀ (A D⁻¹Aᵀ + δ²I)⁻¹ (A q̇ + b)

The damping δ = 1e-7 σ_max (Tikhonov: the pseudo-inverse of A D^{-1/2} with filter factors
σ/(σ² + δ²)) matters only where the constraint Jacobian loses rank — a linkage folded flat: there
the correction along the degenerate direction stays bounded. (This does not keep a linkage on its
branch through a fold: the acceleration-level KKT solve itself is singular there; see the xfail
tests in tests/test_simulate_fourbar.py.) Dense matrices go to LAPACK, sparse ones to SuperLU. A model may supply its own
``project(t, q, qd, tol=, max_iter=)`` (structured O(N) solvers do).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse as sps
import scipy.sparse.linalg as spla

DAMPING = 1e-7  # δ / σ_max
q_arr = np.array
_gesv = scipy.linalg.lapack.dgesv


def _correction(A: np.ndarray | sps.spmatrix, d: np.ndarray, r: np.ndarray) -> np.ndarray:
    """D⁻¹Aᵀ (A D⁻¹ Aᵀ + δ²I)⁻¹ r: the damped minimum-D-norm Δ with A Δ ≈ r."""
    if sps.issparse(A):
        A = sps.csr_matrix(A)
        Ad = A @ sps.diags(1.0 / d)
        G = (Ad @ A.T).tocsc()
        delta2 = DAMPING**2 * max(G.diagonal().max(initial=0.0), 1e-300)
        lu = spla.splu((G + delta2 * sps.identity(G.shape[0], format="csc")).tocsc())
        return Ad.T @ lu.solve(r)
    Ad = A / d
    G = Ad @ A.T
    G.flat[:: G.shape[0] + 1] += DAMPING**2 * max(G.trace(), 1e-300)
    y, info = _gesv(G, r)[2:]
    if info != 0:
        y = np.linalg.lstsq(G, r, rcond=None)[0]
    return Ad.T @ y


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
        fk = getattr(self.model, "_fused", None)
        if fk is not None:
            A, f, g, d = fk.pfn(t, *q.tolist(), *qd.tolist(), *self.model._p)
            d = np.array(d)
            d[~(d > 0)] = 1.0
            return np.array(A), d, np.array(f), np.array(g)
        K, _, _, _, f, g = self.model._kkt(t, q, qd)
        n = self.model.n
        if sps.issparse(K):
            K = sps.csr_matrix(K)
            d, A = K[:n, :n].diagonal(), K[n:, :n]
        else:
            d, A = np.diag(K)[:n].copy(), K[n:, :n]
        d[~(d > 0)] = 1.0  # a coordinate without inertia of its own: unit weight
        return A, d, np.where(self.holonomic, f, 0.0), g

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """The projected (q, qd) and whether anything changed."""
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
        A, d, f, g = self._matrices(t, q, qd)
        if max(np.abs(f).max(), np.abs(g).max()) <= self.tol:
            return q, qd, False
        q, qd = q.copy(), qd.copy()
        it, last = 0, np.inf
        while (err := np.abs(f).max()) > self.tol and it < self.max_iter and err < last:
            q -= _correction(A, d, f)  # Newton, with the Jacobian at the current q
            it, last = it + 1, err
            A, d, f, g = self._matrices(t, q, qd)
        if np.abs(g).max() > self.tol:
            qd -= _correction(A, d, g)  # exact up to the damping: g is linear in q̇
        self._count(max(it, 1))
        return q, qd, True

    def _small(self, fk: Any, t: float, q: list, qd: list) -> tuple | None:
        """The projection of a fused small model; None to take the general path (rank loss)."""
        n, m, p, tol = self.model.n, self.model.m, self.model._p, self.tol
        v = fk.qfn(t, *q, *qd, *p)
        nA = len(v) - n - 2 * m
        f, g = v[n + nA : n + nA + m], v[n + nA + m :]
        if max(map(abs, f + g)) <= tol:
            return q_arr(q), q_arr(qd), False
        zeros = [0.0] * n
        shift = DAMPING**2
        it = 0
        try:
            while max(map(abs, f)) > tol and it < self.max_iter:
                d = [x if x > 0 else 1.0 for x in v[:n]]
                dq = fk.cfn(*d, *v[n : n + nA], *zeros, *f, shift)
                q = [a - b for a, b in zip(q, dq, strict=True)]
                it += 1
                v = fk.qfn(t, *q, *qd, *p)
                f, g = v[n + nA : n + nA + m], v[n + nA + m :]
            if max(map(abs, g)) > tol:
                d = [x if x > 0 else 1.0 for x in v[:n]]
                dv = fk.cfn(*d, *v[n : n + nA], *zeros, *g, shift)
                qd = [a - b for a, b in zip(qd, dv, strict=True)]
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
