"""A closed 5-link pendulum built with SymPy joints (learn-multibody-dynamics#239: its IDA run
"aborted after 2 sec"), converted by pfaff.from_sympy and simulated.

Five uniform rods (lengths 1, masses 1.1 … 1.5) in a vertical plane form a chain of
``PinJoint``s from the ground pivot O; the free end of the fifth rod is pinned to the ground at
(d, 0) = (2.5, 0): two holonomic constraints on a ``sympy.physics.mechanics.System``, three
degrees of freedom. 30 s must keep |f| ≤ 1e-10 m and the energy balance (kinetic energy against
the work of SymPy's gravity loads) to 1e-7 J, and the chain must really move. Its accelerations
agree with SymPy's Kane equations (dependent speeds u4, u5) to 1e-12 at 5 states on the loop.
Both are slow: SymPy's lambdify of the Kane matrices alone takes about 10 s.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import (
    PinJoint,
    Point,
    ReferenceFrame,
    RigidBody,
    System,
    dynamicsymbols,
    inertia,
)

import pfaff

VALUES = {"g": 9.81, "d": 2.5} | {f"m{i}": 1.0 + 0.1 * i for i in range(1, 6)}
VALUES |= {f"l{i}": 1.0 for i in range(1, 6)}


def closed_chain(n: int = 5) -> System:
    """n rods pinned end to end from O; the last rod's free end pinned at (d, 0)."""
    g, d = sp.symbols("g d")
    N, origin = ReferenceFrame("N"), Point("O")
    ground = RigidBody("ground", origin, N)
    system = System.from_newtonian(ground)
    q, u = dynamicsymbols(f"q1:{n + 1}"), dynamicsymbols(f"u1:{n + 1}")
    parent, on_parent = ground, origin
    for i in range(n):
        m, length = sp.symbols(f"m{i + 1} l{i + 1}")
        frame, centre = ReferenceFrame(f"L{i + 1}"), Point(f"C{i + 1}")
        rod = RigidBody(
            f"link{i + 1}", centre, frame, m, (inertia(frame, 0, 0, m * length**2 / 12), centre)
        )
        system.add_joints(
            PinJoint(f"J{i + 1}", parent, rod, q[i], u[i], parent_point=on_parent,
                     child_point=-length / 2 * frame.x, joint_axis=N.z)
        )  # fmt: skip
        parent, on_parent = rod, length / 2 * frame.x
    tip = parent.masscenter.locatenew("tip", on_parent)
    gap = tip.pos_from(origin) - d * N.x
    system.add_holonomic_constraints(gap.dot(N.x), gap.dot(N.y))
    system.q_ind, system.q_dep = q[: n - 2], q[n - 2 :]
    system.u_ind, system.u_dep = u[: n - 2], u[n - 2 :]
    system.apply_uniform_gravity(-g * N.y)
    system.validate_system()
    return system


@pytest.mark.slow
def test_closed_five_link_pendulum_runs_30_s():
    system = pfaff.from_sympy(closed_chain())
    assert system.n_constraints == 2
    model = system.equations().compile(VALUES)
    # an arch guess (absolute angles −80°, −50°, 0°, 50°, 80°), the last two relative angles
    # and speeds completed on the loop
    q0 = np.radians([-80.0, 30.0, 50.0, 50.0, 30.0])
    q0, qd0 = pfaff.consistent_state(model, q0, [1.0, -0.5, 0.3, 0.0, 0.0], independent=[0, 1, 2])
    run = pfaff.simulate(model, q0, qd0, (0.0, 30.0), rtol=1e-10, atol=1e-12, throw=True)
    assert run.status == "success" and run.t[-1] == pytest.approx(30.0)
    assert np.abs(run.position_residual).max() <= 1e-10
    assert np.abs(run.energy_balance).max() < 1e-7
    assert np.ptp(run.q, axis=0).min() > 1.0  # every joint swung more than a radian


@pytest.mark.slow
def test_closed_five_link_accelerations_against_kane():
    """q̈ against SymPy's Kane equations (dependent speeds u4, u5) at 5 states on the loop."""
    sympy_system = closed_chain()
    model = pfaff.from_sympy(sympy_system).equations().compile(VALUES)
    sympy_system.form_eoms()
    q, u = list(sympy_system.q), list(sympy_system.u)
    pars = [sp.Symbol(k) for k in VALUES]
    full = sp.lambdify(
        [*q, *u, *pars], [sympy_system.mass_matrix_full, sympy_system.forcing_full], cse=True
    )
    rows = sp.Matrix(sympy_system.velocity_constraints)
    rows = rows.jacobian(u) + rows.jacobian([c.diff(pfaff.t) for c in q])
    loop = sp.lambdify([*q, *pars], [sp.Matrix(sympy_system.holonomic_constraints), rows])
    rng = np.random.default_rng(239)
    for _ in range(5):
        # q1..q3 at random near an arch, links 4 and 5 closing the loop to (d, 0) by hand (two
        # circles of radius 1); SymPy's own constraints check the closure
        qn = np.radians([-50.0, 30.0, 30.0, 0.0, 0.0]) + np.r_[rng.uniform(-0.1, 0.1, 3), 0, 0]
        theta = np.cumsum(qn[:3])
        gap = np.array([VALUES["d"], 0.0]) - np.array([np.cos(theta).sum(), np.sin(theta).sum()])
        towards, spread = np.arctan2(gap[1], gap[0]), np.arccos(np.hypot(*gap) / 2)
        qn[3:] = [towards - spread - theta[-1], 2 * spread]
        f, A = (np.array(a, float) for a in loop(*qn, *VALUES.values()))
        assert np.abs(f).max() < 1e-13
        un = np.r_[rng.uniform(-1, 1, 3), 0.0, 0.0]
        un[3:] = np.linalg.solve(A[:, 3:], -A[:, :3] @ un[:3])
        M, F = full(*qn, *un, *VALUES.values())
        ref = np.linalg.solve(np.array(M, float), np.array(F, float).ravel())[5:]
        qdd, _ = model.accelerations(0.0, qn, un)
        np.testing.assert_allclose(qdd, ref, rtol=0, atol=1e-12 * max(1.0, np.abs(ref).max()))
