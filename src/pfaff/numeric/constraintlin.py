"""The constraints of a general model linearized at a state, for the projection.

The projection (:mod:`pfaff.numeric.projection`) corrects positions and velocities by the
mass-metric step M⁻¹Aᵀ(A M⁻¹Aᵀ)⁻¹ r. Small fused systems compute it on Python floats
(:class:`pfaff.numeric.fused.FusedLinearization`); the others on arrays (dense: a Cholesky of M;
sparse: the KKT solve with zero forcing). Where the run's constraints are redundant, the step
comes from its independent rows (the others follow) and the residuals are still every row's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sps

from pfaff.numeric.fused import FusedLinearization
from pfaff.numeric.kkt import KKTSystem
from pfaff.numeric.projection import ArrayLinearization, mass_metric_correction
from pfaff.numeric.protocol import ConstraintLinearization

if TYPE_CHECKING:
    from pfaff.numeric.model import NumericModel


def linearized_constraints(
    model: NumericModel, t: float, q: np.ndarray, qd: np.ndarray, tol: float
) -> ConstraintLinearization:
    """f, g, row norms and corrections at (t, q, q̇) (:class:`ArrayLinearization` or
    :class:`FusedLinearization`)."""
    fk, run = model._fused, model._run_state
    if fk is not None and fk.cfn is not None and not run["full"] and run["rows"] is None:
        try:
            return FusedLinearization(
                fk, t, q.tolist(), qd.tolist(), list(model._p), tol, model._holonomic_list,
                lambda: _on_arrays(model, t, q, qd, tol),
            )  # fmt: skip
        except (ValueError, ArithmeticError, TypeError):
            pass  # not defined or not real here: the array path names the error
    return _on_arrays(model, t, q, qd, tol)


def _on_arrays(
    model: NumericModel, t: float, q: np.ndarray, qd: np.ndarray, tol: float
) -> ArrayLinearization:
    K, _, _, _, f, g = model._kkt(t, q, qd)
    n, cache = model.n, []
    rows = model._run_state["rows"]
    if sps.issparse(K) and rows is not None:
        K = K.toarray()  # (a model with redundant rows is at most REDUNDANT_DENSE large)
    A, M = K[n:, :n], K[:n, :n]
    if sps.issparse(K):  # the KKT solve with zero forcing: M⁻¹Aᵀ(A M⁻¹Aᵀ)⁻¹ r by SuperLU
        sq = np.asarray(A.multiply(A).sum(axis=1)).ravel()
        zeros = np.zeros(n)

        def correct(r: np.ndarray) -> np.ndarray:
            return model._solver.solve(KKTSystem(zeros, r, K), multipliers=False)[0]

    else:
        sq = (A * A).sum(1)

        def correct(r: np.ndarray) -> np.ndarray:
            if not cache:  # redundant rows: the correction of the independent ones
                cache.append(mass_metric_correction(M, A if rows is None else A[rows]))
            return cache[0](r if rows is None else r[rows])

    f = np.where(model.holonomic, f, 0.0)
    return ArrayLinearization(
        f, g, np.sqrt(sq), tol, correct, correct, lambda v: model.residual(t, q, v)[1]
    )
