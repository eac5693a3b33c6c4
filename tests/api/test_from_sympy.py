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
