"""A planar parallelogram four-bar in its three link angles: the rank-deficient folds.

Ground pivots O = (0, 0) and P = (L, 0); crank OA of length a at angle θ1, coupler AB of length L
at angle θ2, rocker PB of length a at angle θ3. Loop closure (holonomic, ``loop x`` and
``loop y``):

    a cos θ1 + L cos θ2 − L − a cos θ3 = 0,    a sin θ1 + L sin θ2 − a sin θ3 = 0.

Uniform rods (crank and rocker about their pivots, I = m a²/3; coupler about its centre,
I = m L²/12) under gravity g along −y. On the parallelogram branch θ2 = 0, θ3 = θ1 = θ the coupler
translates, and the motion obeys the one-angle equation

    (m1/3 + m3/3 + m2) a θ̈ = −(m1/2 + m2 + m3/2) g cos θ.

At θ = 0 and π all links are collinear: the first row of A = ∂f/∂q vanishes and the Jacobian
loses rank; the velocity (θ̇, 0, θ̇) selects the parallelogram branch.
"""

from __future__ import annotations

import sympy as sp

from pfaff.api.system import System
from pfaff.core.symbols import coordinates, t

#: the values of the tests and the gallery
FOURBAR = {"a": 1.0, "L": 2.0, "m1": 1.0, "m2": 2.0, "m3": 1.0, "g": 9.81}


def parallelogram_fourbar() -> System:
    """The parallelogram four-bar (module doc): 3 angles, 2 loop-closure constraints.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.parallelogram_fourbar()
    >>> s.constraint_rows()[0]
    ('loop x', 'loop y')
    """
    th1, th2, th3 = coordinates("theta1 theta2 theta3")
    a, L, m1, m2, m3, g = sp.symbols("a L m1 m2 m3 g")
    w1, w2, w3 = (q.diff(t) for q in (th1, th2, th3))
    vx = -a * sp.sin(th1) * w1 - L / 2 * sp.sin(th2) * w2  # coupler centre
    vy = a * sp.cos(th1) * w1 + L / 2 * sp.cos(th2) * w2
    s = System([th1, th2, th3], name="parallelogram four-bar")
    s.add_kinetic_energy(m1 * a**2 / 6 * w1**2, name="crank")
    s.add_kinetic_energy(m2 / 2 * (vx**2 + vy**2) + m2 * L**2 / 24 * w2**2, name="coupler")
    s.add_kinetic_energy(m3 * a**2 / 6 * w3**2, name="rocker")
    s.add_potential_energy(
        g * (m1 * a / 2 * sp.sin(th1) + m2 * (a * sp.sin(th1) + L / 2 * sp.sin(th2))),
        name="gravity crank, coupler",
    )
    s.add_potential_energy(g * m3 * a / 2 * sp.sin(th3), name="gravity rocker")
    s.add_holonomic_constraint(
        a * sp.cos(th1) + L * sp.cos(th2) - L - a * sp.cos(th3), name="loop x"
    )
    s.add_holonomic_constraint(a * sp.sin(th1) + L * sp.sin(th2) - a * sp.sin(th3), name="loop y")
    return s
