"""Contact models of the zoo: a particle sliding off a sphere and a bouncing ball.

Each is a :class:`pfaff.System` with a unilateral constraint
(``System.add_unilateral_constraint``) and a helper for a consistent initial state.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.errors import ModelError
from pfaff.core.symbols import coordinates
from pfaff.models.params import _param
from pfaff.numeric.checks import real_number


def particle_on_sphere(
    *, mass: object = None, radius: object = None, gravity: object = None
) -> System:
    """A particle on the outside of a frictionless sphere: q = (x, y, z), z up, the sphere's
    centre at the origin, V = m g z, the unilateral constraint ``"sphere"``
    √(x² + y² + z²) − R ≥ 0 (its multiplier is the normal force).

    Started at the top with speed v0 it leaves the sphere where
    cos θ* = (2/3)(1 + v0²/(2 g R)) and flies on a parabola.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.particle_on_sphere()
    >>> [c.name for c in s.contacts], [str(p) for p in s.parameters]
    (['sphere'], ['R', 'g', 'm'])
    """
    m, R, g = (
        _param(mass, "m", "mass"),
        _param(radius, "R", "radius"),
        _param(gravity, "g", "gravity"),
    )
    x, y, z = coordinates("x y z")
    s = System([x, y, z], name="particle on a sphere")
    s.add_particle(m, [x, y, z], name="particle")
    s.add_potential_energy(m * g * z, name="gravity")
    s.add_unilateral_constraint(sp.sqrt(x**2 + y**2 + z**2) - R, name="sphere")
    return s


def particle_on_sphere_state(
    radius: float, speed: float = 0.0, theta: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A state of :func:`particle_on_sphere` on the sphere, at the polar angle θ from the top in
    the x–z plane, moving along the surface (towards +x) at ``speed``.

    Returns
    -------
    q, qd : ndarray, shape (3,)

    Examples
    --------
    >>> q, qd = particle_on_sphere_state(2.0, speed=0.5)
    >>> q.tolist(), qd.tolist()
    ([0.0, 0.0, 2.0], [0.5, 0.0, 0.0])
    """
    radius, speed, theta = (
        real_number(v, name, ModelError)
        for v, name in ((radius, "radius"), (speed, "speed"), (theta, "theta"))
    )
    if radius <= 0:
        raise ModelError(f"`radius` must be positive, got {radius}")
    s, c = np.sin(theta), np.cos(theta)
    q = np.array([radius * s, 0.0, radius * c]) + 0.0
    return q, np.array([speed * c, 0.0, -speed * s]) + 0.0  # (no -0.0)


def bouncing_ball(
    restitution: object = 0.8, *, mass: object = None, gravity: object = None
) -> System:
    """A ball (a particle) over a floor: q = (x, y), y up, V = m g y, the unilateral constraint
    ``"floor"`` y ≥ 0 with Newton's restitution e.

    Dropped from rest at height h (:func:`bouncing_ball_state`) it hits the floor at
    t₁ = √(2h/g) and then at t_{k+1} = t_k + 2 eᵏ √(2h/g), coming to rest at
    t∞ = t₁ (1 + e)/(1 − e).

    Parameters
    ----------
    restitution : float, sympy expression or None
        A number in [0, 1] is the default value of the parameter ``e`` (``compile`` may give
        another); a SymPy expression is used as the restitution itself; None leaves ``e``
        without a default.
    mass, gravity : optional
        Numbers or expressions for m and g (default: the parameters ``m``, ``g``).

    Examples
    --------
    >>> import pfaff
    >>> ball = pfaff.models.bouncing_ball()
    >>> [str(p) for p in ball.parameters], ball.parameter_defaults
    (['e', 'g', 'm'], {'e': 0.8})
    >>> model = ball.equations().compile({"m": 1, "g": 9.81})  # e = 0.8
    """
    m, g = _param(mass, "m", "mass"), _param(gravity, "g", "gravity")
    default = None
    if restitution is not None and not isinstance(restitution, sp.Basic | str):
        default = real_number(restitution, "restitution", ModelError)
        if not 0.0 <= default <= 1.0:
            raise ModelError(f"`restitution` must be in [0, 1], got {default}")
    e = _param(None if default is not None else restitution, "e", "restitution")
    x, y = coordinates("x y")
    s = System([x, y], name="bouncing ball")
    s.add_particle(m, [x, y], name="ball")
    s.add_potential_energy(m * g * y, name="gravity")
    s.add_unilateral_constraint(y, name="floor", restitution=e)
    if default is not None:
        s.set_parameter_defaults({e: default})
    return s


def bouncing_ball_state(
    height: float, speed: float = 0.0, vx: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A state of :func:`bouncing_ball`: at x = 0, y = ``height`` ≥ 0, with vertical velocity
    ``speed`` (positive up) and horizontal ``vx``.

    Returns
    -------
    q, qd : ndarray, shape (2,)

    Examples
    --------
    >>> q, qd = bouncing_ball_state(1.0)
    >>> q.tolist(), qd.tolist()
    ([0.0, 1.0], [0.0, 0.0])
    """
    height, speed, vx = (
        real_number(v, name, ModelError)
        for v, name in ((height, "height"), (speed, "speed"), (vx, "vx"))
    )
    if height < 0:
        raise ModelError(f"`height` must be >= 0 (above the floor), got {height}")
    return np.array([0.0, height]), np.array([vx, speed])
