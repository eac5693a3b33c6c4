"""The default constraint tolerance of :func:`pfaff.simulate`, scaled to the problem's size.

An absolute ``constraint_tol`` of 1e-12 means nothing for a 1 mm pendulum: its constraint
``x² + y² − L²`` is of order ``L² = 1e-6``, so residuals under the tolerance allow a relative
drift of the length of 1e-6. The scale of a holonomic row ``f_i`` is ``‖∂f_i/∂q‖ · ℓ`` at the
initial state, with ``ℓ`` the largest initial coordinate (1 when all are 0): the change of
``f_i`` when the coordinates change by their own size. The default tolerance is ``DEFAULT_TOL``
times the smallest such scale, capped at 1 (a problem of unit size or larger keeps 1e-12) and
floored at ``FLOOR`` (a degenerate start).
"""

from __future__ import annotations

import numpy as np

DEFAULT_TOL = 1e-12
FLOOR = 1e-8  # the smallest factor applied to DEFAULT_TOL
A_ALONE_FROM = 1 << 12  # coordinates from which A is asked for alone (constraint_matrix)


def constraint_scale(model: object, t0: float, q0: np.ndarray, qd0: np.ndarray) -> float:
    """The factor in (FLOOR, 1] applied to the default constraint tolerance.

    Parameters
    ----------
    model : a compiled model (``holonomic`` flags, ``dae_blocks``, ``constraint_matrix``)
    t0 : float
    q0, qd0 : ndarray, shape (n,)

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> eom = pfaff.models.cartesian_pendulum().equations()
    >>> small = eom.compile({"m": 1, "g": 9.81, "L": 1e-3})
    >>> float(constraint_scale(small, 0.0, np.array([1e-3, 0.0]), np.zeros(2)))  # 2 L · L
    2e-06
    >>> float(constraint_scale(eom.compile({"m": 1, "g": 9.81, "L": 2}), 0.0,
    ...                        np.array([2.0, 0.0]), np.zeros(2)))
    1.0
    """
    holonomic = np.asarray(getattr(model, "holonomic", ()), dtype=bool)
    if not holonomic.any() or not hasattr(model, "dae_blocks"):
        return 1.0
    try:
        q0, qd0 = np.asarray(q0, float), np.asarray(qd0, float)
        if q0.size >= A_ALONE_FROM:  # (a family's M and forcing with it: 1.1 s at 2^20)
            A = model.constraint_matrix(t0, q0)
        else:  # (the blocks in one call of a small model's fused code: 8 µs, A checked 160 µs)
            _, A, _, _, _ = model.dae_blocks(t0, q0, qd0)
    except Exception:  # not defined there: the run reports it itself
        return 1.0
    if hasattr(A, "multiply"):  # sparse (a family): row norms without a dense copy
        squares = np.asarray(A.multiply(A).sum(axis=1)).ravel()
        gradients = np.sqrt(squares[: holonomic.size][holonomic])
    else:
        gradients = np.linalg.norm(np.asarray(A)[holonomic], axis=1)
    length = float(np.abs(q0).max(initial=0.0)) or 1.0
    scales = gradients[gradients > 0] * length
    if not scales.size or not np.isfinite(scales).all():
        return 1.0
    return float(np.clip(scales.min(), FLOOR, 1.0))
