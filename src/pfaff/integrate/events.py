"""Discrete attitude events between integration steps: MRP shadow-set switching and the Euler-angle
singularity check.

A model's ``attitudes`` (set by the compiler from the system's rigid bodies) lists, per body, its
name, the kind of attitude set, the indices of its coordinates and, for Euler angles, the
sequence. After each accepted step:

- MRPs with |σ| > 1 switch to the shadow set σˢ = −σ/|σ|², with σ̇ˢ = −σ̇/|σ|² + 2(σ·σ̇)σ/|σ|⁴
  (the derivative of the map): the same attitude and angular velocity, the DCM continuous. The
  integrator restarts from the switched state; the switch is recorded as (t, body name).
- Euler angles whose kinematic matrix is nearly singular (|cos θ₂| for a sequence like 3-2-1,
  |sin θ₂| for one like 3-1-3, below :data:`SINGULAR`) stop the run: past that point the angle
  rates grow without bound and the numbers would be garbage.
"""

from __future__ import annotations

import math

import numpy as np

SINGULAR = 1e-3  # |cos θ₂| (or |sin θ₂|) below which Euler angles are at their singularity


class AttitudeEvents:
    """The attitude events of a model (see the module docstring).

    Examples
    --------
    >>> ev = AttitudeEvents([("b", "mrp", (0, 1, 2), "")])
    >>> q, qd, names = ev.switch(np.array([2.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]))
    >>> q.tolist(), qd.tolist(), names
    ([-0.5, 0.0, 0.0], [0.25, 0.0, 0.0], ['b'])
    """

    def __init__(self, attitudes: object) -> None:
        sets = list(attitudes or ())
        self.mrps = [(name, list(idx)) for name, kind, idx, _ in sets if kind == "mrp"]
        self.eulers = [
            (name, idx[1], seq, seq[0] == seq[2])
            for name, kind, idx, seq in sets
            if kind == "euler"
        ]

    def __bool__(self) -> bool:
        return bool(self.mrps or self.eulers)

    def switch(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """The state with every MRP of |σ| > 1 on its shadow set, and the bodies switched."""
        names = []
        for name, idx in self.mrps:
            s, sd = q[idx], qd[idx]
            s2 = float(s @ s)
            if s2 > 1.0:
                if not names:
                    q, qd = q.copy(), qd.copy()
                q[idx] = -s / s2 + 0.0  # no -0.0
                qd[idx] = -sd / s2 + 2.0 * float(s @ sd) * s / s2**2 + 0.0
                names.append(name)
        return q, qd, names

    def singular(
        self, q: np.ndarray, threshold: float = SINGULAR, before: np.ndarray | None = None
    ) -> str | None:
        """A message when some Euler angles are at their singularity (or crossed it since the
        state ``before``: a step may jump over the neighbourhood), else None."""
        for name, i, seq, symmetric in self.eulers:
            fn = math.sin if symmetric else math.cos
            value = fn(q[i])
            crossed = before is not None and value * fn(before[i]) < 0
            if abs(value) < threshold or crossed:
                name_fn = "sin" if symmetric else "cos"
                where = "crossed zero" if crossed else f"= {abs(value):.3g} < {threshold:g}"
                return (
                    f"the {seq} Euler angles of body `{name}` reached their singularity (gimbal "
                    f"lock): |{name_fn}(second angle)| {where}, where the "
                    "angle rates grow without bound; use a quaternion (pfaff.attitude.Quaternion) "
                    "or MRPs (pfaff.attitude.MRP) for this motion, or Euler angles whose "
                    "singular attitude the motion avoids"
                )
        return None
