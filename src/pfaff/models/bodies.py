"""The zoo's rigid bodies: a torque-free body, the heavy top, the rolling disk, rolling on an
incline, the spherical pendulum. Each function returns a :class:`pfaff.System`."""

from __future__ import annotations

import sympy as sp

from pfaff.api import System
from pfaff.core.errors import ModelError
from pfaff.core.symbols import coordinates
from pfaff.mechanics.attitude import MRP, Attitude, EulerAngles, PlanarAngle, Quaternion
from pfaff.models.params import _param

ATTITUDES = ("euler", "quaternion", "mrp")


def attitude_set(kind: str, sequence: str = "321", prefix: str = "") -> Attitude:
    """A fresh attitude set of ``kind`` ("euler", "quaternion" or "mrp") with its coordinates:
    ``psi theta phi`` (Euler angles), ``beta0:4`` or ``sigma1:4``, each name after ``prefix``.

    Examples
    --------
    >>> attitude_set("mrp").coordinates
    (sigma1(t), sigma2(t), sigma3(t))
    """
    if kind == "euler":
        return EulerAngles(
            coordinates(" ".join(prefix + s for s in ("psi", "theta", "phi"))), sequence
        )
    if kind == "quaternion":
        return Quaternion(coordinates(" ".join(f"{prefix}beta{i}" for i in range(4))))
    if kind == "mrp":
        return MRP(coordinates(" ".join(f"{prefix}sigma{i}" for i in range(1, 4))))
    raise ModelError(f"`attitude` must be one of {', '.join(ATTITUDES)}; got {kind!r:.40}")


def torque_free_body(
    attitude: str = "quaternion", *, inertia: object = None, sequence: str = "321"
) -> System:
    """A rigid body spinning freely about its fixed mass centre (Euler's equations).

    Principal moments ``I1, I2, I3`` (symbols unless given), unit mass at the origin.

    Parameters
    ----------
    attitude : {"quaternion", "euler", "mrp"}
    inertia : sequence of 3, optional
    sequence : str
        Euler-angle sequence for ``attitude="euler"``.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> s = pfaff.models.torque_free_body("euler")  # 3-2-1 angles, clear of pitch ±90°
    >>> model = s.equations().compile({"I1": 1, "I2": 2, "I3": 3})
    >>> att = s.bodies[0].attitude
    >>> q0 = att.from_dcm(np.eye(3)); qd0 = att.rates(q0, [0.0, 0.0, 1.0])
    >>> float(np.abs(model.accelerations(0.0, q0, qd0)[0]).max()) < 1e-12  # steady spin
    True
    """
    att = attitude_set(attitude, sequence)
    s = System(list(att.coordinates), name=f"torque-free body ({attitude})")
    moments = inertia if inertia is not None else sp.symbols("I1 I2 I3")
    s.add_rigid_body(1, list(moments), [0, 0, 0], att, name="body")
    return s


def heavy_top(
    attitude: str = "euler",
    *,
    mass: object = None,
    length: object = None,
    gravity: object = None,
    inertia: object = None,
) -> System:
    """A heavy symmetric top with its tip fixed at the origin, its axis the body z axis.

    The mass centre is at distance ``l`` along the axis; ``I1`` (transverse) and ``I3`` (axial)
    are the moments **about the fixed tip** (the mass centre's transverse moment is I1 − m l²).
    With Euler angles the sequence is 3-1-3 (precession ψ, nutation θ, spin φ), singular at
    θ = 0: the sleeping top needs a quaternion or MRPs.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.heavy_top("quaternion")
    >>> [str(p) for p in s.parameters]
    ['I1', 'I3', 'g', 'l', 'm']
    """
    m = _param(mass, "m", "mass")
    L = _param(length, "l", "length")
    g = _param(gravity, "g", "gravity")
    I1, I3 = inertia if inertia is not None else sp.symbols("I1 I3")
    att = attitude_set(attitude, "313")
    s = System(list(att.coordinates), name=f"heavy top ({attitude})")
    centre = att.dcm * sp.Matrix([0, 0, L])
    s.add_rigid_body(m, [I1 - m * L**2, I1 - m * L**2, I3], list(centre), att, name="top")
    s.add_potential_energy(m * g * centre[2], name="gravity")
    return s


def rolling_disk(*, mass: object = None, radius: object = None, gravity: object = None) -> System:
    """A thin disk rolling without slip on the horizontal plane z = 0 (all constraints kept).

    Coordinates: the mass centre (x, y, z) and 3-1-2 Euler angles (yaw ψ, lean θ, spin φ); the
    disk's axis is the body y axis, θ = 0 upright. Constraints: ``contact height``
    z − r cos θ = 0 (holonomic) and ``no slip x``, ``no slip y``: the material point at the contact
    has no horizontal velocity. The multipliers are the contact force components
    (horizontal friction, and the normal force through the height constraint).

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.rolling_disk()
    >>> s.constraint_rows()[0]
    ('contact height', 'no slip x', 'no slip y')
    """
    m = _param(mass, "m", "mass")
    r = _param(radius, "r", "radius")
    g = _param(gravity, "g", "gravity")
    x, y, z = coordinates("x y z")
    att = EulerAngles(coordinates("psi theta phi"), "312")
    s = System([x, y, z, *att.coordinates], name="rolling disk")
    disk = s.add_rigid_body(
        m, [m * r**2 / 4, m * r**2 / 2, m * r**2 / 4], [x, y, z], att, name="disk"
    )
    s.add_potential_energy(m * g * z, name="gravity")
    theta = att.coordinates[1]
    s.add_holonomic_constraint(z - r * sp.cos(theta), name="contact height")
    # the body z axis without the spin (the lean frame's): from the centre to the contact is -r of it
    lean_z = att.dcm[:, 2].subs(att.coordinates[2], 0)
    contact = sp.Matrix([x, y, z]) - r * lean_z
    v = disk.velocity_of(list(contact))
    s.add_velocity_constraint(v[0], name="no slip x")
    s.add_velocity_constraint(v[1], name="no slip y")
    return s


SHAPES = {"hoop": sp.Integer(1), "disk": sp.Rational(1, 2), "sphere": sp.Rational(2, 5)}


def rolling_on_incline(
    shape: str = "disk",
    *,
    mass: object = None,
    radius: object = None,
    gravity: object = None,
    angle: object = None,
) -> System:
    """A hoop, disk or sphere (I = k m r², k = 1, ½, ⅖) rolling without slip down an incline.

    Coordinates: x, the distance of the mass centre down the slope, and the rotation θ about z
    (counterclockwise: it decreases rolling downhill). The ``no slip`` velocity constraint sets the
    contact point's
    velocity along the slope to zero; its multiplier is the friction force along the slope
    (uphill positive), m g sin α k/(1 + k). The acceleration is g sin α /(1 + k).

    Examples
    --------
    >>> import pfaff
    >>> model = pfaff.models.rolling_on_incline("hoop").equations().compile(
    ...     {"m": 2, "r": 0.5, "g": 9.81, "alpha": 0.3})
    >>> qdd, lam = model.accelerations(0.0, [0.0, 0.0], [0.0, 0.0])
    >>> round(float(qdd[0]), 12) == round(9.81 * 0.29552020666133955 / 2, 12)
    True
    """
    if shape not in SHAPES:
        raise ModelError(f"`shape` must be one of {', '.join(SHAPES)}; got {shape!r:.40}")
    m = _param(mass, "m", "mass")
    r = _param(radius, "r", "radius")
    g = _param(gravity, "g", "gravity")
    a = _param(angle, "alpha", "angle")
    x, th = coordinates("x theta")
    s = System([x, th], name=f"{shape} on an incline")
    down = sp.Matrix([sp.cos(a), -sp.sin(a)])  # unit vector down the slope
    normal = sp.Matrix([sp.sin(a), sp.cos(a)])  # out of the slope
    centre = x * down + r * normal
    body = s.add_rigid_body(m, SHAPES[shape] * m * r**2, list(centre), PlanarAngle(th), name=shape)
    s.add_potential_energy(m * g * centre[1], name="gravity")
    v = body.velocity_of(list(centre - r * normal))
    s.add_velocity_constraint(-(v.dot(down)), name="no slip")
    return s


def spherical_pendulum(
    *, mass: object = None, length: object = None, gravity: object = None
) -> System:
    """A point mass on a massless rod of length L about a fixed point, in Cartesian coordinates
    (x, y, z) with the holonomic ``rod`` constraint x² + y² + z² − L² = 0 (its multiplier gives
    the rod tension −2Lλ).

    Examples
    --------
    >>> import pfaff
    >>> pfaff.models.spherical_pendulum().constraint_rows()[0]
    ('rod',)
    """
    m = _param(mass, "m", "mass")
    L = _param(length, "L", "length")
    g = _param(gravity, "g", "gravity")
    x, y, z = coordinates("x y z")
    s = System([x, y, z], name="spherical pendulum")
    s.add_particle(m, [x, y, z], name="bob")
    s.add_potential_energy(m * g * z, name="gravity")
    s.add_holonomic_constraint(x**2 + y**2 + z**2 - L**2, name="rod")
    return s
