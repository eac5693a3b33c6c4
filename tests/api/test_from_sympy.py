"""pfaff.from_sympy against SymPy's own equations of the same model.

Each model is built once with sympy.physics.mechanics (frames, points, particles, rigid bodies,
gravity as loads); pfaff's compiled accelerations are compared with the solution of SymPy's
``mass_matrix_full`` / ``forcing_full`` at random states.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import (
    KanesMethod,
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    RigidBody,
    dynamicsymbols,
    inertia,
)

import pfaff

t = pfaff.t
m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
VALUES = {m1: 1.3, m2: 0.7, l1: 1.1, l2: 0.9, g: 9.81}


def _double_pendulum():
    """Two particles on massless rods, angles from the vertical; gravity as loads."""
    q1, q2 = dynamicsymbols("q1 q2")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    O0 = Point("O")
    O0.set_vel(N, 0)
    P1 = O0.locatenew("P1", -l1 * A.y)
    P2 = P1.locatenew("P2", -l2 * B.y)
    P1.set_vel(N, P1.pos_from(O0).dt(N))
    P2.set_vel(N, P2.pos_from(O0).dt(N))
    bodies = [Particle("p1", P1, m1), Particle("p2", P2, m2)]
    loads = [(P1, -m1 * g * N.y), (P2, -m2 * g * N.y)]
    return (q1, q2), N, bodies, loads


def _double_pendulum_kane():
    (q1, q2), N, _, _ = _double_pendulum()
    u1, u2 = dynamicsymbols("u1 u2")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    A.set_ang_vel(N, u1 * N.z)
    B.set_ang_vel(N, u2 * N.z)
    O0 = Point("O")
    O0.set_vel(N, 0)
    P1 = O0.locatenew("P1", -l1 * A.y)
    P2 = P1.locatenew("P2", -l2 * B.y)
    P1.v2pt_theory(O0, N, A)
    P2.v2pt_theory(P1, N, B)
    bodies = [Particle("p1", P1, m1), Particle("p2", P2, m2)]
    loads = [(P1, -m1 * g * N.y), (P2, -m2 * g * N.y)]
    kd = [q1.diff(t) - u1, q2.diff(t) - u2]
    km = KanesMethod(N, [q1, q2], [u1, u2], kd_eqs=kd)
    km.kanes_equations(bodies, loads)
    return km


def _solve_full(M, F, args, x):
    f = sp.lambdify(args, [M, F], "numpy")
    Mn, Fn = f(*x)
    return np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())


def test_double_pendulum_kane():
    km = _double_pendulum_kane()
    model = pfaff.from_sympy(km).equations().compile({s.name: v for s, v in VALUES.items()})
    pars = list(VALUES)
    args = [*km.q, *km.u, *pars]
    f = sp.lambdify(args, [km.mass_matrix_full, km.forcing_full], "numpy")
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(20):
        q, u = rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3, 3, 2)
        Mn, Fn = f(*q, *u, *VALUES.values())
        ref = np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())[2:]
        qdd, _ = model.accelerations(0.0, q, u)  # u = q̇ here
        worst = max(worst, np.max(np.abs(qdd - ref)) / max(1.0, np.max(np.abs(ref))))
    assert worst < 1e-12


def test_double_pendulum_lagrange():
    (q1, q2), N, bodies, loads = _double_pendulum()
    lm = LagrangesMethod(Lagrangian(N, *bodies), [q1, q2], forcelist=loads, frame=N)
    lm.form_lagranges_equations()
    system = pfaff.from_sympy(lm)
    assert set(system.parameters) == set(VALUES)
    model = system.equations().compile(VALUES)
    qd = [q1.diff(t), q2.diff(t)]
    f = sp.lambdify([q1, q2, *qd, *VALUES], [lm.mass_matrix_full, lm.forcing_full], "numpy")
    rng = np.random.default_rng(2)
    worst = 0.0
    for _ in range(20):
        q, v = rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3, 3, 2)
        Mn, Fn = f(*q, *v, *VALUES.values())
        ref = np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())[2:]
        qdd, _ = model.accelerations(0.0, q, v)
        worst = max(worst, np.max(np.abs(qdd - ref)) / max(1.0, np.max(np.abs(ref))))
    assert worst < 1e-12


def test_cartesian_pendulum_lagrange_multiplier_sign():
    """A holonomic constraint: same q̈, and λ_pfaff = +λ of SymPy's matrix form."""
    x, y = dynamicsymbols("x y")
    m, L = sp.symbols("m L")
    N = ReferenceFrame("N")
    P = Point("P")
    P.set_vel(N, x.diff(t) * N.x + y.diff(t) * N.y)
    lm = LagrangesMethod(
        Lagrangian(N, Particle("p", P, m)),
        [x, y],
        hol_coneqs=[x**2 + y**2 - L**2],
        forcelist=[(P, -m * g * N.y)],
        frame=N,
    )
    lm.form_lagranges_equations()
    vals = {m: 0.8, L: 1.5, g: 9.81}
    model = pfaff.from_sympy(lm).equations().compile(vals)
    th = 0.4
    qn = np.array([1.5 * np.sin(th), -1.5 * np.cos(th)])
    v = np.array([np.cos(th), np.sin(th)]) * 0.7
    f = sp.lambdify([x, y, x.diff(t), y.diff(t), *vals], [lm.mass_matrix_full, lm.forcing_full])
    Mn, Fn = f(*qn, *v, *vals.values())
    ref = np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())
    qdd, lam = model.accelerations(0.0, qn, v)
    np.testing.assert_allclose(qdd, ref[2:4], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(lam, ref[4:], rtol=1e-12)


def test_parameters_dict_and_declared():
    km = _double_pendulum_kane()
    s = pfaff.from_sympy(km, parameters={"g": 9.81, l2: 0.9})
    assert {p.name for p in s.parameters} == {"m1", "m2", "l1"}
    s = pfaff.from_sympy(km, parameters=list(VALUES))
    assert set(s.parameters) == set(VALUES)
    with pytest.raises(pfaff.ModelError, match="outside the declared parameters"):
        pfaff.from_sympy(km, parameters=[m1, m2, l1])
    with pytest.raises(pfaff.ModelError, match="not a symbol of the model"):
        pfaff.from_sympy(km, parameters={"k": 1.0})


@pytest.mark.parametrize("obj", ["pendulum", 3, ReferenceFrame("N")])
def test_refuses_other_objects(obj):
    with pytest.raises(pfaff.ModelTypeError, match="LagrangesMethod, KanesMethod or System"):
        pfaff.from_sympy(obj)


def test_refuses_a_body():
    B, O0 = ReferenceFrame("B"), Point("O")
    body = RigidBody("B", O0, B, 1, (inertia(B, 1, 1, 1), O0))
    with pytest.raises(pfaff.ModelError, match="got RigidBody"):
        pfaff.from_sympy(body)


def _rolling_disc_kane():
    """A thin disc rolling without slip on the plane z = 0: yaw q1, lean q2, spin q3, contact
    point (q4, q5). Speeds: u1..u3 the disc's angular velocity in the lean frame B, u4, u5 the
    contact point's velocity (dependent, from the two no-slip constraints)."""
    q = dynamicsymbols("q1:6")
    u = dynamicsymbols("u1:6")
    m, r = sp.symbols("m r")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q[0], N.z])
    B = A.orientnew("B", "Axis", [q[1], A.x])
    C = B.orientnew("C", "Axis", [q[2], B.y])
    w = C.ang_vel_in(N)
    kd = [w.dot(B.x) - u[0], w.dot(B.y) - u[1], w.dot(B.z) - u[2]]
    kd += [q[3].diff(t) - u[3], q[4].diff(t) - u[4]]
    C.set_ang_vel(N, u[0] * B.x + u[1] * B.y + u[2] * B.z)
    O0 = Point("O")
    O0.set_vel(N, 0)
    D = O0.locatenew("D", q[3] * N.x + q[4] * N.y + r * B.z)
    D.set_vel(N, D.pos_from(O0).dt(N))
    contact = D.vel(N) + C.ang_vel_in(N).cross(-r * B.z)  # the disc's material contact point
    I = inertia(B, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)  # noqa: E741
    disc = RigidBody("disc", D, C, m, (I, D))
    km = KanesMethod(
        N,
        q_ind=list(q),
        u_ind=list(u[:3]),
        kd_eqs=kd,
        u_dependent=list(u[3:]),
        velocity_constraints=[contact.dot(A.x), contact.dot(A.y)],
    )
    km.kanes_equations([disc], [(D, -m * g * N.z)])
    return km, (m, r)


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_rolling_disc_kane_nonholonomic():
    km, (m, r) = _rolling_disc_kane()
    vals = {m: 1.7, r: 0.4, g: 9.81}
    system = pfaff.from_sympy(km)
    assert system.n_constraints == 2
    model = system.equations().compile(vals)
    q, u = list(km.q), list(km.u)
    qdmap = km.kindiffdict()
    qd_of_u = sp.Matrix([qdmap[c.diff(t)] for c in q])
    ud = sp.symbols("ud1:6")
    qdd_of_ud = qd_of_u.diff(t).xreplace(dict(zip([c.diff(t) for c in u], ud, strict=True)))
    qdd_of_ud = qdd_of_ud.xreplace(qdmap)
    pars = list(vals)
    f_kane = sp.lambdify([*q, *u, *pars], [km.mass_matrix_full, km.forcing_full])
    f_qd = sp.lambdify([*q, *u, *pars], qd_of_u)
    f_qdd = sp.lambdify([*q, *u, *ud, *pars], qdd_of_ud)
    # dependent speeds from the constraints k_nh u + f_nh = 0
    f_nh = sp.lambdify([*q, *u[:3], *pars], [km._k_nh[:, 3:], km._k_nh[:, :3], km._f_nh])
    rng = np.random.default_rng(3)
    pv = list(vals.values())
    worst = 0.0
    for _ in range(5):
        qn = rng.uniform(-1, 1, 5)
        ui = rng.uniform(-2, 2, 3)
        Kd, Ki, f0 = (np.array(a, float) for a in f_nh(*qn, *ui, *pv))
        un = np.concatenate([ui, np.linalg.solve(Kd, -(Ki @ ui + f0.ravel()))])
        Mn, Fn = f_kane(*qn, *un, *pv)
        x = np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())
        assert x.size == 10  # q̇ (5) and u̇ (all 5 speeds)
        ref = np.array(f_qdd(*qn, *un, *x[5:], *pv), float).ravel()
        qd = np.array(f_qd(*qn, *un, *pv), float).ravel()
        np.testing.assert_allclose(model.constraint_residual(0.0, qn, qd)[1], 0, atol=1e-12)
        qdd, _ = model.accelerations(0.0, qn, qd)
        worst = max(worst, np.max(np.abs(qdd - ref)) / max(1.0, np.max(np.abs(ref))))
    assert worst < 1e-10


def test_cartesian_pendulum_kane_configuration_constraint():
    """Kane's configuration constraint is holonomic; its restated velocity constraint is dropped."""
    x, y = dynamicsymbols("x y")
    ux, uy = dynamicsymbols("ux uy")
    m, L = sp.symbols("m L")
    N = ReferenceFrame("N")
    P = Point("P")
    P.set_vel(N, ux * N.x + uy * N.y)
    km = KanesMethod(
        N,
        q_ind=[x],
        u_ind=[ux],
        kd_eqs=[x.diff(t) - ux, y.diff(t) - uy],
        q_dependent=[y],
        configuration_constraints=[x**2 + y**2 - L**2],
        u_dependent=[uy],
        velocity_constraints=[x * ux + y * uy],
    )
    km.kanes_equations([Particle("p", P, m)], [(P, -m * g * N.y)])
    system = pfaff.from_sympy(km)
    assert system.n_constraints == 1  # the holonomic row only
    vals = {m: 0.8, L: 1.5, g: 9.81}
    model = system.equations().compile(vals)
    f = sp.lambdify([x, y, ux, uy, *vals], [km.mass_matrix_full, km.forcing_full])
    rng = np.random.default_rng(4)
    for _ in range(5):
        th, w = rng.uniform(-2, 2, 2)
        q = 1.5 * np.array([np.sin(th), -np.cos(th)])
        v = 1.5 * w * np.array([np.cos(th), np.sin(th)])
        Mn, Fn = f(*q, *v, *vals.values())
        ref = np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())[2:]
        qdd, _ = model.accelerations(0.0, q, v)
        np.testing.assert_allclose(qdd, ref, rtol=1e-12, atol=1e-12)


def test_mechanics_system_double_pendulum():
    """A sympy.physics.mechanics.System (the Kane data) maps like the KanesMethod it forms."""
    km = _double_pendulum_kane()
    s = sp.physics.mechanics.System(km._inertial)
    s.q_ind, s.u_ind = list(km.q), list(km.u)
    s.kdes = [c.diff(t) - v for c, v in zip(km.q, km.u, strict=True)]
    s.add_bodies(*km.bodies)
    s.add_loads(*km.loads)
    a = pfaff.from_sympy(s).equations().compile(VALUES)
    b = pfaff.from_sympy(km).equations().compile(VALUES)
    for q, v in ([0.3, -0.5], [0.2, 1.1]), ([2.0, 1.0], [-1.0, 0.5]):
        np.testing.assert_allclose(a.accelerations(0, q, v)[0], b.accelerations(0, q, v)[0])


def test_knife_edge_lagrange_nonholonomic_and_torque():
    """A nonholonomic LagrangesMethod with a torque on a frame: q̈ and λ_pfaff = +λ (matrices)."""
    x, y, th = dynamicsymbols("x y theta")
    m, J, tau = sp.symbols("m J tau")
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    P = Point("P")
    P.set_vel(N, x.diff(t) * N.x + y.diff(t) * N.y)
    body = RigidBody("sleigh", P, B, m, (inertia(B, 0, 0, J), P))
    lm = LagrangesMethod(
        Lagrangian(N, body),
        [x, y, th],
        nonhol_coneqs=[-sp.sin(th) * x.diff(t) + sp.cos(th) * y.diff(t)],
        forcelist=[(B, tau * N.z), (P, -m * g * N.x)],
        frame=N,
    )
    lm.form_lagranges_equations()
    vals = {m: 1.2, J: 0.3, tau: 0.7, g: 9.81}
    model = pfaff.from_sympy(lm, parameters=["m", "J", "tau", "g"]).equations().compile(vals)
    qd = [c.diff(t) for c in (x, y, th)]
    f = sp.lambdify([x, y, th, *qd, *vals], [lm.mass_matrix_full, lm.forcing_full])
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = rng.uniform(-2, 2, 3)
        s = rng.uniform(-1, 1)
        v = np.array([s * np.cos(q[2]), s * np.sin(q[2]), rng.uniform(-1, 1)])
        Mn, Fn = f(*q, *v, *vals.values())
        ref = np.linalg.solve(np.array(Mn, float), np.array(Fn, float).ravel())
        qdd, lam = model.accelerations(0.0, q, v)
        np.testing.assert_allclose(qdd, ref[3:6], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(lam, ref[6:], rtol=1e-12, atol=1e-12)
