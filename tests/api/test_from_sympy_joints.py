"""pfaff.from_sympy on every joint kind of SymPy, against KanesMethod of the same System.

Each case is a small ``sympy.physics.mechanics.System``: the joint under test between the ground
and a body with a full (off-diagonal) inertia, most with a pendulum body hung on it by a
``PinJoint`` so the joint's coordinates couple with another one; gravity is tilted (−z and +x/3)
so no coordinate is spared. The reference is SymPy's own ``System.form_eoms()`` (Kane's method):
[q̇; u̇] from ``mass_matrix_full`` and ``forcing_full`` at random states. Every joint sets
u = q̇ (its kinematic differential equations are u − q̇ = 0, checked), so u̇ is q̈. One more
case adds SymPy's actuators (springs, a damper, a torque), which enter through their loads.
The refusals at the end are what cannot be mapped: each is a pfaff error naming the problem.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import (
    CylindricalJoint,
    DuffingSpring,
    Force,
    LagrangesMethod,
    LinearDamper,
    LinearPathway,
    LinearSpring,
    PinJoint,
    PlanarJoint,
    Point,
    PrismaticJoint,
    ReferenceFrame,
    RigidBody,
    SphericalJoint,
    System,
    TorqueActuator,
    WeldJoint,
    dynamicsymbols,
    inertia,
)

import pfaff

t = pfaff.t
g = sp.Symbol("g")


def _body(name: str) -> RigidBody:
    """A body of mass m_name with a full inertia dyadic scaled by l_name²."""
    m, length = sp.symbols(f"m_{name} l_{name}")
    body = RigidBody(name, mass=m)
    i = m * length**2
    body.inertia = (inertia(body.frame, i / 12, i / 6, i / 5, i / 30, 0, i / 40), body.masscenter)
    return body


def _length(body: RigidBody) -> sp.Symbol:
    return sp.Symbol(f"l_{body.name}")


def _pendulum(parent: RigidBody, axis) -> PinJoint:
    """A second body hung on ``parent`` by a pin about ``axis`` (a vector of parent's frame)."""
    child = _body("c")
    return PinJoint(
        "pin_c",
        parent,
        child,
        parent_point=_length(parent) / 2 * parent.frame.x,
        child_point=-_length(child) * child.frame.x,
        joint_axis=axis,
    )


def _joints(kind: str, ground: RigidBody, b: RigidBody) -> list:
    N, lb = ground.frame, _length(b)
    if kind == "pin":
        return [
            PinJoint("j", ground, b, child_point=-lb * b.frame.x, joint_axis=N.y),
            _pendulum(b, b.frame.z),
        ]
    if kind == "prismatic":
        return [PrismaticJoint("j", ground, b, joint_axis=N.x + N.y), _pendulum(b, b.frame.z)]
    if kind == "cylindrical":
        j = CylindricalJoint("j", ground, b, joint_axis=N.x, child_point=-lb * b.frame.y)
        return [j, _pendulum(b, b.frame.z)]
    if kind == "planar":
        tilted = N.orientnew("tilted", "Axis", [sp.Rational(3, 10), N.y])
        j = PlanarJoint("j", ground, b, child_point=-lb * b.frame.y, parent_interframe=tilted)
        return [j, _pendulum(b, b.frame.z)]
    if kind == "spherical":
        return [SphericalJoint("j", ground, b, child_point=-lb * b.frame.z)]
    assert kind == "weld"  # a body welded onto a pendulum: the pair swings as one
    pin = PinJoint("j", ground, b, child_point=-lb * b.frame.x, joint_axis=N.y)
    c = _body("c")
    weld = WeldJoint(
        "weld", b, c, parent_point=lb / 2 * b.frame.x, child_point=-_length(c) * c.frame.y
    )
    return [pin, weld]


def _system(kind: str) -> System:
    ground = RigidBody("ground", frame=ReferenceFrame("N"))
    system = System.from_newtonian(ground)
    system.add_joints(*_joints(kind, ground, _body("b")))
    system.apply_uniform_gravity(-g * ground.frame.z + g / 3 * ground.frame.x)
    system.validate_system()
    return system


KINDS = ["pin", "prismatic", "cylindrical", "planar", "spherical", "weld"]


@pytest.mark.parametrize(
    "kind", [k if k in ("pin", "weld") else pytest.param(k, marks=pytest.mark.slow) for k in KINDS]
)  # (about a second each: the full suite runs all)
def test_joint_against_kane(kind):
    _assert_matches_kane(_system(kind), seed=KINDS.index(kind))


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_actuators_against_kane():
    """Actuators enter through their loads: a spring, a damper and a Duffing spring along the
    line from a ground point to the sliding body, a torque between the slider and its pendulum."""
    system = _system("prismatic")
    k, c, k3, tau = sp.symbols("k c k3 tau")
    anchor = system.fixed_point.locatenew("anchor", system.frame.y + system.frame.z / 2)
    slider, pendulum = system.bodies[1], system.bodies[2]
    line = LinearPathway(anchor, slider.masscenter)
    system.add_actuators(
        LinearSpring(k, line, equilibrium_length=sp.Rational(1, 2)),
        LinearDamper(c, line),
        DuffingSpring(k, k3, LinearPathway(anchor, pendulum.masscenter)),
        TorqueActuator(tau, slider.frame.z, pendulum, slider),
    )
    _assert_matches_kane(system, seed=11)


def _assert_matches_kane(system: System, *, seed: int) -> None:
    """q̈ of from_sympy(system) equal to SymPy's Kane [q̇; u̇] at 4 random states (u = q̇)."""
    q, u = list(system.q), list(system.u)
    assert list(system.kdes) == [a - c.diff(t) for c, a in zip(q, u, strict=True)]
    converted = pfaff.from_sympy(system)
    assert list(converted.coordinates) == q
    pars = sorted(converted.parameters, key=str)
    rng = np.random.default_rng(seed)
    values = dict(zip(pars, rng.uniform(0.5, 1.5, len(pars)), strict=True))
    model = converted.equations().compile(values)
    system.form_eoms()
    full = sp.lambdify([*q, *u, *pars], [system.mass_matrix_full, system.forcing_full])
    n = len(q)
    for _ in range(4):
        qn, un = rng.uniform(-1.2, 1.2, n), rng.uniform(-1.5, 1.5, n)
        M, F = full(*qn, *un, *values.values())
        ref = np.linalg.solve(np.array(M, float), np.array(F, float).ravel())
        np.testing.assert_allclose(ref[:n], un, rtol=1e-14)  # q̇ = u
        qdd, _ = model.accelerations(0.0, qn, un)
        scale = max(1.0, np.abs(ref[n:]).max())
        np.testing.assert_allclose(qdd, ref[n:], rtol=0, atol=1e-12 * scale)


# --------------------------------------------------------------------------- refusals
def test_refuses_auxiliary_speeds():
    system = _system("spherical")
    system.add_auxiliary_speeds(dynamicsymbols("ua"))
    with pytest.raises(pfaff.ModelError, match=r"auxiliary speeds \[ua\(t\)\]"):
        pfaff.from_sympy(system)


def test_refuses_a_load_on_a_point_without_velocity():
    system = _system("spherical")
    system.add_loads(Force(Point("P"), system.frame.x))
    with pytest.raises(pfaff.ModelError, match="load on point `P`: SymPy cannot give its velocity"):
        pfaff.from_sympy(system)


def test_refuses_a_body_without_velocity():
    system = _system("spherical")
    system.add_bodies(RigidBody("loose"))
    with pytest.raises(pfaff.ModelError, match="body `loose`: SymPy cannot give its velocity"):
        pfaff.from_sympy(system)


def test_refuses_nonlinear_kinematic_equations():
    system = _system("pin")
    q, u = system.q[0], system.u[0]
    system.kdes = [u - q.diff(t) ** 2, system.u[1] - system.q[1].diff(t)]
    with pytest.raises(pfaff.ModelError, match="not linear in u, q̇"):
        pfaff.from_sympy(system)


def test_refuses_a_load_with_a_foreign_function_of_time():
    system = _system("spherical")
    F = dynamicsymbols("F")
    body = system.bodies[-1]
    system.add_loads(Force(body.masscenter, F * system.frame.x))
    with pytest.raises(pfaff.ModelError, match=r"depends on `F\(t\)`"):
        pfaff.from_sympy(system)


@pytest.mark.parametrize("value", ["9.81", None, float("nan")])
def test_refuses_a_parameter_value_that_is_not_a_number(value):
    """A user's string never reaches sympify; NaN is not a value."""
    with pytest.raises((pfaff.ModelTypeError, pfaff.ModelError), match="the value of 'g'"):
        pfaff.from_sympy(_system("spherical"), parameters={"g": value})


def test_refuses_lagrange_loads_on_velocities_in_speeds():
    """A LagrangesMethod whose loads act on points whose velocity is in a joint's speed u:
    ∂v/∂q̇ would be 0 and gravity would vanish; refused instead."""
    system = _system("pin")
    u_to_qd = {u: c.diff(t) for c, u in zip(system.q, system.u, strict=True)}
    lagrangian = sum((b.kinetic_energy(system.frame) for b in system.bodies[1:]), sp.S.Zero)
    lm = LagrangesMethod(
        lagrangian.xreplace(u_to_qd),
        list(system.q),
        forcelist=list(system.loads),
        frame=system.frame,
    )
    with pytest.raises(pfaff.ModelError, match=r"its velocity in `N` depends on u_j\(t\)"):
        pfaff.from_sympy(lm)
