"""Rigid-body motion: the three attitude sets against an independent integration of Euler's
equations, closed forms (the flip period, steady precession, the sleeping top, the incline),
MRP switching and the Euler-angle singularity."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.special import ellipk

import pfaff
from pfaff.attitude import dcm_from

INERTIA = np.array([1.0, 2.0, 3.0])
TOL = {"rtol": 1e-12, "atol": 1e-13}


def _omega_fn(att):
    """ω_body(q, q̇) of an attitude set, numeric."""
    qs, ds = att.coordinates, att.rates_symbols
    x = sp.symbols(f"_x0:{2 * len(qs)}")
    w = att.angular_velocity.xreplace(
        dict(zip([*ds, *qs], x[len(qs) :] + x[: len(qs)], strict=True))
    )
    f = sp.lambdify([x], w, "numpy")
    return lambda q, qd: np.ravel(f(np.concatenate([q, qd])))


def _reference(w0, ts):
    """Euler's equations with quaternion kinematics (scalar first), by solve_ivp: C(t)."""

    def rhs(_t, y):
        w, b = y[:3], y[3:]
        dw = np.array([(INERTIA[1] - INERTIA[2]) * w[1] * w[2] / INERTIA[0],
                       (INERTIA[2] - INERTIA[0]) * w[2] * w[0] / INERTIA[1],
                       (INERTIA[0] - INERTIA[1]) * w[0] * w[1] / INERTIA[2]])  # fmt: skip
        b0, v = b[0], b[1:]
        db = 0.5 * np.concatenate([[-v @ w], b0 * w + np.cross(v, w)])
        return np.concatenate([dw, db])

    sol = solve_ivp(rhs, (0, ts[-1]), [*w0, 1, 0, 0, 0], method="DOP853", t_eval=ts, **TOL)
    out = []
    for b in sol.y[3:].T:
        b = b / np.linalg.norm(b)
        b0, v = b[0], b[1:]
        cross = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
        out.append((b0**2 - v @ v) * np.eye(3) + 2 * np.outer(v, v) + 2 * b0 * cross)
    return np.array(out)


@functools.cache
def _compiled(kind, sequence):
    """The torque-free body derived and compiled once per attitude set (a compiled model is
    immutable; each simulate runs on its own copy)."""
    s = pfaff.models.torque_free_body(kind, sequence=sequence)
    att = s.bodies[0].attitude
    return att, s.equations().compile(dict(zip(["I1", "I2", "I3"], INERTIA, strict=True)))


def _run(kind, w0, t_end, n_out, sequence="321"):
    att, model = _compiled(kind, sequence)
    q0 = att.from_dcm(np.eye(3))
    tr = pfaff.simulate(
        model, q0, att.rates(q0, w0), (0, t_end), t_eval=np.linspace(0, t_end, n_out), **TOL
    )
    assert tr.status == "success", tr.message
    return tr, att, model


@pytest.mark.slow  # (4 s at 10 s: the full suite runs both)
@pytest.mark.parametrize("t_end", [10.0, 100.0])
def test_three_attitude_sets_agree_with_eulers_equations(t_end) -> None:
    """A motion that keeps 3-2-1 angles clear of their singularity: H along inertial z (the
    body starts with ω mostly about its z axis), so the pitch stays small."""
    w0 = np.array([0.2, 0.15, 1.5])
    ts = np.linspace(0, t_end, 101)
    ref = _reference(w0, ts)
    H0 = INERTIA * w0
    for kind in ("euler", "quaternion", "mrp"):
        tr, att, _model = _run(kind, w0, t_end, 101)
        C = np.array([dcm_from(att, q) for q in tr.q])
        assert np.abs(C - ref).max() < 1e-8, kind
        omega = _omega_fn(att)
        w = np.array([omega(q, qd) for q, qd in zip(tr.q, tr.qd, strict=True)])
        H = np.einsum("kij,kj->ki", C, INERTIA * w)  # inertial angular momentum
        assert np.abs(H - C[0] @ H0).max() < 1e-9, kind
        assert np.abs(tr.energy - tr.energy[0]).max() < 1e-10, kind
        if kind == "quaternion":
            assert np.abs(np.sum(tr.q**2, axis=1) - 1).max() < 1e-12


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_mrp_switches_keep_the_dcm_continuous() -> None:
    w0 = np.array([0.2, 0.15, 1.5])  # turns about z: |σ| passes 1 every half turn
    tr, att, _ = _run("mrp", w0, 12.0, 2001)
    assert len(tr.switches) >= 2 and all(name == "body" for _, name in tr.switches)
    assert np.all(np.linalg.norm(tr.q, axis=1) <= 1 + 1e-9)
    C = np.array([dcm_from(att, q) for q in tr.q])
    jumps = np.abs(np.diff(C, axis=0)).max(axis=(1, 2))
    assert jumps.max() < 0.02  # 6 ms between outputs at |ω| ≈ 1.5: no jump at any switch
    ref = _reference(w0, tr.t)
    assert np.abs(C - ref).max() < 1e-8


@pytest.mark.parametrize("kinds", [("mrp",), ("quaternion",)])
@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_flip_period_matches_the_elliptic_integral(kinds) -> None:
    """The intermediate-axis flip: ω(t) is periodic with period 4K(k)/p (Landau & Lifshitz §37)."""
    w0 = np.array([0.05, 1.0, 0.05])
    I1, I2, I3 = INERTIA
    T2 = INERTIA @ w0**2  # 2T
    H2 = (INERTIA * w0) @ (INERTIA * w0)
    if H2 > T2 * I2:  # about the axis of I3
        p = np.sqrt((I3 - I2) * (H2 - T2 * I1) / (I1 * I2 * I3))
        k2 = (I2 - I1) * (T2 * I3 - H2) / ((I3 - I2) * (H2 - T2 * I1))
    else:  # about the axis of I1
        p = np.sqrt((I2 - I1) * (T2 * I3 - H2) / (I1 * I2 * I3))
        k2 = (I3 - I2) * (H2 - T2 * I1) / ((I2 - I1) * (T2 * I3 - H2))
    period = 4 * ellipk(k2) / p
    for kind in kinds:
        tr, att, _ = _run(kind, w0, 1.5 * period, 3001)
        omega = _omega_fn(att)
        w2 = np.array([omega(q, qd)[1] for q, qd in zip(tr.q, tr.qd, strict=True)])
        s = np.sign(w2)
        idx = np.nonzero(s[1:] != s[:-1])[0]
        crossings = [tr.t[i] - w2[i] * (tr.t[i + 1] - tr.t[i]) / (w2[i + 1] - w2[i]) for i in idx]
        assert len(crossings) >= 3, kind  # two flips and the start of a third
        assert crossings[2] - crossings[0] == pytest.approx(period, rel=2e-5), kind


def test_euler_angles_stop_at_gimbal_lock() -> None:
    s = pfaff.models.torque_free_body("euler")
    att = s.bodies[0].attitude
    model = s.equations().compile({"I1": 1, "I2": 2, "I3": 3})
    q0 = att.from_dcm(np.eye(3))
    tr = pfaff.simulate(model, q0, att.rates(q0, [0, 1.0, 0]), (0, 3.0))  # pitch to 90°
    assert tr.status == "failed"
    assert "singularity" in tr.message and "Quaternion" in tr.message
    assert tr.t[-1] < np.pi / 2
    assert np.isfinite(tr.q).all()


def _top_model(kind, values):
    s = pfaff.models.heavy_top(kind)
    return s, s.equations().compile(values)


def test_heavy_top_steady_precession() -> None:
    m, g, L, I1, I3 = 1.0, 9.81, 0.4, 0.3, 0.25
    theta, w3 = 0.6, 40.0
    # m g l = Ω (I3 ω3 − I1 Ω cos θ): the slow root
    a, b, c = I1 * np.cos(theta), -I3 * w3, m * g * L
    Om = (-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)
    _s, model = _top_model("euler", {"m": m, "g": g, "l": L, "I1": I1, "I3": I3})
    q0 = np.array([0.0, theta, 0.0])
    qd0 = np.array([Om, 0.0, w3 - Om * np.cos(theta)])  # ω3 = φ̇ + ψ̇ cos θ
    qdd, _ = model.accelerations(0.0, q0, qd0)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-10)
    tr = pfaff.simulate(model, q0, qd0, (0, 2.0), **TOL)
    assert np.abs(tr.q[:, 1] - theta).max() < 1e-9
    assert np.abs(tr.qd[:, 0] - Om).max() < 1e-9


@pytest.mark.parametrize("factor", [1.25, 0.75])
def test_sleeping_top_threshold(factor) -> None:
    """Upright spin is stable when ω3² > 4 m g l I1 / I3² (quaternions: θ = 0 is no singularity)."""
    m, g, L, I1, I3 = 1.0, 9.81, 0.4, 0.3, 0.25
    w3 = factor * np.sqrt(4 * m * g * L * I1 / I3**2)
    s, model = _top_model("quaternion", {"m": m, "g": g, "l": L, "I1": I1, "I3": I3})
    att = s.bodies[0].attitude
    tilt0 = 1e-3
    q0 = att.from_dcm(
        dcm_from(pfaff.attitude.EulerAngles(pfaff.coordinates("a b c"), "313"), [0, tilt0, 0])
    )
    tr = pfaff.simulate(model, q0, att.rates(q0, [0, 0, w3]), (0, 6.0), rtol=1e-10, atol=1e-12)
    assert tr.status == "success", tr.message
    axis_z = np.array([dcm_from(att, q)[2, 2] for q in tr.q])  # cos of the tilt
    tilt = np.arccos(np.clip(axis_z, -1, 1))
    if factor > 1:
        assert tilt.max() < 5 * tilt0
    else:
        assert tilt.max() > 100 * tilt0
    assert np.abs(tr.energy - tr.energy[0]).max() < 1e-8


@pytest.mark.parametrize(("shape", "k"), [("hoop", 1.0), ("disk", 0.5), ("sphere", 0.4)])
def test_rolling_on_incline(shape, k) -> None:
    m, r, g, alpha = 2.0, 0.3, 9.81, 0.35
    model = (
        pfaff.models.rolling_on_incline(shape)
        .equations()
        .compile({"m": m, "r": r, "g": g, "alpha": alpha})
    )
    qdd, lam = model.accelerations(0.0, np.array([0.0, 0.0]), np.array([0.0, 0.0]))
    assert qdd[0] == pytest.approx(g * np.sin(alpha) / (1 + k), rel=1e-12)
    assert qdd[1] == pytest.approx(-qdd[0] / r, rel=1e-12)  # rolls (counterclockwise negative)
    assert lam[0] == pytest.approx(m * g * np.sin(alpha) * k / (1 + k), rel=1e-12)  # friction


def test_hoop_on_incline_matches_the_seeds_ring() -> None:
    """The N-particle ring of the seed on an incline is a hoop: the same acceleration."""
    m, r, g, alpha = 2.0, 0.3, 9.81, 0.35
    hoop = (
        pfaff.models.rolling_on_incline("hoop")
        .equations()
        .compile({"m": m, "r": r, "g": g, "alpha": alpha})
    )
    a_hoop = hoop.accelerations(0.0, np.zeros(2), np.zeros(2))[0][0]
    ring = pfaff.models.rolling_ring(8, incline=True, gravity=True).equations()
    names = {p.name for p in ring.parameters}
    vals = {"M": m, "r": r, "g": g, "alpha": alpha}
    model = ring.compile({k: v for k, v in vals.items() if k in names})
    q, qd = pfaff.models.ring_state(8, r)
    a_ring = model.accelerations(0.0, q, qd)[0][0]
    assert abs(a_ring) == pytest.approx(a_hoop, rel=1e-12)


@pytest.mark.parametrize("method", ["baumgarte", "ida"])
def test_singular_mass_matrix_every_method(method) -> None:
    """Quaternion coordinates make M singular (β is its null vector): the augmented system is
    regular, and every method integrates it (IDA through the augmented Lagrangian M + ρAᵀA)."""
    w0 = np.array([0.2, 0.15, 1.5])
    s = pfaff.models.torque_free_body("quaternion")
    att = s.bodies[0].attitude
    model = s.equations().compile(dict(zip(["I1", "I2", "I3"], INERTIA, strict=True)))
    q0 = att.from_dcm(np.eye(3))
    ts = np.linspace(0, 4.0, 9)
    tr = pfaff.simulate(
        model, q0, att.rates(q0, w0), (0, 4.0), method=method, t_eval=ts, rtol=1e-9, atol=1e-11
    )
    assert tr.status == "success", tr.message
    C = np.array([dcm_from(att, q) for q in tr.q])
    assert np.abs(C - _reference(w0, ts)).max() < 1e-6
    assert np.abs(tr.energy - tr.energy[0]).max() < 1e-6
    assert not model.mass_singular  # the run's mode is the run's: the model keeps none
    run = model.for_run()
    run.check_determined(0.0, q0, att.rates(q0, w0))
    assert run.mass_singular


def test_a_start_at_gimbal_lock_names_it() -> None:
    """Exactly at pitch 90° the kinematic matrix and so M are singular: the start is refused
    naming the singular attitude (it used to say a coordinate had no inertia)."""
    s = pfaff.models.torque_free_body("euler")
    model = s.equations().compile({"I1": 1, "I2": 2, "I3": 3})
    with pytest.raises(pfaff.StateError, match=r"singular attitude: .*gimbal lock.*Quaternion"):
        pfaff.simulate(model, [0.0, np.pi / 2, 0.0], [0.1, 0.2, 0.3], (0, 1))
    # a degree away it runs, until the motion reaches the lock (the run's own stop)
    tr = pfaff.simulate(model, [0.0, np.radians(89), 0.0], [0.0, 0.0, 0.0], (0, 1))
    assert tr.status == "success" and np.allclose(tr.q, tr.q[0])  # at rest, stays there
