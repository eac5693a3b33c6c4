"""Whether the constraints can still be met: the one test every method's run fails by.

A rheonomic constraint can drive a system where no configuration satisfies every constraint (a
bead on the unit circle whose x is driven past 1). The methods meet this differently: the
projection ("projection") cannot reach the constraints after a step, IDA's Newton iteration on
f = 0 fails, and Baumgarte stabilization ("baumgarte"), which only damps the drift, would go on
with a residual growing without bound. The test is the same for all of them: a state whose
projection (:class:`pfaff.numeric.projection.Projector`) stops more than :data:`UNREACHED` ×
``constraint_tol`` off the constraints ends the run ("failed"), with a message naming the time,
the constraint furthest off and its residual.

:class:`DriftWatch` is how a method that does not project its steps applies it without a
projection per step: one residual evaluation per step, a projection of a copy of the state only
when the residual has doubled since the last one that projected back.
"""

from __future__ import annotations

import numpy as np

from pfaff.numeric.projection import Projector

UNREACHED = 1e6  # a projected state this many times constraint_tol off the constraints: failed


def _worst(projector: Projector, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, str]:
    """max(|f|, |A q̇ + b|) at a state and the name of the constraint it comes from."""
    f, g = projector.model.residual(t, q, qd)
    off = np.maximum(np.abs(np.where(projector.holonomic, f, 0.0)), np.abs(g))
    if off.size == 0:
        return 0.0, ""
    i = int(np.argmax(off))
    return float(off[i]), str(projector.model.constraint_names[i])


def unreached(
    projector: Projector, t: float, q: np.ndarray, qd: np.ndarray, grew: float | None = None
) -> str | None:
    """Why a run must stop at a projected state (q, q̇) at ``t``, or None when it is on the
    constraints (within :data:`UNREACHED` × the projector's tolerance).

    Parameters
    ----------
    projector : Projector
    t : float
    q, qd : ndarray, shape (n,)
        The state after projection.
    grew : float or None
        The residual before projection, when the method let it grow (Baumgarte).

    Returns
    -------
    str or None

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> x, y = pfaff.coordinates("x y")
    >>> s = pfaff.System([x, y])
    >>> s.add_particle(1, [x, y])
    >>> s.add_holonomic_constraint(x - 2, name="drive")
    >>> s.add_holonomic_constraint(x**2 + y**2 - 1, name="circle")
    >>> p = Projector(s.equations().compile({}))
    >>> q, qd, _ = p(0.0, np.array([1.5, 0.0]), np.zeros(2))
    >>> print(unreached(p, 0.0, q, qd)[:63])
    the constraints cannot be satisfied at t = 0: projecting leaves
    """
    reached, name = _worst(projector, t, q, qd)
    if np.isfinite(reached) and reached <= UNREACHED * projector.tol:
        return None
    before = "" if grew is None else f"their residual grew to {grew:.3g} and "
    return (
        f"the constraints cannot be satisfied at t = {t:.17g}: {before}projecting leaves "
        f"{reached:.3g} on `{name}` (max(|f|, |A q̇ + b|); constraint_tol {projector.tol:.3g}); "
        "they may have become inconsistent (a rheonomic constraint driving the system where no "
        "configuration satisfies them all)"
    )


class DriftWatch:
    """The test of :func:`unreached` for a method whose steps drift off the constraints.

    Parameters
    ----------
    projector : Projector
        Used on copies only: the method's own states are never changed.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> watch = DriftWatch(Projector(model))
    >>> watch(0.0, np.array([0.0, -1.001]), np.zeros(2)) is None  # drifted, but reachable
    True
    """

    def __init__(self, projector: Projector) -> None:
        self.projector = projector
        self.level = UNREACHED * projector.tol  # a residual below this is never tested

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray) -> str | None:
        """None while the state at ``t`` projects onto the constraints, else why it does not."""
        p = self.projector
        if p.model.m == 0:
            return None
        r = p.residual(t, q, qd)
        if r <= self.level:
            return None
        q2, qd2, _ = p(t, q.copy(), qd.copy())
        why = unreached(p, t, q2, qd2, grew=r)
        if why is None:
            self.level = 2.0 * r
        return why
