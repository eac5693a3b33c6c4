"""The inertia check of a dense model: is M positive definite on the admissible motions?

Run at the first state of a simulation (the run's KKT mode) and by every checked
:meth:`pfaff.NumericModel.accelerations`; never in a right-hand side.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg

from pfaff.core.errors import InertiaError

M_PIVOT = 1e-10  # a Cholesky pivot of M below this times max diag M: M is (nearly) singular
_potrf = scipy.linalg.lapack.dpotrf


def inertia_test(K: np.ndarray, t: float, n: int, m: int, names: Sequence[str]) -> bool:
    """The test of :meth:`check_determined` on a dense K: True when M is not safely definite.

    "Safely": every pivot of the Cholesky factorization of M above ``M_PIVOT`` times the
    largest diagonal entry; a singular M passes LAPACK's test with pivots of rounding size.
    """
    if not np.isfinite(K).all():
        return False  # NaN or infinity: a StateError of the solve, not a question of inertia
    # Jacobi scaling (velocities u = D q̇, D = √diag M): the test is then independent of the
    # units, so 1 µg beside 1000 kg is not "no inertia"; a zero diagonal stays unscaled
    diag = np.diag(K[:n, :n]).copy()
    d = np.where(diag > 1e-300, np.sqrt(np.abs(diag)), 1.0)
    M = K[:n, :n] / d[:, None] / d[None, :]
    A = K[n:, :n] / d[None, :]
    U, info = _potrf(M)
    if info == 0 and np.diag(U).min() ** 2 > M_PIVOT * np.diag(M).max():
        return False  # positive definite: so is ZᵀMZ
    Z = scipy.linalg.null_space(A) if m else np.eye(n)
    if Z.shape[1] == 0:  # the constraints fix every acceleration
        return True
    H = Z.T @ M @ Z
    w, V = np.linalg.eigh(0.5 * (H + H.T))
    tol = 1e-12 * max(np.abs(w).max(), np.abs(np.diag(M)).max(), np.finfo(float).tiny)
    bad = w <= tol
    if not bad.any():
        return True
    U = np.abs((Z @ V[:, bad]) / d[:, None])  # the offending directions in coordinates
    coords = np.flatnonzero((U >= 1e-6 * U.max(axis=0)).any(axis=1))
    if (w[bad] < -tol).any():
        raise InertiaError(
            f"M is not positive definite on the admissible motions at t = {t:.17g}: the "
            f"kinetic energy is negative along a motion of {coordinate_list(names, coords)} "
            f"(eigenvalue {w.min():.3g} of ZᵀMZ); check the masses and kinetic-energy terms"
        )
    raise InertiaError(undetermined_message(names, t, coords))


def coordinate_list(names: Sequence[str], idx: np.ndarray) -> str:
    names = ", ".join(f"`{names[i]}`" for i in idx[:8])
    return names + (f" and {idx.size - 8} more" if idx.size > 8 else "")


def undetermined_message(names: Sequence[str], t: float, idx: np.ndarray) -> str:
    return (
        f"the acceleration of {coordinate_list(names, idx)} is undetermined at t = {t:.17g}: "
        "no inertia and no constraint fixes it (M is singular on the admissible motions). "
        "Give it a mass or kinetic energy, or constrain it"
    )
