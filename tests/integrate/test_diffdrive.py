"""The differential-drive robot (``pfaff.models.diffdrive``) against SymPy's ``KanesMethod``.

The reference (``diffdrive_reference.py``) is checked first against the closed form derived by
hand (straight-line acceleration 2τ/(r (m_c + 2 m_w + 2 I_w/r²)) under equal torques, the full
q̈ at random states, the linearization about straight driving with its yaw-rate eigenvalue
−m_c d v/I_P). pfaff's model writes each wheel's rolling and no-side-slip rows, one of them
redundant: its rows are checked directly (residuals on no-slip motions, rank 3, the redundancy
subspace), and its accelerations and linearization (the redundant pair accepted, reported) agree
with Kane's.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
import sympy as sp
from diffdrive_reference import (
    NAMES,
    closed_form_accelerations,
    closed_form_linearization,
    kane_accelerations,
    kane_linearization,
    rolling_state,
)

import pfaff

VALUES = {"m_c": 12.0, "I_c": 0.8, "d": 0.15, "m_w": 0.7, "I_w": 0.004, "J_w": 0.0025}
VALUES |= {"r": 0.08, "b": 0.2}
OTHER = {"m_c": 3.0, "I_c": 0.05, "d": -0.04, "m_w": 0.3, "I_w": 0.001, "J_w": 0.0006}
OTHER |= {"r": 0.05, "b": 0.11}
SPEED = 1.5


def random_states(values: dict, count: int, seed: int = 22) -> list:
    """(q, q̇, τ) on the no-slip motions: any q, forward speed, yaw rate and torques."""
    rng = np.random.default_rng(seed)
    states = []
    for _ in range(count):
        q = rng.uniform(-3, 3, 5)
        qd = rolling_state(q, rng.uniform(-2, 2), rng.uniform(-3, 3), values["r"], values["b"])
        states.append((q, qd, tuple(rng.uniform(-1, 1, 2))))
    return states


# --------------------------------------------------------------------------- the reference
@pytest.mark.parametrize("values", [VALUES, OTHER], ids=["robot", "small"])
def test_kane_straight_line(values: dict) -> None:
    """Equal torques from any heading at rest: straight, v̇ = 2τ/(r (m_c + 2 m_w + 2 I_w/r²))."""
    tau, psi = 0.37, 0.9
    r = values["r"]
    a = 2 * tau / (r * (values["m_c"] + 2 * values["m_w"] + 2 * values["I_w"] / r**2))
    q = np.array([0.2, -0.4, psi, 1.0, -2.0])
    qdd = kane_accelerations(values, q, np.zeros(5), (tau, tau))
    expected = [a * np.cos(psi), a * np.sin(psi), 0.0, a / r, a / r]
    np.testing.assert_allclose(qdd, expected, rtol=1e-12, atol=1e-12)


def test_straight_line_value() -> None:
    """The reference value of the robot: τ = 0.37 N m gives v̇ = 0.6162 m/s² (by hand:
    2·0.37/(0.08·(12 + 1.4 + 1.25)) = 0.74/1.172)."""
    q = np.zeros(5)
    qdd = kane_accelerations(VALUES, q, np.zeros(5), (0.37, 0.37))
    assert qdd[0] == pytest.approx(0.74 / 1.172, rel=1e-12)


@pytest.mark.parametrize("values", [VALUES, OTHER], ids=["robot", "small"])
def test_kane_matches_closed_form(values: dict) -> None:
    for q, qd, tau in random_states(values, 5):
        np.testing.assert_allclose(
            kane_accelerations(values, q, qd, tau),
            closed_form_accelerations(values, q, qd, tau),
            rtol=1e-11,
            atol=1e-11,
        )


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_kane_linearization_closed_form() -> None:
    A, B = kane_linearization(VALUES, SPEED)
    A0, B0 = closed_form_linearization(VALUES, SPEED)
    np.testing.assert_allclose(A, A0, atol=1e-12)
    np.testing.assert_allclose(B, B0, atol=1e-12)
    v = VALUES
    i_p = v["I_c"] + v["m_c"] * v["d"] ** 2 + 2 * v["m_w"] * v["b"] ** 2 + 2 * v["J_w"]
    i_p += 2 * v["I_w"] * v["b"] ** 2 / v["r"] ** 2
    eig = np.sort(np.linalg.eigvals(A).real)
    np.testing.assert_allclose(eig, [-v["m_c"] * v["d"] * SPEED / i_p, *[0.0] * 6], atol=1e-12)


# --------------------------------------------------------------------------- pfaff's rows
def constraint_function():
    system = pfaff.models.diffdrive()
    qs = list(system.coordinates)
    qds = [q.diff(pfaff.t) for q in qs]
    exprs = sp.Matrix([p.exprs[0] for p in system.constraints])
    plain = sp.symbols("_q0:5"), sp.symbols("_qd0:5")
    rule = {**dict(zip(qds, plain[1], strict=True)), **dict(zip(qs, plain[0], strict=True))}
    exprs = exprs.xreplace(rule)
    params = [sp.Symbol(n) for n in NAMES]
    A = exprs.jacobian(plain[1])
    return sp.lambdify([*plain, params], [exprs, A], "numpy")


def test_rows_vanish_on_no_slip_motion_and_one_is_redundant() -> None:
    """A q̇ = 0 on every no-slip motion, rank A = 3 < 4, and Aᵀ (0, 0, 1, −1) = 0: equal and
    opposite side forces on the wheels move nothing."""
    f = constraint_function()
    p = [VALUES[n] for n in NAMES]
    for q, qd, _ in random_states(VALUES, 5):
        res, A = (np.asarray(x, dtype=float) for x in f(q, qd, p))
        np.testing.assert_allclose(res, 0.0, atol=1e-13)
        assert np.linalg.matrix_rank(A) == 3
        np.testing.assert_allclose(A.T @ [0.0, 0.0, 1.0, -1.0], 0.0, atol=1e-14)
        np.testing.assert_allclose(A[2], A[3], atol=1e-14)
    q, qd, _ = random_states(VALUES, 1)[0]
    qd[1] += 0.01  # a side slip: both side-slip rows see it
    res = np.asarray(f(q, qd, p)[0], dtype=float).ravel()
    assert abs(res[2]) > 1e-3 and res[2] == pytest.approx(res[3], abs=1e-15)


def test_the_side_slip_pair_is_reported() -> None:
    """Both wheels forbid side-slip: the dependent pair is named, not refused."""
    with pytest.warns(pfaff.RedundancyWarning, match="no side slip L`, `no side slip R"):
        eom = pfaff.models.diffdrive().equations()
    assert eom.redundant_sets == [["no side slip L", "no side slip R"]]


# --------------------------------------------------------------------------- pfaff's motion
@functools.cache
def _eom():
    return pfaff.models.diffdrive(inputs=True).equations()


@functools.cache
def _eom_independent():
    """The same robot with one side-slip row (``redundant=False``): accepted today."""
    return pfaff.models.diffdrive(inputs=True, redundant=False).equations()


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_independent_rows_match_kane() -> None:
    """Today's baseline of the xfail tests below: the three independent rows."""
    model = _eom_independent().compile(VALUES)
    for q, qd, tau in random_states(VALUES, 3, seed=7):
        qdd, lam = model.accelerations(0.0, q, qd, inputs={"tau_L": tau[0], "tau_R": tau[1]})
        np.testing.assert_allclose(
            qdd, kane_accelerations(VALUES, q, qd, tau), rtol=1e-10, atol=1e-10
        )
        np.testing.assert_allclose(lam, multipliers(q, qd, tau), rtol=1e-10, atol=1e-10)
    eom = _eom_independent()
    op, ind, speeds = _pfaff_point(eom)
    lin = eom.linearize(op, ind, speeds, inputs=["tau_L", "tau_R"])
    A, B = kane_linearization(VALUES, SPEED)
    np.testing.assert_allclose(np.asarray(lin.A, dtype=float), A, atol=1e-10)
    np.testing.assert_allclose(np.asarray(lin.B, dtype=float), B, atol=1e-10)


def test_accelerations_match_kane() -> None:
    model = _eom().compile(VALUES)
    for q, qd, tau in random_states(VALUES, 3, seed=7):
        qdd, lam = model.accelerations(0.0, q, qd, inputs={"tau_L": tau[0], "tau_R": tau[1]})
        np.testing.assert_allclose(
            qdd, kane_accelerations(VALUES, q, qd, tau), rtol=1e-10, atol=1e-10
        )
        np.testing.assert_allclose(lam[:2], multipliers(q, qd, tau)[:2], rtol=1e-10, atol=1e-10)
        assert lam[2] + lam[3] == pytest.approx(multipliers(q, qd, tau)[2], rel=1e-10, abs=1e-10)


def multipliers(q: np.ndarray, qd: np.ndarray, tau: tuple) -> np.ndarray:
    """What is unique of λ: the rolling rows' λ_{L,R} = (τ − I_w φ̈)/r (each wheel's spin
    equation I_w φ̈ = τ − r λ), and the side-slip rows' sum, the total side force, by Newton
    across the heading: λ_3 + λ_4 = (m_c + 2 m_w) v ω + m_c d ω̇ (their difference is the
    redundant direction)."""
    v = VALUES
    qdd = closed_form_accelerations(v, q, qd, tau)
    speed, w = qd[0] * np.cos(q[2]) + qd[1] * np.sin(q[2]), qd[2]
    return np.array(
        [
            (tau[0] - v["I_w"] * qdd[3]) / v["r"],
            (tau[1] - v["I_w"] * qdd[4]) / v["r"],
            (v["m_c"] + 2 * v["m_w"]) * speed * w + v["m_c"] * v["d"] * qdd[2],
        ]
    )


def _pfaff_point(eom) -> tuple[dict, list, list]:
    x, y, psi, phi_l, phi_r = eom.coordinates
    r = VALUES["r"]
    rates = {x: SPEED, y: 0.0, psi: 0.0, phi_l: SPEED / r, phi_r: SPEED / r}
    op = {**dict.fromkeys(eom.coordinates, 0.0), **VALUES}
    op |= {q.diff(pfaff.t): v for q, v in rates.items()}
    return op, list(eom.coordinates), [phi_l, phi_r]


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_linearize_matches_kane() -> None:
    """About straight driving at SPEED: eom.linearize with state (x, y, ψ, φ_L, φ_R, φ̇_L, φ̇_R)."""
    eom = _eom()
    op, ind, speeds = _pfaff_point(eom)
    lin = eom.linearize(op, ind, speeds, inputs=["tau_L", "tau_R"])
    A, B = kane_linearization(VALUES, SPEED)
    np.testing.assert_allclose(np.asarray(lin.A, dtype=float), A, atol=1e-10)
    np.testing.assert_allclose(np.asarray(lin.B, dtype=float), B, atol=1e-10)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_compiled_linearize_matches_kane() -> None:
    eom = _eom()
    model = eom.compile(VALUES)
    _, ind, speeds = _pfaff_point(eom)
    r = VALUES["r"]
    q, qd = np.zeros(5), np.array([SPEED, 0.0, 0.0, SPEED / r, SPEED / r])
    lin = model.linearize(0.0, q, qd, ind, speeds, inputs=["tau_L", "tau_R"])
    A, B = kane_linearization(VALUES, SPEED)
    np.testing.assert_allclose(lin.A, A, atol=1e-10)
    np.testing.assert_allclose(lin.B, B, atol=1e-10)
