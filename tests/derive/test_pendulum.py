"""Cartesian pendulum against the hand derivation and the one-angle pendulum."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff

t = pfaff.t
m, g, L = sp.symbols("m g L")


@pytest.fixture(scope="module")
def cart() -> pfaff.EquationsOfMotion:
    return pfaff.models.cartesian_pendulum().equations()


def test_equations_match_hand_derivation(cart: pfaff.EquationsOfMotion) -> None:
    x, y = cart.coordinates
    assert cart.mass_matrix == sp.Matrix([[m, 0], [0, m]])
    assert cart.forcing == sp.Matrix([0, -m * g])
    assert cart.constraint_matrix == sp.Matrix([[2 * x, 2 * y]])
    assert cart.constraint_bias == sp.Matrix([0])
    xd, yd = x.diff(t), y.diff(t)
    expected = 2 * x * x.diff(t, 2) + 2 * y * y.diff(t, 2) + 2 * xd**2 + 2 * yd**2
    assert sp.expand(cart.acceleration_constraints[0] - expected) == 0
    lam = cart.multipliers[0]
    assert cart.lagrange_equations[0] == sp.Eq(m * x.diff(t, 2), 2 * lam * x)
    assert sp.expand(cart.lagrange_equations[1].lhs - (m * y.diff(t, 2) + m * g)) == 0


def test_multiplier_closed_form(cart: pfaff.EquationsOfMotion) -> None:
    """λ = m (g y - ẋ² - ẏ²) / (2 (x² + y²)), i.e. m(gy - v²)/(2L²) on the circle."""
    x, y = cart.coordinates
    sol = cart.solve()
    v2 = x.diff(t) ** 2 + y.diff(t) ** 2
    lam = sol[cart.multipliers[0]]
    assert sp.simplify(lam - m * (g * y - v2) / (2 * (x**2 + y**2))) == 0
    assert sp.simplify(sol[x.diff(t, 2)] - 2 * lam * x / m) == 0


def test_tension_three_mg_at_bottom(cart: pfaff.EquationsOfMotion) -> None:
    """Released at rest from horizontal: v² = 2gL at the bottom, tension -2Lλ = 3mg."""
    vals = {"m": 0.7, "g": 9.81, "L": 1.3}
    model = cart.compile(vals)
    v = np.sqrt(2 * 9.81 * 1.3)
    _, lam = model.accelerations(0.0, [0.0, -1.3], [v, 0.0])
    assert -2 * 1.3 * lam[0] == pytest.approx(3 * 0.7 * 9.81, rel=1e-13)
    _, lam_rest = model.accelerations(0.0, [0.0, -1.3], [0.0, 0.0])
    assert -2 * 1.3 * lam_rest[0] == pytest.approx(0.7 * 9.81, rel=1e-13)


def test_agrees_with_one_angle_pendulum(cart: pfaff.EquationsOfMotion) -> None:
    """θ̈ = -(g/L) sin θ from the angle model; the Cartesian model's q̈ is its image."""
    vals = {"m": 1.1, "g": 9.81, "L": 0.8}
    angle = pfaff.models.pendulum().equations()
    th = angle.coordinates[0]
    assert sp.simplify(angle.solve()[th.diff(t, 2)] + g / L * sp.sin(th)) == 0
    a_model, c_model = angle.compile(vals), cart.compile(vals)
    for theta, w in [(0.3, 0.0), (1.2, -2.0), (2.9, 0.5)]:
        thdd = a_model.accelerations(0.0, [theta], [w])[0][0]
        q = 0.8 * np.array([np.sin(theta), -np.cos(theta)])
        qd = 0.8 * w * np.array([np.cos(theta), np.sin(theta)])
        qdd, lam = c_model.accelerations(0.0, q, qd)
        expect = 0.8 * (
            thdd * np.array([np.cos(theta), np.sin(theta)])
            + w**2 * np.array([-np.sin(theta), np.cos(theta)])
        )
        np.testing.assert_allclose(qdd, expect, rtol=1e-12, atol=1e-12)
        tension = 1.1 * (0.8 * w**2 + 9.81 * np.cos(theta))  # m (v²/l + g cos θ)
        assert -2 * 0.8 * lam[0] == pytest.approx(tension, rel=1e-12)


def test_reduce_with_branch_matches_angle_model() -> None:
    """Reducing to x on the hanging branch y = -√(L² - x²) gives the pendulum's motion."""
    sys_ = pfaff.models.cartesian_pendulum()
    x, y = sys_.coordinates
    red = sys_.reduce([x], solutions={y: -sp.sqrt(L**2 - x**2)})
    model = red.compile({"m": 1.0, "g": 9.81, "L": 1.0})
    theta, w = 0.5, 1.3
    xdd = model.accelerations(0.0, [np.sin(theta)], [w * np.cos(theta)])[0][0]
    thdd = -9.81 * np.sin(theta)
    assert xdd == pytest.approx(thdd * np.cos(theta) - w**2 * np.sin(theta), rel=1e-12)


def test_latex_output(cart: pfaff.EquationsOfMotion) -> None:
    tex = cart.latex()
    assert tex.startswith("\\begin{align*}") and "\\ddot{x}" in tex and "\\lambda_{1}" in tex
    assert cart._repr_latex_().startswith("$$")
