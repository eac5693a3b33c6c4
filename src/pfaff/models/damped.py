"""Pendulums with joint dampers: the test systems of sensitivities and identification.

``damped_pendulum()``: one rod, m l² θ̈ + c θ̇ + m g l sin θ = 0. ``damped_double_pendulum()``:
two point masses on rods l1, l2, joint dampers c on the absolute rate θ̇1 and the relative rate
θ̇2 − θ̇1 (R = ½c θ̇1² + ½c (θ̇2 − θ̇1)²), in the angles (θ1, θ2 from the downward vertical) or, with
``cartesian=True``, in the masses' positions (x1, y1, x2, y2) with two rod constraints and the
same dampers written through the angles' rates (x ẏ − y ẋ)/(x² + y²).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.symbols import coordinates


def damped_pendulum() -> System:
    """A rod pendulum with a joint damper: m l² θ̈ + c θ̇ + m g l sin θ = 0 (parameters m, l, g, c).

    Examples
    --------
    >>> import pfaff
    >>> pfaff.models.damped_pendulum().equations().lagrange_equations[0]
    Eq(g*l*m*sin(theta(t)) + l**2*m*Derivative(theta(t), (t, 2)), -c*Derivative(theta(t), t))
    """
    m, length, g, c = sp.symbols("m l g c")
    th = coordinates("theta")
    s = System([th], name="damped pendulum")
    pos = [length * sp.sin(th), -length * sp.cos(th)]
    s.add_particle(m, pos, name="bob")
    s.add_potential_energy(m * g * pos[1], name="gravity")
    s.add_dissipation(c * th.diff() ** 2 / 2, name="joint damper")
    return s


def _rate(x: sp.Expr, y: sp.Expr) -> sp.Expr:
    """The rate of the angle of (x, y) from the downward vertical: (x ẏ − y ẋ)/(x² + y²)."""
    return (x * y.diff() - y * x.diff()) / (x**2 + y**2)


def damped_double_pendulum(*, cartesian: bool = False) -> System:
    """The double pendulum with joint dampers (parameters m1, m2, l1, l2, g, c).

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.damped_double_pendulum(cartesian=True)
    >>> [str(q.func) for q in s.coordinates], len(s.equations().constraint_names)
    (['x1', 'y1', 'x2', 'y2'], 2)
    """
    m1, m2, l1, l2, g, c = sp.symbols("m1 m2 l1 l2 g c")
    if cartesian:
        x1, y1, x2, y2 = coordinates("x1 y1 x2 y2")
        s = System([x1, y1, x2, y2], name="damped double pendulum (Cartesian)")
        p1, p2 = [x1, y1], [x2, y2]
        s.add_holonomic_constraint(x1**2 + y1**2 - l1**2, name="rod1")
        s.add_holonomic_constraint((x2 - x1) ** 2 + (y2 - y1) ** 2 - l2**2, name="rod2")
        w1, w2 = _rate(x1, y1), _rate(x2 - x1, y2 - y1)
    else:
        th1, th2 = coordinates("theta1 theta2")
        s = System([th1, th2], name="damped double pendulum")
        p1 = [l1 * sp.sin(th1), -l1 * sp.cos(th1)]
        p2 = [p1[0] + l2 * sp.sin(th2), p1[1] - l2 * sp.cos(th2)]
        w1, w2 = th1.diff(), th2.diff()
    s.add_particle(m1, p1, name="bob1")
    s.add_particle(m2, p2, name="bob2")
    s.add_potential_energy(g * (m1 * p1[1] + m2 * p2[1]), name="gravity")
    s.add_dissipation(c * (w1**2 + (w2 - w1) ** 2) / 2, name="joint dampers")
    return s


def double_pendulum_cartesian_state(
    angles: object, rates: object, values: Mapping[str, float]
) -> tuple[np.ndarray, np.ndarray]:
    """(x1, y1, x2, y2) and their rates from the angles (θ1, θ2), their rates and l1, l2.

    Examples
    --------
    >>> q, qd = double_pendulum_cartesian_state([0.0, 0.0], [1.0, 0.0], {"l1": 1.0, "l2": 2.0})
    >>> q.tolist(), qd.tolist()
    ([0.0, -1.0, 0.0, -3.0], [1.0, 0.0, 1.0, 0.0])
    """
    (a1, a2), (w1, w2) = np.asarray(angles, float), np.asarray(rates, float)
    l1, l2 = float(values["l1"]), float(values["l2"])
    p1 = l1 * np.array([np.sin(a1), -np.cos(a1)])
    v1 = l1 * w1 * np.array([np.cos(a1), np.sin(a1)])
    p2 = p1 + l2 * np.array([np.sin(a2), -np.cos(a2)])
    v2 = v1 + l2 * w2 * np.array([np.cos(a2), np.sin(a2)])
    return np.concatenate((p1, p2)), np.concatenate((v1, v2))
