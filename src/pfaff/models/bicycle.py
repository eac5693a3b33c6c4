"""The Whipple bicycle: the benchmark of Meijaard, Papadopoulos, Ruina and Schwab (2007).

J. P. Meijaard, J. M. Papadopoulos, A. Ruina and A. L. Schwab, "Linearized dynamics equations for
the balance and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463 (2007)
1955-1982: four rigid bodies (rear wheel R, rear frame with rider B, front fork and handlebar H,
front wheel F), knife-edge wheels rolling without slip on flat ground. Eight coordinates, in
Meijaard's axes (x forward, y right, z down):

    q = (x, y, ψ, φ, θ_R, θ_B, δ, θ_F)

the rear contact point (x, y), yaw ψ, lean (roll) φ, the rear wheel's rotation θ_R relative to
the frame, the frame's pitch θ_B, steer δ and the front wheel's rotation θ_F relative to the fork;
four nonholonomic no-slip constraints (both contact points, in the ground plane) and one holonomic
one (the front wheel touches the ground), so three degrees of freedom at the velocity level.

:func:`whipple_bicycle` builds it: the kinetic energy of each body from
``sympy.physics.mechanics`` frames and points, gravity as a potential, the contact constraints.
:data:`MEIJAARD` holds the benchmark parameters (Table 1 of the paper),
:func:`bicycle_operating_point` upright straight running at a speed, and the published linearized
lean-and-steer matrices M, C1, K0, K2 with the weave and capsize speeds are kept here as the
reference the tests and ``pfaff demo bicycle`` compare with (:func:`meijaard_lean_steer`).
``sympy.physics.mechanics`` is imported only when a bicycle is built.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.symbols import coordinates, speed

__all__ = [
    "COORDINATES",
    "MEIJAARD",
    "MEIJAARD_CAPSIZE_SPEED",
    "MEIJAARD_WEAVE_SPEED",
    "Bicycle",
    "bicycle_kinematics",
    "bicycle_operating_point",
    "bicycle_state",
    "lean_steer_eigenvalues",
    "meijaard_eigenvalues",
    "meijaard_lean_steer",
    "stability_speeds",
    "whipple_bicycle",
]

COORDINATES = "x y psi phi thetaR thetaB delta thetaF"
"""Names of the eight coordinates of :func:`whipple_bicycle`, in order."""

MEIJAARD = {
    "w": 1.02,  # wheelbase
    "c": 0.08,  # trail
    "lam": float(np.pi / 10),  # steer axis tilt
    "g": 9.81,
    "rR": 0.3,  # rear wheel radius, mass, inertia (axial: yy)
    "mR": 2.0,
    "IRxx": 0.0603,
    "IRyy": 0.12,
    "xB": 0.3,  # rear frame and rider: mass centre (x, z) in the upright reference, mass, inertia
    "zB": -0.9,
    "mB": 85.0,
    "IBxx": 9.2,
    "IByy": 11.0,
    "IBzz": 2.8,
    "IBxz": 2.4,
    "xH": 0.9,  # front fork and handlebar
    "zH": -0.7,
    "mH": 4.0,
    "IHxx": 0.05892,
    "IHyy": 0.06,
    "IHzz": 0.00708,
    "IHxz": -0.00756,
    "rF": 0.35,  # front wheel
    "mF": 3.0,
    "IFxx": 0.1405,
    "IFyy": 0.28,
}
"""The benchmark parameters of Meijaard et al. (2007), Table 1 (SI units, z down)."""

# The linearized lean and steer equations M ẍ + v C1 ẋ + (g K0 + v² K2) x = 0, x = (φ, δ), of the
# benchmark bicycle as published by Meijaard et al. (2007), with its weave and capsize speeds.
MEIJAARD_M = [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]]
MEIJAARD_C1 = [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]]
MEIJAARD_K0 = [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]]
MEIJAARD_K2 = [[0.0, 76.59734589573222], [0.0, 2.65431523794604]]
MEIJAARD_WEAVE_SPEED = 4.29238253634111
MEIJAARD_CAPSIZE_SPEED = 6.02426201538837


# ------------------------------------------------------------------ the model
def bicycle_kinematics(q: list, rates: list) -> dict:
    """Frames, points, bodies and contact conditions of the Whipple bicycle.

    ``q`` are the eight coordinates (order :data:`COORDINATES`), ``rates`` their time
    derivatives: either ``q̇`` (pfaff) or generalized speeds ``u`` (Kane). Parameters are the
    plain symbols named as in :data:`MEIJAARD`. Axes as in Meijaard et al.: x forward, y right,
    z down; in the upright reference configuration (all angles 0) every body frame coincides with
    the inertial one, so the published inertia components are entered as they are.

    Returns a dict: ``N`` (inertial frame), ``Y`` (yaw frame), ``P`` (rear contact point),
    ``bodies`` (RigidBody: rear wheel, frame, fork, front wheel), ``holonomic`` (z, down, of the
    front contact point: 0), ``v_rear``, ``v_front`` (velocity of each wheel's material point at
    its contact: 0) and ``g``.
    """
    import sympy.physics.mechanics as me

    p = {name: sp.Symbol(name) for name in MEIJAARD}
    _, _, psi, phi, th_r, th_b, delta, th_f = q
    u_x, u_y, u_psi, u_phi, u_th_r, u_th_b, u_delta, u_th_f = rates
    lam, w, c, r_r, r_f = p["lam"], p["w"], p["c"], p["rR"], p["rF"]
    N, Y, R, B, H, WR, WF = (me.ReferenceFrame(s) for s in ("N", "Y", "R", "B", "H", "WR", "WF"))
    Y.orient_axis(N, N.z, psi)  # yaw
    R.orient_axis(Y, Y.x, phi)  # lean
    B.orient_axis(R, R.y, th_b)  # pitch: the rear frame
    H.orient_body_fixed(B, (lam, delta, -lam), "YZY")  # steer about the tilted axis
    WR.orient_axis(B, B.y, th_r)
    WF.orient_axis(H, H.y, th_f)
    Y.set_ang_vel(N, u_psi * N.z)
    R.set_ang_vel(Y, u_phi * Y.x)
    B.set_ang_vel(R, u_th_b * R.y)
    H.set_ang_vel(B, u_delta * (sp.sin(lam) * B.x + sp.cos(lam) * B.z))
    WR.set_ang_vel(B, u_th_r * B.y)
    WF.set_ang_vel(H, u_th_f * H.y)

    P = me.Point("P")  # rear contact
    P.set_vel(N, u_x * N.x + u_y * N.y)
    rear = P.locatenew("rear hub", -r_r * R.z)
    rear.v2pt_theory(P, N, R)
    frame_mc = rear.locatenew("frame mc", p["xB"] * B.x + (p["zB"] + r_r) * B.z)
    frame_mc.v2pt_theory(rear, N, B)
    steer = rear.locatenew("steer axis at the ground", (w + c) * B.x + r_r * B.z)
    steer.v2pt_theory(rear, N, B)
    fork_mc = steer.locatenew("fork mc", (p["xH"] - w - c) * H.x + p["zH"] * H.z)
    fork_mc.v2pt_theory(steer, N, H)
    front = steer.locatenew("front hub", -c * H.x - r_f * H.z)
    front.v2pt_theory(steer, N, H)

    # The front contact is the wheel's lowest point: from the hub, r_F along the unit vector in the
    # wheel plane closest to straight down, (z - (z·n) n)/√(1 - (z·n)²) with n the wheel axis.
    zn = me.dot(Y.z, H.y)
    root = sp.sqrt(1 - zn**2)
    down = (Y.z - zn * H.y) / root
    holonomic = me.dot(front.pos_from(P), Y.z) + r_f * root
    v_rear = rear.vel(N) + me.cross(WR.ang_vel_in(N), r_r * R.z)
    v_front = front.vel(N) + me.cross(WF.ang_vel_in(N), r_f * down)

    def wheel_inertia(frame, axial: str, radial: str):
        return me.inertia(frame, p[radial], p[axial], p[radial])  # symmetric about frame.y

    bodies = [
        me.RigidBody("rear wheel", rear, WR, p["mR"], (wheel_inertia(B, "IRyy", "IRxx"), rear)),
        me.RigidBody(
            "frame",
            frame_mc,
            B,
            p["mB"],
            (me.inertia(B, p["IBxx"], p["IByy"], p["IBzz"], 0, 0, p["IBxz"]), frame_mc),
        ),
        me.RigidBody(
            "fork",
            fork_mc,
            H,
            p["mH"],
            (me.inertia(H, p["IHxx"], p["IHyy"], p["IHzz"], 0, 0, p["IHxz"]), fork_mc),
        ),
        me.RigidBody("front wheel", front, WF, p["mF"], (wheel_inertia(H, "IFyy", "IFxx"), front)),
    ]
    return {
        "N": N,
        "Y": Y,
        "P": P,
        "bodies": bodies,
        "holonomic": holonomic,
        "v_rear": v_rear,
        "v_front": v_front,
        "g": p["g"],
    }


class Bicycle(System):
    """The Whipple bicycle as a :class:`pfaff.System`, with its benchmark values at hand.

    It unpacks as ``(system, parameters, operating_point)``: the system itself,
    :data:`MEIJAARD` (a new dict each time) and :func:`bicycle_operating_point`, so both
    ``bike = whipple_bicycle()`` and ``bike, values, op = whipple_bicycle()`` work.

    Attributes
    ----------
    values : dict
        The benchmark parameters by name (:data:`MEIJAARD`).
    independent, independent_speeds : list
        The usual choice for linearizing: every coordinate but the pitch θ_B (fixed by the
        contact constraint); the rates of lean φ, rear wheel θ_R and steer δ.
    lean_steer : list
        The states of Meijaard's linearized equations: φ, δ, φ̇, δ̇.
    """

    values: dict
    independent: list
    independent_speeds: list
    lean_steer: list

    def operating_point(self, v: float, values: dict | None = None) -> dict:
        """:func:`bicycle_operating_point` (upright, straight, at speed ``v``)."""
        return bicycle_operating_point(v, values if values is not None else self.values)

    def __iter__(self):
        return iter((self, dict(self.values), bicycle_operating_point))


def whipple_bicycle() -> Bicycle:
    """The Whipple bicycle: 8 coordinates, 4 no-slip and 1 contact constraint.

    Coordinates ``x y psi phi thetaR thetaB delta thetaF`` (:data:`COORDINATES`), parameters the
    symbols of :data:`MEIJAARD` (compile with those values for the benchmark bicycle).
    Constraints, in order: ``front contact`` (holonomic), ``rear no slip x``, ``rear no slip y``,
    ``front no slip x``, ``front no slip y`` (components along the yaw frame's x and y).

    Returns
    -------
    Bicycle
        A :class:`pfaff.System` that also unpacks as ``(system, parameters,
        operating_point)``: the benchmark values :data:`MEIJAARD` and the function
        :func:`bicycle_operating_point` ``(v) -> op_point`` of upright straight running.

    Examples
    --------
    >>> bike, values, operating_point = whipple_bicycle()
    >>> bike.n, len(bike.parameters), values["w"]
    (8, 26, 1.02)
    >>> lin = bike.equations().linearize(
    ...     operating_point(5.0), bike.independent, bike.independent_speeds
    ... )
    >>> lin.is_stable()  # inside the self-stable range 4.29 < v < 6.02 m/s
    True
    """
    import sympy.physics.mechanics as me

    q = coordinates(COORDINATES)
    kin = bicycle_kinematics(q, [speed(qi) for qi in q])
    N, Y, P = kin["N"], kin["Y"], kin["P"]
    bike = Bicycle(list(q), name="Whipple bicycle")
    for body in kin["bodies"]:
        bike.add_kinetic_energy(body.kinetic_energy(N), name=body.name)
    height = [me.dot(b.masscenter.pos_from(P), Y.z) for b in kin["bodies"]]  # z is down
    bike.add_potential_energy(
        -kin["g"] * sum(b.mass * h for b, h in zip(kin["bodies"], height, strict=True)),
        name="gravity",
    )
    bike.add_holonomic_constraint(kin["holonomic"], name="front contact")
    for wheel in ("rear", "front"):
        v = kin[f"v_{wheel}"]
        bike.add_velocity_constraint(me.dot(v, Y.x), name=f"{wheel} no slip x")
        bike.add_velocity_constraint(me.dot(v, Y.y), name=f"{wheel} no slip y")
    x, y, psi, phi, th_r, _, delta, th_f = q
    _add_shapes(bike, kin, x * N.x + y * N.y)
    bike.values = dict(MEIJAARD)
    bike.independent = [x, y, psi, phi, th_r, delta, th_f]
    bike.independent_speeds = [phi, th_r, delta]
    bike.lean_steer = [phi, delta, speed(phi), speed(delta)]
    return bike


def _add_shapes(bike: System, kin: dict, rear_contact: object) -> None:
    """What animations and the viewer draw (``add_shape``; nothing enters the equations): the
    wheels as discs of their radii, the frame with its rider and the fork as the ellipsoids of
    their masses and inertias."""
    N = kin["N"]
    for body in kin["bodies"]:
        where = rear_contact + body.masscenter.pos_from(kin["P"])
        if "wheel" in body.name:
            r = sp.Symbol("rR" if body.name.startswith("rear") else "rF")
            size = [r, r / 12, r]  # the axle is the wheel frame's y
            bike.add_shape(where, body.frame, size=size, name=body.name, frame=N)
        else:  # Meijaard's table: I_xx, I_yy, I_zz and I_xz of the frame (B) and the fork (H)
            b = "B" if body.name == "frame" else "H"
            ixx, iyy, izz, ixz = (sp.Symbol(f"I{b}{k}") for k in ("xx", "yy", "zz", "xz"))
            inertia = sp.Matrix([[ixx, 0, ixz], [0, iyy, 0], [ixz, 0, izz]])
            bike.add_shape(
                where, body.frame, mass=body.mass, inertia=inertia, name=body.name, frame=N
            )


def bicycle_operating_point(v: float, values: dict | None = None) -> dict:
    """Upright straight running at forward speed ``v`` (m/s): the operating point of the benchmark.

    All coordinates 0 (the pitch is 0 upright for the benchmark's geometry), ẋ = v, the wheels
    rolling θ̇_R = −v/r_R, θ̇_F = −v/r_F (they spin about −y as the bicycle runs along +x), the
    other rates 0; and the parameter values by name (``values``, default :data:`MEIJAARD`), so
    that the linearization is numeric. Keys: the coordinates, their rates and parameter names.

    Examples
    --------
    >>> op = bicycle_operating_point(5.0)
    >>> x, y, psi, phi, thR, thB, delta, thF = coordinates(COORDINATES)
    >>> op[x.diff()], op[thR.diff()], op["rR"]
    (5.0, -16.666666666666668, 0.3)
    """
    values = dict(MEIJAARD if values is None else values)
    q = coordinates(COORDINATES)
    v = float(v)
    rates = dict.fromkeys(q, 0.0)
    rates[q[0]] = v
    rates[q[4]] = -v / float(values["rR"])
    rates[q[7]] = -v / float(values["rF"])
    return {**dict.fromkeys(q, 0.0), **{speed(qi): r for qi, r in rates.items()}, **values}


def meijaard_lean_steer(speed: float, g: float = MEIJAARD["g"]) -> np.ndarray:
    """-M⁻¹ [g K0 + v² K2, v C1] from the published benchmark matrices (Meijaard et al., eq. A1):
    the lower half of the state matrix of (φ, δ, φ̇, δ̇)."""
    M, C1, K0, K2 = (np.array(a) for a in (MEIJAARD_M, MEIJAARD_C1, MEIJAARD_K0, MEIJAARD_K2))
    return -np.linalg.solve(M, np.hstack([g * K0 + speed**2 * K2, speed * C1]))


def meijaard_eigenvalues(speed: float) -> np.ndarray:
    """Eigenvalues of the published linearized equations at ``speed``, sorted as
    :meth:`pfaff.Linearization.eigenvalues` (by real part, then imaginary part)."""
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2:] = meijaard_lean_steer(speed)
    w = np.linalg.eigvals(A).astype(complex)
    return w[np.lexsort((w.imag, w.real))]


# ------------------------------------------------------------------ consistent states
@functools.cache
def _constraint_functions() -> tuple:
    """Lambdified front contact height f(q, params) and the 5 x 8 matrix of all constraint rows
    (∂f/∂q, then the four no-slip rows) at (q, params), from the kinematics alone (not pfaff)."""
    import sympy.physics.mechanics as me

    q = coordinates(COORDINATES)
    qd = [speed(qi) for qi in q]
    kin = bicycle_kinematics(q, qd)
    Y = kin["Y"]
    qs = sp.symbols("q0:8")
    us = sp.symbols("u0:8")
    rep = {**dict(zip(qd, us, strict=True)), **dict(zip(q, qs, strict=True))}
    rows = [
        me.dot(kin["v_rear"], Y.x),
        me.dot(kin["v_rear"], Y.y),
        me.dot(kin["v_front"], Y.x),
        me.dot(kin["v_front"], Y.y),
    ]
    f = kin["holonomic"].xreplace(rep)
    slip = sp.Matrix([r.xreplace(rep) for r in rows])
    A = sp.Matrix([f]).jacobian(qs).col_join(slip.jacobian(us))
    params = [sp.Symbol(s) for s in MEIJAARD]
    return (
        sp.lambdify([qs, params], f, modules="numpy", cse=True),
        sp.lambdify([qs, params], A, modules="numpy", cse=True),
    )


def bicycle_state(
    values: dict,
    *,
    phi: float = 0.0,
    delta: float = 0.0,
    phi_dot: float = 0.0,
    delta_dot: float = 0.0,
    speed: float = 0.0,
    x: float = 0.0,
    y: float = 0.0,
    psi: float = 0.0,
    theta_r: float = 0.0,
    theta_f: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """A state (q, q̇) of :func:`whipple_bicycle` that satisfies all five constraints.

    The pitch θ_B solves the contact condition (``scipy.optimize.brentq``, near 0); the rates of x,
    y, ψ, θ_B and θ_F solve the velocity constraints given φ̇, δ̇ and θ̇_R = -speed / r_R (``speed``
    is the rear hub's forward speed when the frame does not pitch).
    """
    from scipy.optimize import brentq

    f, A = _constraint_functions()
    p = [float(values[s]) for s in MEIJAARD]
    q = np.array([x, y, psi, phi, theta_r, 0.0, delta, theta_f], dtype=float)

    def height(pitch: float) -> float:
        q[5] = pitch
        return float(f(q, p))

    q[5] = brentq(height, -0.5, 0.5, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    ind, dep = [3, 4, 6], [0, 1, 2, 5, 7]
    qd = np.zeros(8)
    qd[ind] = phi_dot, -speed / float(values["rR"]), delta_dot
    Aq = np.asarray(A(q, p), dtype=float)
    qd[dep] = np.linalg.solve(Aq[:, dep], -Aq[:, ind] @ qd[ind])
    return q, qd


# ------------------------------------------------------------------ stability
def lean_steer_eigenvalues(lin) -> np.ndarray:
    """The eigenvalues of a bicycle's :class:`pfaff.Linearization` without the zero ones of its
    ignorable states (position, yaw, wheel angles, rear wheel rate): Meijaard's four, sorted by
    real part, then imaginary part."""
    A = np.asarray(lin.A, dtype=float)
    keep = [k for k in range(A.shape[0]) if k not in set(lin.ignorable())]
    w = np.linalg.eigvals(A[np.ix_(keep, keep)]).astype(complex)
    return w[np.lexsort((w.imag, w.real))]


def _crossing(fn, speeds: np.ndarray, rising: bool) -> float:
    """The first speed where ``fn`` turns positive (``rising``) or negative, by Brent's method."""
    from scipy.optimize import brentq

    vals = [fn(v) for v in speeds]
    for k in range(len(speeds) - 1):
        lo, hi = (vals[k], vals[k + 1]) if rising else (-vals[k], -vals[k + 1])
        if lo <= 0 < hi:
            return float(brentq(fn, speeds[k], speeds[k + 1], xtol=1e-14, rtol=1e-15))
    return float("nan")


def stability_speeds(eom=None, values: dict | None = None, vmax: float = 10.0) -> tuple:
    """The weave and capsize speeds (m/s) of a Whipple bicycle, by root finding on pfaff's own
    linearization (:meth:`pfaff.EquationsOfMotion.linearize`).

    The weave speed is where the real part of the oscillating pair of lean-steer eigenvalues
    turns negative, the capsize speed where the real eigenvalue of the capsize mode turns
    positive; the bicycle is self-stable between them. NaN where no crossing lies in
    [1, ``vmax``] (the capsize speed: above the weave speed). For the benchmark: 4.29238253634111 and 6.02426201538837 (Meijaard et al.).

    Parameters
    ----------
    eom : EquationsOfMotion, optional
        The bicycle's equations (default: derived here from :func:`whipple_bicycle`).
    values : dict, optional
        Parameter values (default :data:`MEIJAARD`).
    vmax : float
        The largest speed searched.
    """
    bike = whipple_bicycle()
    eom = bike.equations() if eom is None else eom
    values = MEIJAARD if values is None else values

    @functools.cache
    def eig(v: float) -> np.ndarray:
        lin = eom.linearize(
            bicycle_operating_point(v, values), bike.independent, bike.independent_speeds
        )
        return lean_steer_eigenvalues(lin)

    def weave(v: float) -> float:
        w = eig(v)
        osc = w[np.abs(w.imag) > 1e-9]
        return float(osc.real.max()) if osc.size else 1.0

    def capsize(v: float) -> float:
        w = eig(v)
        real = w[np.abs(w.imag) <= 1e-9].real
        return float(real.max()) if real.size else -1.0

    grid = np.arange(1.0, vmax + 0.5, 1.0)
    v_weave = _crossing(weave, grid, rising=False)
    start = v_weave if np.isfinite(v_weave) else grid[0]
    return v_weave, _crossing(capsize, np.arange(start, vmax + 0.5, 1.0), rising=True)
