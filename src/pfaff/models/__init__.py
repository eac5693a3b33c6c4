"""A zoo of ready models, used by the tests, the CLI, the docs and the benchmarks.

Every function returns a :class:`pfaff.System`. Parameters given as SymPy symbols stay symbolic;
numbers are built in. Default parameter symbols are plain (no assumptions), so ``sympy.symbols("M r")``
made by a user compares equal to them.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.errors import ModelError, ModelTypeError
from pfaff.core.symbols import coordinates
from pfaff.models.params import _param
from pfaff.numeric.checks import real_number

FAMILY_FROM = 1024  # rolling_ring(n) uses the family form above this n unless told otherwise


def rolling_ring(
    n: int,
    *,
    mass: object = None,
    radius: object = None,
    force: object = None,
    incline: object = None,
    gravity: object = None,
    family: bool | None = None,
    closed: bool = False,
) -> System:
    """The seed's ring of ``n`` particles rolling without slip on a line (DESIGN.md).

    Coordinates q = (x, θ_1, …, θ_n); particle k (mass M/n) sits at (x + r sin θ_k, r cos θ_k), so
    θ = 0 is the top and θ = π the contact point. Constraints (holonomic): ``no slip``
    x - r θ_1 = 0 and ``spacing k`` θ_{k+1} - θ_k - 2π/n = 0 for k = 1 … n-1.

    Parameters
    ----------
    n : int
        Number of particles, n >= 2.
    mass, radius : Expr or float, optional
        Total mass ``M`` and radius ``r`` (default: symbols ``M``, ``r``).
    force : Expr, float or True, optional
        Horizontal push at the centre; ``True`` means the symbol ``F``. Expected: θ̈ = F/(2Mr),
        ẍ = F/(2M), no-slip multiplier λ_1 = -F/2.
    incline : Expr, float or True, optional
        Incline angle (``True``: symbol ``alpha``); x then runs down the slope and gravity
        ``g`` (or ``gravity``) acts on every particle. Expected: ẍ = g sin α / 2.
    family : bool, optional
        Declare θ as an indexed family with one particle template and one spacing template
        (constant symbolic work, structured O(N) numerics) instead of n explicit pieces. Default:
        the family form when ``n > FAMILY_FROM`` (1024). Both give identical equations.
    closed : bool, optional
        Also add ``spacing n``, θ_1 − θ_n − 2π/n + 2π = 0, which closes the loop (θ_{n+1} is
        θ_1 + 2π), as an ordinary constraint after the others: n + 1 constraints on n + 1
        coordinates. The n spacing rows are then dependent, one of them redundant: their sum is
        the no-op 0 = 0, so the all-ones vector over the spacing rows (zero on ``no slip``) spans
        the null space of Aᵀ, the redundancy subspace: a hoop stress, the same tension in every
        spacing row, that moves nothing. ``equations()`` reports it (a
        :class:`pfaff.RedundancyWarning`); the motion is the open ring's, θ̈ = F/(2Mr),
        ẍ = F/(2M), the friction λ_1 = -F/2 is unique, and the spacing multipliers are the
        minimum-norm ones (determined only up to a multiple of that vector). Default False: the
        open ring, exactly as before.

    Examples
    --------
    >>> import pfaff
    >>> ring = pfaff.models.rolling_ring(4, force=True)
    >>> [str(p) for p in ring.parameters]
    ['F', 'M', 'r']
    >>> pfaff.models.rolling_ring(3, closed=True).constraint_rows()[0]
    ('no slip', 'spacing 1', 'spacing 2', 'spacing 3')
    """
    n = _count(n, "n")
    if family or (family is None and n > FAMILY_FROM):
        return _ring_family(n, mass, radius, force, incline, gravity, closed)
    M, r = _param(mass, "M", "mass"), _param(radius, "r", "radius")
    qs = coordinates(f"x theta1:{n + 1}")
    x, th = qs[0], qs[1:]
    ring = System(qs, name=f"rolling ring, N={n}")
    m = M / n
    dth = 2 * sp.pi / n
    # sin/cos of a bare coordinate never simplify: skip SymPy's evaluation (the costliest part).
    sin = [sp.sin(q, evaluate=False) for q in th]
    cos = [sp.cos(q, evaluate=False) for q in th]
    for k in range(n):
        ring.add_particle(m, [x + r * sin[k], r * cos[k]], name=f"particle {k + 1}")
    ring.add_holonomic_constraint(x - r * th[0], name="no slip")
    for k in range(n - 1):
        ring.add_holonomic_constraint(th[k + 1] - th[k] - dth, name=f"spacing {k + 1}")
    if closed:
        _close_ring(ring, th[0], th[n - 1], n)
    if force is not None and force is not False:
        ring.add_force([_param(force, "F", "force"), 0], at=[x, 0], name="push")
    if incline is not None and incline is not False:
        a, g = _param(incline, "alpha", "incline"), _param(gravity, "g", "gravity")
        for k in range(n):
            s_, h_ = x + r * sin[k], r * cos[k]
            ring.add_potential_energy(
                -m * g * (s_ * sp.sin(a) - h_ * sp.cos(a)), name=f"gravity {k + 1}"
            )
    return ring


def _ring_family(
    n: int,
    mass: object,
    radius: object,
    force: object,
    incline: object,
    gravity: object,
    closed: bool = False,
) -> System:
    """:func:`rolling_ring` with θ_1 … θ_n as a family: the seed's ring in ten lines."""
    M, r, k = _param(mass, "M", "mass"), _param(radius, "r", "radius"), sp.Symbol("k", integer=True)
    x = coordinates("x")
    ring = System([x], name=f"rolling ring, N={n}")
    th = ring.add_family("theta", n, first=1)
    pos = [x + r * sp.sin(th[k]), r * sp.cos(th[k])]
    ring.add_particle(M / n, pos, name="particle", over=k)
    ring.add_holonomic_constraint(x - r * th[1], name="no slip")
    ring.add_holonomic_constraint(th[k + 1] - th[k] - 2 * sp.pi / n, "spacing", over=(k, 1, n - 1))
    if closed:  # an ordinary row after the template: `spacing n`, numbered on from it
        _close_ring(ring, th[1], th[n], n)
    if force is not None and force is not False:
        ring.add_force([_param(force, "F", "force"), 0], at=[x, 0], name="push")
    if incline is not None and incline is not False:
        a, g = _param(incline, "alpha", "incline"), _param(gravity, "g", "gravity")
        V = -(M / n) * g * (pos[0] * sp.sin(a) - pos[1] * sp.cos(a))
        ring.add_potential_energy(V, name="gravity", over=k)
    return ring


def _close_ring(ring: System, first: sp.Expr, last: sp.Expr, n: int) -> None:
    """The closing row ``spacing n``: θ_{n+1} − θ_n − 2π/n = 0 with θ_{n+1} = θ_1 + 2π."""
    ring.add_holonomic_constraint(first - last - 2 * sp.pi / n + 2 * sp.pi, name=f"spacing {n}")


def _count(value: object, name: str, low: int = 2) -> int:
    """A number of particles: a whole number from ``low`` to 2^31 - 1."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ModelTypeError(f"`{name}` must be a whole number, got {value!r:.80}")
    if not low <= int(value) < 2**31:
        raise ModelError(f"`{name}` must be between {low} and 2^31 - 1, got {value}")
    return int(value)


def ring_state(
    n: int, radius: float, theta: float = 0.0, theta_dot: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A consistent state (q, q̇) of :func:`rolling_ring`: x = rθ, θ_k = θ + (k-1)2π/n.

    Returns
    -------
    q, qd : ndarray, shape (n + 1,)

    Examples
    --------
    >>> q, qd = ring_state(4, radius=0.5, theta=0.2, theta_dot=1.0)
    >>> q.shape, float(qd[0])
    ((5,), 0.5)
    """
    n = _count(n, "n")
    radius, theta, theta_dot = (
        real_number(v, name, ModelError)
        for v, name in ((radius, "radius"), (theta, "theta"), (theta_dot, "theta_dot"))
    )
    if radius <= 0:
        raise ModelError(f"`radius` must be positive, got {radius}")
    th = theta + 2 * np.pi * np.arange(n) / n
    q = np.concatenate([[radius * theta], th])
    qd = np.concatenate([[radius * theta_dot], np.full(n, float(theta_dot))])
    return q, qd


def rolling_ring_minimal(
    *,
    mass: object = None,
    radius: object = None,
    force: object = None,
    incline: object = None,
    gravity: object = None,
) -> System:
    """The ring in one coordinate θ: T = ½Mẋ² + ½Iθ̇² with ẋ = rθ̇ and I = Mr², i.e. T = Iθ̇².

    Lagrange's equation is 2Iθ̈ = Q_θ; a push F at the centre gives Q_θ = F r. Parameters as in
    :func:`rolling_ring`.

    Examples
    --------
    >>> import pfaff
    >>> pfaff.models.rolling_ring_minimal(force=True).equations().lagrange_equations[0]
    Eq(2*M*r**2*Derivative(theta(t), (t, 2)), F*r)
    """
    M, r = _param(mass, "M", "mass"), _param(radius, "r", "radius")
    th = coordinates("theta")
    s = System([th], name="rolling ring, minimal")
    s.add_kinetic_energy(M * r**2 * th.diff() ** 2, name="T = I θ̇²")
    if force is not None and force is not False:
        s.add_force([_param(force, "F", "force"), 0], at=[r * th, 0], name="push")
    if incline is not None and incline is not False:
        a, g = _param(incline, "alpha", "incline"), _param(gravity, "g", "gravity")
        s.add_potential_energy(-M * g * r * th * sp.sin(a), name="gravity")
    return s


def cartesian_pendulum(
    *, mass: object = None, length: object = None, gravity: object = None
) -> System:
    """Point mass on a rod in Cartesian coordinates: q = (x, y), V = m g y, x² + y² - L² = 0.

    The multiplier is λ = m(g y - ẋ² - ẏ²)/(2L²); the rod tension (pull towards the pivot) is
    -2Lλ: m g hanging at rest, 3 m g at the bottom after release from horizontal rest.

    Examples
    --------
    >>> import pfaff
    >>> pfaff.models.cartesian_pendulum().equations().lagrange_equations[0]
    Eq(m*Derivative(x(t), (t, 2)), 2*lambda1*x(t))
    """
    m, L, g = (
        _param(mass, "m", "mass"),
        _param(length, "L", "length"),
        _param(gravity, "g", "gravity"),
    )
    x, y = coordinates("x y")
    s = System([x, y], name="Cartesian pendulum")
    s.add_particle(m, [x, y], name="bob")
    s.add_potential_energy(m * g * y, name="gravity")
    s.add_holonomic_constraint(x**2 + y**2 - L**2, name="rod")
    return s


def pendulum(*, mass: object = None, length: object = None, gravity: object = None) -> System:
    """Simple pendulum in its angle θ from the downward vertical: m L² θ̈ + m g L sin θ = 0.

    Examples
    --------
    >>> import pfaff
    >>> pfaff.models.pendulum().equations().lagrange_equations[0]
    Eq(L**2*m*Derivative(theta(t), (t, 2)) + L*g*m*sin(theta(t)), 0)
    """
    m, L, g = (
        _param(mass, "m", "mass"),
        _param(length, "L", "length"),
        _param(gravity, "g", "gravity"),
    )
    th = coordinates("theta")
    s = System([th], name="pendulum")
    pos = [L * sp.sin(th), -L * sp.cos(th)]
    s.add_particle(m, pos, name="bob")
    s.add_potential_energy(m * g * pos[1], name="gravity")
    return s


def n_link_pendulum_on_cart(n: int) -> System:
    """A cart on a line carrying a chain of n point-mass links, pushed by a force F.

    The planar chain of SymPy's ``sympy.physics.mechanics.models.n_link_pendulum_on_cart``: the
    cart q0 (mass m0) moves along x; link i has an absolute angle q_i from the upward vertical
    (counter-clockwise), length l_{i-1} and its mass m_i at its end; gravity g points along −y,
    F pushes the cart. With p_0 = (q0, 0) and p_i = p_{i−1} + l_{i−1}(−sin q_i, cos q_i):

        T = Σ_i m_i |ṗ_i|² / 2,   V = g Σ_i m_i y_i,   Q_{q0} = F.

    Parameters
    ----------
    n : int
        Number of links, at least 1.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.n_link_pendulum_on_cart(2)
    >>> [str(q.func) for q in s.coordinates], sorted(str(p) for p in s.equations().parameters)
    (['q0', 'q1', 'q2'], ['F', 'g', 'l0', 'l1', 'm0', 'm1', 'm2'])
    """
    n = _count(n, "n", low=1)
    q = coordinates(f"q0:{n + 1}")
    m = sp.symbols(f"m0:{n + 1}")
    length = sp.symbols(f"l0:{n}")
    g, F = sp.symbols("g F")
    s = System(list(q), name=f"{n}-link pendulum on a cart")
    x, y = q[0], sp.S.Zero
    s.add_particle(m[0], [x, y], name="cart")
    V = sp.S.Zero
    for i in range(1, n + 1):
        x = x - length[i - 1] * sp.sin(q[i])
        y = y + length[i - 1] * sp.cos(q[i])
        s.add_particle(m[i], [x, y], name=f"bob{i}")
        V += m[i] * g * y
    s.add_potential_energy(V, name="gravity")
    s.add_generalized_force(q[0], F, name="push")
    return s


from pfaff.models.andrews import ANDREWS, andrews_squeezer  # noqa: E402, F401  (Andrews' squeezer)
from pfaff.models.bicycle import (  # noqa: E402, F401  (the Whipple bicycle)
    MEIJAARD,
    bicycle_operating_point,
    whipple_bicycle,
)
from pfaff.models.bodies import (  # noqa: E402, F401  (the rigid-body zoo)
    heavy_top,
    rolling_disk,
    rolling_on_incline,
    spherical_pendulum,
    torque_free_body,
)
from pfaff.models.bricard import BRICARD, bricard, bricard_state  # noqa: E402, F401  (IFToMM A04)
from pfaff.models.contacts import (  # noqa: E402, F401  (unilateral contacts)
    bouncing_ball,
    bouncing_ball_state,
    particle_on_sphere,
    particle_on_sphere_state,
)
from pfaff.models.damped import (  # noqa: E402, F401  (identification's test systems)
    damped_double_pendulum,
    damped_pendulum,
    double_pendulum_cartesian_state,
)
from pfaff.models.diffdrive import diffdrive  # noqa: E402, F401  (a robot with a redundant row)
from pfaff.models.fourbar import FOURBAR, parallelogram_fourbar  # noqa: E402, F401  (the folds)
from pfaff.models.fourbar3d import FOURBAR3D, fourbar3d, fourbar3d_state  # noqa: E402, F401
from pfaff.models.robot import (  # noqa: E402, F401  (an n-joint spatial arm)
    robot_arm,
    robot_arm_state,
    robot_arm_urdf,
    robot_arm_values,
)
