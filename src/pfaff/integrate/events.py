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

from pfaff.integrate.stepper import _RunFailure

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


def root_tolerance(t: float) -> float:
    """How tightly a user event's root is bracketed at time ``t``: 1e-12·max(1, |t|)."""
    return 1e-12 * max(1.0, abs(t))


class UserEvents:
    """The zero crossings of user events (:class:`pfaff.Event`, ``model.events``) during a run.

    After each accepted step the driver calls :meth:`find`: every event whose value at the state
    the step ends on (the state the next step starts from) has the other sign than at the
    previous one, in its ``direction``, has crossed; its root is bracketed on the step's dense
    output by Brent's method to :func:`root_tolerance`. Checking the states the steps start from
    counts each crossing once, even when a projection moves the end of a step. Two crossings
    inside one step are not seen (as in SciPy): ``max_step`` bounds the steps.

    Examples
    --------
    >>> from pfaff.core.events import Event
    >>> ev = UserEvents([Event(lambda t, q, qd: q[0], direction=-1)])
    >>> ev.names, ev.counts
    (['event1'], [0])
    """

    def __init__(self, events: object) -> None:
        self.events = list(events or ())
        self.names = [ev.name or f"event{i + 1}" for i, ev in enumerate(self.events)]
        self.counts = [0] * len(self.events)
        self._g: list[float] = []

    def __bool__(self) -> bool:
        return bool(self.events)

    def _value(self, i: int, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        v = float(self.events[i].fn(t, q, qd))
        if not math.isfinite(v):
            raise _RunFailure(f"event `{self.names[i]}` is {v} at t = {t:.17g}", hint=False)
        return v

    def start(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """The events' values at the state the next step starts from."""
        self._g = [self._value(i, t, q, qd) for i in range(len(self.events))]

    def _crossed(self, i: int, a: float, b: float) -> bool:
        d = self.events[i].direction
        rising, falling = a < 0 <= b, a > 0 >= b
        return (rising and d >= 0) or (falling and d <= 0)

    def find(self, st: object, t_prev: float) -> tuple[list[tuple[float, int]], bool]:
        """The crossings of the step just taken by ``st`` (a :class:`pfaff.Stepper`) from
        ``t_prev``, as (t, event index) in time order, cut after a terminal event's last
        occurrence; and whether the run stops there."""
        t1 = float(st.t)  # type: ignore[attr-defined]
        q1, qd1 = st.state()  # type: ignore[attr-defined]
        before = self._g
        self.start(t1, q1, qd1)
        roots = [
            (self._root(st, i, t_prev, t1), i)
            for i in range(len(self.events))
            if self._crossed(i, before[i], self._g[i])
        ]
        roots.sort()
        for k, (_, i) in enumerate(roots):
            self.counts[i] += 1
            if self.events[i].terminal and self.counts[i] >= self.events[i].terminal:
                return roots[: k + 1], True
        return roots, False

    def _root(self, st: object, i: int, a: float, b: float) -> float:
        """The root of event ``i`` on the dense output of the last step, inside [a, b]."""
        from scipy.optimize import brentq

        def h(s: float) -> float:
            ((q, qd),) = st.dense(np.array([s]))  # type: ignore[attr-defined]
            return self._value(i, s, q, qd)

        ha, hb = h(a), h(b)
        if ha == 0.0 or hb == 0.0 or (ha > 0) == (hb > 0):  # the sign change is the projection's
            return a if abs(ha) < abs(hb) else b
        return float(brentq(h, a, b, xtol=root_tolerance(b), rtol=4 * np.finfo(float).eps))
