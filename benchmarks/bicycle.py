"""Benchmark: the Whipple bicycle of Meijaard et al. (2007), pfaff against SymPy's KanesMethod.

The benchmark bicycle of J. P. Meijaard, J. M. Papadopoulos, A. Ruina and A. L. Schwab,
"Linearized dynamics equations for the balance and steer of a bicycle: a benchmark and review",
Proc. R. Soc. A 463 (2007) 1955-1982: four rigid bodies (rear wheel R, rear frame with rider B,
front fork and handlebar H, front wheel F), knife-edge wheels rolling without slip on flat
ground. Eight coordinates, in Meijaard's axes (x forward, y right, z down):

    q = (x, y, ψ, φ, θ_R, θ_B, δ, θ_F)

the rear contact point (x, y), yaw ψ, lean (roll) φ, the rear wheel's rotation θ_R relative to
the frame, the frame's pitch θ_B, steer δ and the front wheel's rotation θ_F relative to the fork;
four nonholonomic no-slip constraints (both contact points, in the ground plane) and one holonomic
one (the front wheel touches the ground), so three degrees of freedom at the velocity level.

:func:`whipple_bicycle` builds it in pfaff: the kinetic energy of each body from
``sympy.physics.mechanics`` frames and points (an expression in q and q̇), gravity as a potential,
the contact constraints with ``add_velocity_constraint`` / ``add_holonomic_constraint``.
:func:`kane_bicycle` builds the same bicycle from the same kinematics the standard way with
``KanesMethod`` (u = q̇, the pitch dependent with the configuration constraint, the speeds of x, y,
ψ, θ_B, θ_F dependent with five velocity constraints, as in SymPy's ``test_kane3.py``).

Run (from the project root)::

    python benchmarks/bicycle.py               # cold CPU seconds, one fresh process per tool
    python benchmarks/bicycle.py --repeat 3    # best of three fresh processes per tool

Printed: CPU seconds from nothing to a numeric model (pfaff: ``System`` build + ``equations()`` +
``compile(values)``, the on-disk code cache off; Kane: build + ``kanes_equations`` +
``lambdify(cse=True)`` of ``mass_matrix_full`` and ``forcing_full``), each in a fresh subprocess
with SymPy's cache cleared, one BLAS thread, and the imports (and first-call costs, on a pendulum)
excluded; the CPU seconds of pfaff's first ``ode_function()`` call (where its machine-code
right-hand side is made); one right-hand side in CPU µs (timeit, best of several): pfaff's
``accelerations`` (checked, q̈ and λ), ``solve`` (unchecked, q̈ and λ) and ``ode_function`` (q̇ and
q̈ only) against the lambdified Kane matrices + ``numpy.linalg.solve``; and the largest relative
difference of q̈ between pfaff and Kane at three random states that satisfy the constraints.
"""

from __future__ import annotations

import argparse
import functools
import gc
import json
import os
import subprocess
import sys
import time
import timeit

import numpy as np
import sympy as sp
import sympy.physics.mechanics as me
from scipy.optimize import brentq
from sympy.core.cache import clear_cache

import pfaff
from pfaff import System, coordinates

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


# --------------------------------------------------------------------------- the model
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

    def wheel_inertia(frame: me.ReferenceFrame, axial: str, radial: str) -> me.Dyadic:
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


def whipple_bicycle() -> System:
    """The Whipple bicycle in pfaff: 8 coordinates, 4 no-slip and 1 contact constraint.

    Coordinates ``x y psi phi thetaR thetaB delta thetaF`` (:data:`COORDINATES`), parameters the
    symbols of :data:`MEIJAARD` (compile with those values for the benchmark bicycle).
    Constraints, in order: ``front contact`` (holonomic), ``rear no slip x``, ``rear no slip y``,
    ``front no slip x``, ``front no slip y`` (components along the yaw frame's x and y).

    Examples
    --------
    >>> s = whipple_bicycle()
    >>> s.n, len(s.parameters)
    (8, 26)
    """
    q = coordinates(COORDINATES)
    kin = bicycle_kinematics(q, [qi.diff(me.dynamicsymbols._t) for qi in q])  # t of pfaff
    N, Y, P = kin["N"], kin["Y"], kin["P"]
    bike = System(list(q), name="Whipple bicycle")
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
    return bike


def kane_bicycle() -> tuple[me.KanesMethod, list, list]:
    """The same bicycle with SymPy's ``KanesMethod``: u = q̇, θ_B and five speeds dependent.

    Independent speeds: lean, rear wheel and steer rates. The velocity constraints are the rear
    contact's x, y and the front contact's x, y, z components (the last one is the derivative of
    the holonomic constraint, the configuration constraint here). Returns ``(kane, q, u)`` after
    ``kanes_equations``; ``kane.q`` and ``kane.u`` list the independent ones first.

    The dependent speeds are solved for by Cramer's rule, as in ``test_kane3.py``. SymPy's default
    (``constraint_solver="LU"``, elimination in the given row order) takes as its fourth pivot an
    expression that vanishes wherever the front wheel touches the ground (1e-14 at a consistent
    state, 10.6 away from one): its equations are then wrong at every consistent state.
    """
    q = me.dynamicsymbols(COORDINATES)
    u = me.dynamicsymbols(" ".join(f"u_{s}" for s in COORDINATES.split()))
    kin = bicycle_kinematics(q, u)
    Y = kin["Y"]
    v_rear, v_front = kin["v_rear"], kin["v_front"]
    independent, pitch = (3, 4, 6), 5
    kane = me.KanesMethod(
        kin["N"],
        q_ind=[qi for i, qi in enumerate(q) if i != pitch],
        u_ind=[u[i] for i in independent],
        kd_eqs=[qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(q, u, strict=True)],
        q_dependent=[q[pitch]],
        configuration_constraints=[kin["holonomic"]],
        u_dependent=[ui for i, ui in enumerate(u) if i not in independent],
        velocity_constraints=[
            me.dot(v_rear, Y.x),
            me.dot(v_rear, Y.y),
            me.dot(v_front, Y.x),
            me.dot(v_front, Y.y),
            me.dot(v_front, Y.z),
        ],
        constraint_solver="CRAMER",  # as test_kane3; the default LU picks a pivot that is 0
    )
    gravity = [(b.masscenter, b.mass * kin["g"] * Y.z) for b in kin["bodies"]]
    kane.kanes_equations(kin["bodies"], gravity)
    return kane, q, u


def kane_accelerations(kane: me.KanesMethod, q: list, u: list, values: dict):
    """``rhs(q, q̇) -> q̈`` from ``lambdify(cse=True)`` of Kane's full mass matrix and forcing.

    ``q`` and ``q̇`` in the order of ``q`` and ``u`` given (:data:`COORDINATES`); Kane's own
    order (independent first) is undone on the way out.
    """
    names = list(MEIJAARD)
    args = [*q, *u, *(sp.Symbol(s) for s in names)]
    fM = sp.lambdify(args, kane.mass_matrix_full, modules="numpy", cse=True)
    ff = sp.lambdify(args, kane.forcing_full, modules="numpy", cse=True)
    p = [float(values[s]) for s in names]
    n = len(q)
    order = [list(kane.u).index(ui) for ui in u]  # Kane orders u independent first

    def rhs(qv: np.ndarray, qdv: np.ndarray) -> np.ndarray:
        x = np.linalg.solve(fM(*qv, *qdv, *p), np.ravel(ff(*qv, *qdv, *p)))
        return x[n:][order]

    return rhs


# --------------------------------------------------------------------------- consistent states
@functools.cache
def _constraint_functions() -> tuple:
    """Lambdified front contact height f(q, params) and the 5 x 8 matrix of all constraint rows
    (∂f/∂q, then the four no-slip rows) at (q, params), from the kinematics alone (not pfaff)."""
    q = coordinates(COORDINATES)
    qd = [qi.diff(me.dynamicsymbols._t) for qi in q]
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


def random_state(values: dict, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random consistent state: leaning, steered, rolling forward at 1 to 5 m/s."""
    return bicycle_state(
        values,
        phi=rng.uniform(-0.4, 0.4),
        delta=rng.uniform(-0.6, 0.6),
        phi_dot=rng.uniform(-1.0, 1.0),
        delta_dot=rng.uniform(-1.0, 1.0),
        speed=rng.uniform(1.0, 5.0),
        x=rng.uniform(-1.0, 1.0),
        y=rng.uniform(-1.0, 1.0),
        psi=rng.uniform(-np.pi, np.pi),
        theta_r=rng.uniform(-np.pi, np.pi),
        theta_f=rng.uniform(-np.pi, np.pi),
    )


def lean_steer_matrix(accelerations, values: dict, speed: float, h: float = 1e-5) -> np.ndarray:
    """∂(φ̈, δ̈)/∂(φ, δ, φ̇, δ̇) about upright straight running at ``speed`` (central differences).

    ``accelerations(q, q̇) -> q̈``. Meijaard's linearized equations give
    -M⁻¹ [g K0 + v² K2, v C1] for it.
    """
    names = ("phi", "delta", "phi_dot", "delta_dot")
    J = np.empty((2, 4))
    for j, name in enumerate(names):
        plus = accelerations(*bicycle_state(values, speed=speed, **{name: h}))
        minus = accelerations(*bicycle_state(values, speed=speed, **{name: -h}))
        J[:, j] = (plus[[3, 6]] - minus[[3, 6]]) / (2 * h)
    return J


def meijaard_lean_steer(speed: float, g: float = MEIJAARD["g"]) -> np.ndarray:
    """-M⁻¹ [g K0 + v² K2, v C1] from the published benchmark matrices."""
    M, C1, K0, K2 = (np.array(a) for a in (MEIJAARD_M, MEIJAARD_C1, MEIJAARD_K0, MEIJAARD_K2))
    return -np.linalg.solve(M, np.hstack([g * K0 + speed**2 * K2, speed * C1]))


# --------------------------------------------------------------------------- measurements
def _fresh() -> float:
    clear_cache()
    gc.collect()
    return time.process_time()


def _best_us(fn, number: int = 200, repeat: int = 5) -> float:
    """CPU µs of one call, best of ``repeat`` (CPU time: robust on a loaded machine)."""
    runs = timeit.repeat(fn, number=number, repeat=repeat, timer=time.process_time)
    return min(runs) / number * 1e6


def _warm_up() -> None:
    """First-call costs (lazy imports) of both tools on a pendulum, untimed."""
    pendulum = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    pendulum.ode_function()(0.0, np.array([0.1, 0.0]))
    th, u = me.dynamicsymbols("th u")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    A.set_ang_vel(N, u * N.z)
    pivot = me.Point("pivot")
    pivot.set_vel(N, 0)
    bob = pivot.locatenew("bob", A.x)
    bob.v2pt_theory(pivot, N, A)
    km = me.KanesMethod(N, [th], [u], kd_eqs=[th.diff() - u])
    km.kanes_equations([me.Particle("p", bob, 1)], [(bob, -9.81 * N.y)])
    sp.lambdify([th, u], km.mass_matrix_full, cse=True)
    sp.lambdify([th, u], km.forcing_full, cse=True)


def measure(tool: str, states: list) -> dict:
    """One cold run of ``tool`` ("pfaff" or "kane") in this process, then q̈ and λ at ``states``
    ([(q, q̇), …]) and the µs of one right-hand side at the first."""
    _warm_up()
    values = MEIJAARD
    out: dict = {}
    if tool == "pfaff":
        t0 = _fresh()
        bike = whipple_bicycle()
        t1 = time.process_time()
        eom = bike.equations()
        t2 = time.process_time()
        model = eom.compile(values)
        t3 = time.process_time()
        out |= {"build": t1 - t0, "equations": t2 - t1, "compile": t3 - t2, "total": t3 - t0}
        results = [model.accelerations(0.0, q, qd) for q, qd in states]
        out["qdd"] = [r[0].tolist() for r in results]
        out["lambda"] = [r[1].tolist() for r in results]
        q, qd = (np.asarray(a) for a in states[0])
        y = np.concatenate([q, qd])
        t4 = time.process_time()
        fun = model.ode_function()  # the machine-code right-hand side is made here
        fun(0.0, y)
        out["ode_function"] = time.process_time() - t4
        out["us"] = {
            "accelerations": _best_us(lambda: model.accelerations(0.0, q, qd)),
            "solve": _best_us(lambda: model.solve(0.0, q, qd)),
            "ode_function": _best_us(lambda: fun(0.0, y)),
        }
    else:
        t0 = _fresh()
        kane, qs, us = kane_bicycle()
        t1 = time.process_time()
        rhs = kane_accelerations(kane, qs, us, values)
        t2 = time.process_time()
        out |= {"build": t1 - t0, "lambdify": t2 - t1, "total": t2 - t0}
        out["qdd"] = [rhs(np.asarray(q), np.asarray(qd)).tolist() for q, qd in states]
        q, qd = (np.asarray(a) for a in states[0])
        out["us"] = {"lambdified + solve": _best_us(lambda: rhs(q, qd))}
    return out


def _run(tool: str, states: list) -> dict:
    """:func:`measure` in a fresh Python process (pfaff's on-disk code cache off; one BLAS
    thread: matrices of 13 and 16 rows gain nothing from threads, and on a busy machine the
    waiting threads cost 10-50x per solve)."""
    threads = {v: "1" for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env = os.environ | {"PFAFF_CACHE": "0"} | threads
    done = subprocess.run(
        [sys.executable, __file__, "--measure", tool],
        input=json.dumps([[q.tolist(), qd.tolist()] for q, qd in states]),
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    if done.returncode:
        raise RuntimeError(f"the {tool} run failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1, help="fresh processes per tool (best)")
    ap.add_argument("--states", type=int, default=3, help="random consistent states compared")
    ap.add_argument("--seed", type=int, default=2007)
    ap.add_argument("--measure", choices=("pfaff", "kane"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.measure:
        states = [(np.array(q), np.array(qd)) for q, qd in json.loads(sys.stdin.read())]
        print(json.dumps(measure(args.measure, states)))
        return
    rng = np.random.default_rng(args.seed)
    states = [random_state(MEIJAARD, rng) for _ in range(args.states)]
    runs = {tool: [_run(tool, states) for _ in range(args.repeat)] for tool in ("pfaff", "kane")}
    pf = min(runs["pfaff"], key=lambda r: r["total"])
    kn = min(runs["kane"], key=lambda r: r["total"])
    errs = [
        float(np.max(np.abs(np.subtract(a, b))) / np.max(np.abs(b)))
        for a, b in zip(pf["qdd"], kn["qdd"], strict=True)
    ]
    print(
        "Whipple bicycle (Meijaard et al. 2007): 8 coordinates, 4 nonholonomic + 1 holonomic "
        f"constraint; cold CPU s, fresh process, best of {args.repeat}"
    )
    width = 40
    print(f"{'':{width}} {'pfaff':>9} {'kane':>9} {'pfaff/kane':>11}")
    rows = [
        ("model to numeric model (s)", pf["total"], kn["total"]),
        ("  build: System / KanesMethod (s)", pf["build"], kn["build"]),
        ("  equations() (s)", pf["equations"], None),
        ("  compile() / lambdify (s)", pf["compile"], kn["lambdify"]),
        ("first ode_function() call (s)", pf["ode_function"], None),
    ]
    k_us = kn["us"]["lambdified + solve"]
    rows += [(f"one right-hand side, {name} (µs)", us, k_us) for name, us in pf["us"].items()]
    for label, a, b in rows:
        fmt = ".3f" if label.endswith("(s)") else ".1f"
        kane, ratio = ("-", "") if b is None else (f"{b:{fmt}}", f"{a / b:.3f}")
        print(f"{label:{width}} {a:9{fmt}} {kane:>9} {ratio:>11}")
    print(
        f"max relative |Δq̈| pfaff vs Kane over {len(states)} consistent states: {max(errs):.1e} "
        f"({', '.join(f'{e:.1e}' for e in errs)}): {'OK' if max(errs) <= 1e-9 else 'FAIL'}"
    )
    if max(errs) > 1e-9:
        sys.exit(1)


if __name__ == "__main__":
    main()
