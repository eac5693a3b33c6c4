"""Inputs: declared parameters whose values a run supplies (a number, u(t), a feedback law), and
the inverted pendulum on a cart stabilized by LQR from pfaff's own linearization."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import sympy as sp

import pfaff


def _cart_pole():
    """Cart x with a bob (px, py) on a rod of length L: the multiplier form (rod constraint)."""
    x, px, py = pfaff.coordinates("x px py")
    M, m, L, g = sp.symbols("M m L g")
    s = pfaff.System([x, px, py], name="cart-pole (multiplier form)")
    s.add_particle(M, [x, 0], name="cart")
    s.add_particle(m, [px, py], name="bob")
    s.add_potential_energy(m * g * py)
    s.add_holonomic_constraint((px - x) ** 2 + py**2 - L**2, name="rod")
    F = s.add_input("F")
    s.add_force([F, 0], at=[x, 0], name="push")
    return s, (x, px, py), F


VALUES = {"M": 1.0, "m": 0.3, "L": 0.8, "g": 9.81}


def test_lqr_from_pfaffs_linearization_keeps_the_pendulum_up() -> None:
    s, (x, px, py), F = _cart_pole()
    eom = s.equations()
    t = pfaff.t
    op = {x: 0, px: 0, py: VALUES["L"], **{c.diff(t): 0 for c in (x, px, py)}}
    op.update({sp.Symbol(k): v for k, v in VALUES.items()})
    lin = eom.linearize(op, [x, px], inputs=[F])
    A, B = np.asarray(lin.A, dtype=float), np.asarray(lin.B, dtype=float)
    assert not lin.is_stable()  # upright: unstable without control
    Q, R = np.diag([10.0, 10.0, 1.0, 1.0]), np.array([[0.1]])
    P = scipy.linalg.solve_continuous_are(A, B, Q, R)
    K = np.linalg.solve(R, B.T @ P)
    assert np.all(np.linalg.eigvals(A - B @ K).real < 0)
    model = eom.compile(VALUES)
    assert model.inputs == ["F"]

    def law(_t, q, qd):
        return float((-K @ np.array([q[0], q[1], qd[0], qd[1]]))[0])

    L = VALUES["L"]
    tilt = 0.15  # rad from upright
    q0 = np.array([0.0, L * np.sin(tilt), L * np.cos(tilt)])
    tr = pfaff.simulate(model, q0, np.zeros(3), (0, 8.0), inputs={"F": law}, rtol=1e-9)
    assert tr.status == "success", tr.message
    assert tr.q[:, 2].min() > 0.9 * L  # stays upright
    assert abs(tr.q[-1, 0]) < 1e-3 and abs(tr.q[-1, 1]) < 1e-3  # converges to the origin
    assert np.abs(tr.constraint_residual).max() < 1e-9
    # without the controller it falls
    free = pfaff.simulate(model, q0, np.zeros(3), (0, 3.0), inputs={"F": 0.0})
    assert free.q[:, 2].min() < 0


def test_constant_and_time_inputs_against_closed_forms() -> None:
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(2, [x, 0])
    u = s.add_input(sp.Symbol("u"))
    s.add_force([u, 0], at=[x, 0])
    model = s.equations().compile({})
    tr = pfaff.simulate(model, [0.0], [0.0], (0, 2), inputs={"u": 3.0}, rtol=1e-11, atol=1e-12)
    assert tr.q[-1, 0] == pytest.approx(3.0 * 4 / 4, rel=1e-10)  # u t² / (2m)
    tr = pfaff.simulate(model, [0.0], [0.0], (0, 2), inputs={"u": np.cos}, rtol=1e-11, atol=1e-12)
    assert tr.q[-1, 0] == pytest.approx((1 - np.cos(2.0)) / 2, rel=1e-9)  # x = (1 - cos t)/m
    assert tr.nc_work[-1] == pytest.approx(0.5 * 2 * tr.qd[-1, 0] ** 2, rel=1e-8)  # W = ΔT
    assert abs(tr.energy_balance).max() < 1e-9


def test_a_law_that_changes_its_arguments_leaves_the_run_alone() -> None:
    """u(t, q, q̇) = −k q on a unit mass (ẍ = −k x: x = cos(√k t)), the law zeroing its q and
    q̇ in place after reading them: the run gets the same cosine as a well-behaved law."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    u = s.add_input("u")
    s.add_generalized_force(x, u)
    model = s.equations().compile({})

    def vandal(_t, q, qd):
        value = -4.0 * float(q[0])
        q[:] = 0.0
        qd[:] = 0.0
        return value

    ts = np.linspace(0, 2, 5)
    tr = pfaff.simulate(model, [1.0], [0.0], (0, 2), t_eval=ts, inputs={"u": vandal}, rtol=1e-11)
    np.testing.assert_allclose(tr.q[:, 0], np.cos(2.0 * ts), atol=1e-8)


def test_bad_inputs() -> None:
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    u = s.add_input("u")
    s.add_force([u, 0], at=[x, 0])
    model = s.equations().compile({})
    with pytest.raises(pfaff.OptionError, match="not an input"):
        pfaff.simulate(model, [0.0], [0.0], (0, 1), inputs={"v": 1.0})
    with pytest.raises(pfaff.OptionError, match="real number"):
        pfaff.simulate(model, [0.0], [0.0], (0, 1), inputs={"u": "1"})
    with pytest.raises(pfaff.OptionError, match="2 arguments"):
        pfaff.simulate(model, [0.0], [0.0], (0, 1), inputs={"u": lambda a, b: 1.0})
    with pytest.raises(pfaff.ModelError, match="already an input"):
        s.add_input("u")
    with pytest.raises(pfaff.ModelTypeError):
        s.add_input(x)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_chattering_friction_fails_instead_of_hanging() -> None:
    """Coulomb friction −μ m g sign(ẋ) on a spring too weak to overcome it chatters about ẋ = 0
    once the block stops: the run stops with a message naming the cause, in seconds, not hours
    (the steps collapse against the run's own history; a run chattering from its very first step
    has none, and proceeds until interrupted or ``max_steps``)."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    s.add_potential_energy(x**2)  # k = 2: spring force 2 < friction 2.94 at x = 1
    s.add_generalized_force(x, -0.3 * 9.81 * sp.sign(x.diff(pfaff.t)))
    model = s.equations().compile({})
    tr = pfaff.simulate(model, [1.0], [-0.5], (0, 2.0))
    assert tr.status == "failed"
    assert "step-size collapse" in tr.message and "sign()" in tr.message
