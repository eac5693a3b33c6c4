"""Unilateral constraints: impacts, releases and rest, against closed forms and hand-solved
impulse equations, by every method."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import sympy as sp
from tests.methods import ALL_METHODS, IDA_SLOW

import pfaff
from pfaff.errors import ModelError, OptionError, StateError

TOL = {"rtol": 1e-12, "atol": 1e-14}
G = 9.81


# ---------------------------------------------------------------- particle sliding off a sphere
@pytest.fixture(scope="module")
def sphere():
    return pfaff.models.particle_on_sphere().equations().compile({"m": 1.5, "g": G, "R": 2.0})


@pytest.mark.parametrize("method", ALL_METHODS)
def test_particle_leaves_sphere(sphere, method):
    """cos θ* = (2/3)(1 + v0²/(2gR)); on the sphere N = m(g cos θ − v²/R); after: a parabola."""
    R, v0, m = 2.0, 1.0, 1.5
    q0, qd0 = pfaff.models.particle_on_sphere_state(R, speed=v0)
    traj = pfaff.simulate(sphere, q0, qd0, (0.0, 1.6), method=method, **TOL)
    assert traj.status == "success", traj.message
    (ev,) = traj.events
    assert (ev.name, ev.kind) == ("sphere", "release")
    expected = 2 / 3 * (1 + v0**2 / (2 * G * R))
    assert abs(ev.q[2] / R - expected) < 1e-9
    on = traj.t < ev.t
    cos = traj.q[on, 2] / R
    speed2 = v0**2 + 2 * G * R * (1 - cos)
    normal = m * (G * cos - speed2 / R)
    np.testing.assert_allclose(traj.multipliers[on, 0], normal, rtol=0, atol=1e-8)
    after = traj.t > ev.t
    assert after.sum() > 3
    dt = traj.t[after] - ev.t
    flight = ev.q + np.outer(dt, ev.qd) - 0.5 * G * np.outer(dt**2, [0.0, 0.0, 1.0])
    np.testing.assert_allclose(traj.q[after], flight, rtol=0, atol=1e-9)
    assert (traj.multipliers[after, 0] == 0).all()
    gap = np.linalg.norm(traj.q[after], axis=1) - R
    np.testing.assert_allclose(traj.constraint_residual[after, 0, 0], gap, rtol=1e-12, atol=1e-14)
    assert (gap[1:] > 0).all()
    assert np.abs(traj.energy_balance).max() < 1e-8


# ---------------------------------------------------------------- a ball bouncing to rest
@pytest.fixture(scope="module")
def ball():
    return pfaff.models.bouncing_ball(None).equations().compile({"m": 0.3, "g": G, "e": 0.8})


@pytest.mark.parametrize("method", IDA_SLOW)
def test_ball_bounces_to_rest(ball, method):
    """t₁ = √(2h/g), t_{k+1} = t_k + 2eᵏ√(2h/g); rest near t∞ = t₁(1 + e)/(1 − e), λ = m g."""
    h, e, m = 1.0, 0.8, 0.3
    q0, qd0 = pfaff.models.bouncing_ball_state(h)
    traj = pfaff.simulate(ball, q0, qd0, (0.0, 5.0), method=method, **TOL)
    assert traj.status == "success", traj.message
    t1 = np.sqrt(2 * h / G)
    expected = t1 + np.concatenate([[0.0], np.cumsum(2 * e ** np.arange(1, 8) * t1)])
    impacts = [r for r in traj.events if r.kind == "impact"]
    found = np.array([r.t for r in impacts[:8]])
    np.testing.assert_allclose(found, expected, rtol=1e-10)
    rest = [r for r in traj.events if r.kind == "rest"]
    assert len(rest) == 1 and rest[0] is traj.events[-1]
    t_inf = t1 * (1 + e) / (1 - e)
    assert abs(rest[0].t - t_inf) < 1e-3
    later = traj.t > rest[0].t
    np.testing.assert_allclose(traj.multipliers[later, 0], m * G, rtol=1e-10)
    np.testing.assert_allclose(traj.q[later, 1], 0.0, atol=1e-12)
    # the rebound of each impact: Newton's law, and its work = the kinetic energy lost
    for r in impacts[:8]:
        i = np.flatnonzero(traj.t == r.t)
        assert len(i) == 2  # the state before and the state after
        before, after = traj.qd[i[0], 1], traj.qd[i[1], 1]
        assert after == pytest.approx(-e * before, rel=1e-12)
        lost = 0.5 * m * (after**2 - before**2)
        dw = traj.impact_work[i[1]] - traj.impact_work[i[0]]
        assert dw == pytest.approx(lost, rel=1e-12)
    assert traj.impact_work[-1] == pytest.approx(-m * G * h, rel=1e-9)
    assert np.abs(traj.energy_balance).max() < 1e-9


def test_rest_speed_option(ball):
    """A larger rest speed ends the bouncing earlier, at the first impact at most that fast."""
    q0, qd0 = pfaff.models.bouncing_ball_state(1.0)
    traj = pfaff.simulate(ball, q0, qd0, (0.0, 5.0), rest_speed=1.0, **TOL)
    v1 = np.sqrt(2 * G)  # the first impact's speed; the k-th is eᵏ⁻¹ v1
    k = int(np.ceil(np.log(1.0 / v1) / np.log(0.8))) + 1
    kinds = [r.kind for r in traj.events]
    assert kinds == ["impact"] * (k - 1) + ["rest"]
    with pytest.raises(OptionError, match="rest_speed"):
        pfaff.simulate(ball, q0, qd0, (0.0, 1.0), rest_speed=-1.0)


def test_ball_t_eval_and_pickle(ball):
    """Reported times with t_eval; a pickled model gives the same impacts."""
    q0, qd0 = pfaff.models.bouncing_ball_state(1.0)
    te = np.linspace(0, 2, 41)
    traj = pfaff.simulate(ball, q0, qd0, (0.0, 2.0), t_eval=te, **TOL)
    assert set(te) <= set(traj.t)
    again = pickle.loads(pickle.dumps(ball))
    other = pfaff.simulate(again, q0, qd0, (0.0, 2.0), t_eval=te, **TOL)
    np.testing.assert_allclose([r.t for r in other.events], [r.t for r in traj.events], rtol=1e-13)
    softer = ball.with_parameters({"e": 0.5})  # its closed model from the one made above
    assert softer.contacts.restitution == (0.5,)
    soft = pfaff.simulate(softer, q0, qd0, (0.0, 1.0), **TOL)
    i = np.flatnonzero(soft.t == soft.events[0].t)
    assert soft.qd[i[1], 1] == pytest.approx(-0.5 * soft.qd[i[0], 1], rel=1e-12)
    heavier = ball.with_parameters({"m": 2.0})
    rest = pfaff.simulate(heavier, [0.0, 0.0], [0.0, 0.0], (0.0, 0.5), **TOL)
    np.testing.assert_allclose(rest.multipliers[:, 0], 2.0 * G, rtol=1e-12)


# ---------------------------------------------------------------- a double pendulum hitting a wall
def _double_pendulum_wall(e: float, wall: float):
    x1, y1, x2, y2 = pfaff.coordinates("x1 y1 x2 y2")
    m1, m2, L1, L2 = 1.0, 0.7, 1.0, 0.8
    s = pfaff.System([x1, y1, x2, y2])
    s.add_particle(m1, [x1, y1])
    s.add_particle(m2, [x2, y2])
    s.add_potential_energy(G * (m1 * y1 + m2 * y2))
    s.add_holonomic_constraint(x1**2 + y1**2 - L1**2, name="rod1")
    s.add_holonomic_constraint((x2 - x1) ** 2 + (y2 - y1) ** 2 - L2**2, name="rod2")
    s.add_unilateral_constraint(x2 - wall, name="wall", restitution=e)
    return s.equations().compile({}), (m1, m2, L1, L2)


def _minimal(q, qd, L1, L2):
    """Angles from the downward vertical and their rates, from Cartesian positions and rates."""
    th1, th2 = np.arctan2(q[0], -q[1]), np.arctan2(q[2] - q[0], -(q[3] - q[1]))
    w1 = (qd[0] * np.cos(th1) + qd[1] * np.sin(th1)) / L1
    w2 = ((qd[2] - qd[0]) * np.cos(th2) + (qd[3] - qd[1]) * np.sin(th2)) / L2
    return np.array([th1, th2]), np.array([w1, w2])


@pytest.mark.parametrize("method", IDA_SLOW)
def test_double_pendulum_hits_wall(method):
    """Post-impact rates from the impulse equation solved by hand in the two angles:
    M(θ) Δθ̇ = Jᵀ Λ, J θ̇⁺ = −e J θ̇⁻ with J = ∂(x₂ − wall)/∂θ; the energy lost is
    ½(1 − e²)(Jθ̇⁻)²/(J M⁻¹ Jᵀ) and equals −W_impact."""
    e = 0.5
    model, (m1, m2, L1, L2) = _double_pendulum_wall(e, wall=-0.3)
    th = np.array([0.3, 0.2])  # released from rest, swinging towards the wall at x₂ = −0.3
    q0 = np.array([L1 * np.sin(th[0]), -L1 * np.cos(th[0]), 0, 0])
    q0[2:] = q0[:2] + np.array([L2 * np.sin(th[1]), -L2 * np.cos(th[1])])
    traj = pfaff.simulate(model, q0, np.zeros(4), (0.0, 1.5), method=method, **TOL)
    assert traj.status == "success", traj.message
    ev = next(r for r in traj.events if r.kind == "impact")
    i = np.flatnonzero(traj.t == ev.t)
    qd_minus, qd_plus = traj.qd[i[0]], traj.qd[i[1]]
    th, w_minus = _minimal(traj.q[i[0]], qd_minus, L1, L2)
    c = np.cos(th[0] - th[1])
    M = np.array([[(m1 + m2) * L1**2, m2 * L1 * L2 * c], [m2 * L1 * L2 * c, m2 * L2**2]])
    J = np.array([L1 * np.cos(th[0]), L2 * np.cos(th[1])])  # ∂(x₂ − wall)/∂θ
    Minv_J = np.linalg.solve(M, J)
    lam = -(1 + e) * (J @ w_minus) / (J @ Minv_J)
    w_plus = w_minus + Minv_J * lam
    assert J @ w_plus == pytest.approx(-e * (J @ w_minus), rel=1e-12)
    np.testing.assert_allclose(_minimal(traj.q[i[1]], qd_plus, L1, L2)[1], w_plus, rtol=1e-12)
    np.testing.assert_allclose(ev.qd, qd_plus, rtol=0, atol=0)
    lost = 0.5 * (1 - e**2) * (J @ w_minus) ** 2 / (J @ Minv_J)
    dT = traj.kinetic[i[1]] - traj.kinetic[i[0]]
    dW = traj.impact_work[i[1]] - traj.impact_work[i[0]]
    assert dT == pytest.approx(-lost, rel=1e-10)
    assert dW == pytest.approx(dT, rel=1e-10)
    assert np.abs(traj.energy_balance).max() < 1e-9
    assert np.abs(traj.constraint_residual[:, :, :2]).max() < 1e-11  # the rods kept


def test_pendulum_hits_stop():
    """A pendulum released at θ₀ hits a stop at θ = −θ_s with θ̇⁻ = −√(2g/L (cos θ_s − cos θ₀))
    (energy) and rebounds at −e θ̇⁻: a joint's limits as two unilateral constraints on one
    coordinate (which could not both be closed)."""
    s = pfaff.models.pendulum()
    theta = s.coordinates[0]
    s.add_unilateral_constraint(theta + 0.2, name="lower", restitution=0.5)
    s.add_unilateral_constraint(0.6 - theta, name="upper", restitution=0.5)
    model = s.equations().compile({"m": 1.0, "g": G, "L": 1.0})
    traj = pfaff.simulate(model, [0.5], [0.0], (0.0, 1.0), **TOL)
    ev = traj.events[0]
    assert (ev.name, ev.kind) == ("lower", "impact")
    i = np.flatnonzero(traj.t == ev.t)
    incoming = -np.sqrt(2 * G * (np.cos(0.2) - np.cos(0.5)))
    assert traj.qd[i[0], 0] == pytest.approx(incoming, rel=1e-10)
    assert traj.qd[i[1], 0] == pytest.approx(-0.5 * traj.qd[i[0], 0], rel=1e-12)
    assert ev.q[0] == pytest.approx(-0.2, abs=1e-12)


# ---------------------------------------------------------------- a ball landing on two contacts
@pytest.mark.parametrize("method", ALL_METHODS)
def test_ball_on_two_contacts(method):
    """A point dropped into a symmetric V (walls at ±β from the horizontal) hits both at once:
    equal impulses, ġᵢ⁺ = −e ġᵢ⁻ on each; at rest, λ₁ = λ₂ = m g/(2 cos β)."""
    beta, e, m, h = 0.4, 0.6, 2.0, 0.5
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(m, [x, y])
    s.add_potential_energy(m * G * y)
    n1, n2 = np.array([-np.sin(beta), np.cos(beta)]), np.array([np.sin(beta), np.cos(beta)])
    s.add_unilateral_constraint(n1[0] * x + n1[1] * y, name="left", restitution=e)
    s.add_unilateral_constraint(n2[0] * x + n2[1] * y, name="right", restitution=e)
    model = s.equations().compile({})
    traj = pfaff.simulate(model, [0.0, h], [0.0, 0.0], (0.0, 3.0), method=method, **TOL)
    assert traj.status == "success", traj.message
    first = traj.events[:2]
    assert [(r.name, r.kind) for r in first] == [("left", "impact"), ("right", "impact")]
    assert first[0].t == first[1].t == pytest.approx(np.sqrt(2 * h / G), rel=1e-12)
    i = np.flatnonzero(traj.t == first[0].t)
    before, after = traj.qd[i[0]], traj.qd[i[1]]
    impulses = np.linalg.solve(np.column_stack([n1, n2]), m * (after - before))
    assert impulses[0] == pytest.approx(impulses[1], rel=1e-12)
    assert impulses[0] > 0
    for n in (n1, n2):
        assert n @ after == pytest.approx(-e * (n @ before), rel=1e-12)
    rest = traj.events[-1]
    assert rest.kind == "rest"
    later = traj.t > rest.t
    np.testing.assert_allclose(traj.multipliers[later], m * G / (2 * np.cos(beta)), rtol=1e-10)


def test_impulse_lifts_resting_contact():
    """A particle sliding on a floor at v hits a wall leaning at φ (normal n = (−cos φ, sin φ)):
    the wall's impulse Λ = (1 + e) m v cos φ along n lifts the particle off the floor, which
    releases (the LCP leaves the floor's impulse at 0)."""
    phi, e, m, v = 0.5, 0.4, 1.3, 2.0
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(m, [x, y])
    s.add_potential_energy(m * G * y)
    s.add_unilateral_constraint(y, name="floor")
    n = np.array([-np.cos(phi), np.sin(phi)])
    s.add_unilateral_constraint(n[0] * (x - 1) + n[1] * y, name="wall", restitution=e)
    model = s.equations().compile({})
    traj = pfaff.simulate(model, [0.0, 0.0], [v, 0.0], (0.0, 0.6), **TOL)
    assert traj.status == "success", traj.message
    hit = traj.events[0]
    assert hit.t == pytest.approx(1 / v, rel=1e-12)
    assert [(r.name, r.kind) for r in traj.events if r.t == hit.t] == [
        ("wall", "impact"),
        ("floor", "release"),
    ]
    expected = np.array([v, 0.0]) + n * (1 + e) * v * np.cos(phi)
    np.testing.assert_allclose(hit.qd, expected, rtol=1e-12, atol=1e-14)
    before = traj.t < hit.t
    np.testing.assert_allclose(traj.multipliers[before, 0], m * G, rtol=1e-12)
    assert (traj.multipliers[before, 1] == 0).all()


# ---------------------------------------------------------------- bad input
def test_bad_contacts():
    y = pfaff.coordinates("y")
    s = pfaff.System([y])
    s.add_particle(1, [0, y])
    with pytest.raises(ModelError, match="velocity"):
        s.add_unilateral_constraint(y.diff(pfaff.t))
    with pytest.raises(ModelError, match=r"\[0, 1\]"):
        s.add_unilateral_constraint(y, restitution=1.5)
    with pytest.raises(ModelError, match="not a relation"):
        s.add_unilateral_constraint(y >= 0)
    with pytest.raises(ModelError, match="does not depend"):
        s.add_unilateral_constraint(sp.Symbol("a"))
    s.add_unilateral_constraint(y, name="floor", restitution=sp.Symbol("e"))
    with pytest.raises(ModelError, match="already"):
        s.add_unilateral_constraint(y - 1, name="floor")
    with pytest.raises(pfaff.errors.ParameterError, match="restitution"):
        s.equations().compile({"e": 2.0})
    model = s.equations().compile({"e": 0.5})
    with pytest.raises(StateError, match=r"penetrates.*floor"):
        pfaff.simulate(model, [-0.1], [0.0], (0.0, 1.0))


def test_families_refuse_contacts():
    s = pfaff.System()
    th = s.add_family("theta", 3)
    k = sp.Symbol("k")
    s.add_particle(1, [th[k], 0], over=k)
    with pytest.raises(ModelError, match="families"):
        s.add_unilateral_constraint(s.coordinates[0])


def test_zoo_helpers():
    """The state helpers: on the sphere (|q| = R, q̇ tangent, |q̇| = speed) and above the
    floor; bad values refused by name."""
    q, qd = pfaff.models.particle_on_sphere_state(2.0, speed=3.0, theta=0.7)
    assert np.linalg.norm(q) == pytest.approx(2.0, rel=1e-15)
    assert q @ qd == pytest.approx(0.0, abs=1e-15)
    assert np.linalg.norm(qd) == pytest.approx(3.0, rel=1e-15)
    assert q[2] == pytest.approx(2.0 * np.cos(0.7), rel=1e-15)
    with pytest.raises(ModelError, match="radius"):
        pfaff.models.particle_on_sphere_state(-1.0)
    with pytest.raises(ModelError, match="height"):
        pfaff.models.bouncing_ball_state(-0.5)
    e = pfaff.models.bouncing_ball("k").contacts[0].restitution
    assert e == sp.Symbol("k")


def test_max_steps_counts_over_the_segments(ball):
    """The step limit spans the segments between impacts: 40 steps in all, past the first
    impact at t₁ = √(2h/g)."""
    q0, qd0 = pfaff.models.bouncing_ball_state(1.0)
    traj = pfaff.simulate(ball, q0, qd0, (0.0, 5.0), max_steps=40, **TOL)
    assert traj.status == "failed" and "max_steps = 40" in traj.message
    t1 = np.sqrt(2 / G)
    impacts = [r.t for r in traj.events if r.kind == "impact"]
    assert len(impacts) >= 1 and impacts[0] == pytest.approx(t1, rel=1e-10)
    assert traj.t[-1] < 5.0 and traj.stats["steps"] == 40
