"""The seed's rolling ring: exact symbolic results, numeric values, reduction and multipliers."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.cli.backsub import multipliers_by_back_substitution
from pfaff.derive.reduce import tidy
from ringsyms import F, M, on_ring_manifold, r

t = pfaff.t


SIX = pytest.param(6, marks=pytest.mark.slow)  # the same path as 2 and 3, twice their cost


@pytest.mark.parametrize("n", [2, 3, SIX])
def test_ring_without_force_gives_2Mr2_thetadd_zero(n: int) -> None:
    """Summing the θ equations and using the constraints: 2 M r² θ̈ = 0 (the seed's result)."""
    ring = pfaff.models.rolling_ring(n)
    eom = ring.equations()
    rule = on_ring_manifold(eom.coordinates)
    thdd = sp.Symbol("thetadd")
    lhs = [tidy(e.lhs.xreplace(rule)) for e in eom.lagrange_equations]
    rhs = [e.rhs for e in eom.lagrange_equations]
    # x equation: M ẍ = λ1 on the manifold (cross terms sum to zero for N >= 2).
    assert sp.simplify(lhs[0] - M * r * thdd) == 0
    assert rhs[0] == eom.multipliers[0]
    # Sum of θ equations: Σ rhs telescopes to -r λ1; with λ1 = M r θ̈ this is 2 M r² θ̈ = 0.
    total_theta = tidy(sp.Add(*lhs[1:]) + r * lhs[0])
    assert sp.simplify(total_theta - 2 * M * r**2 * thdd) == 0
    assert sp.simplify(sp.Add(*rhs[1:]) + r * rhs[0]) == 0


@pytest.mark.parametrize("n", [2, 3, SIX])
def test_ring_push_symbolic(n: int) -> None:
    """θ̈ = F/(2Mr), ẍ = F/(2M), λ1 = -F/2 with symbolic M, r, F (solved on the manifold)."""
    ring = pfaff.models.rolling_ring(n, force=True)
    sol = ring.equations().solve()
    rule = on_ring_manifold(ring.coordinates)
    x, th1 = ring.coordinates[:2]

    def val(key: sp.Expr) -> sp.Expr:
        return sp.simplify(tidy(sp.together(sol[key].xreplace(rule))))

    assert sp.simplify(val(th1.diff(t, 2)) - F / (2 * M * r)) == 0
    assert sp.simplify(val(x.diff(t, 2)) - F / (2 * M)) == 0
    assert sp.simplify(val(sp.Symbol("lambda1")) + F / 2) == 0


def test_ring_64_numeric() -> None:
    """The issue's check: N = 64, M = 1, r = 0.5, F = 2: θ̈ = 2, λ1 = -1 to 1e-9."""
    model = (
        pfaff.models.rolling_ring(64, force=True).equations().compile({"M": 1, "r": 0.5, "F": 2})
    )
    for theta, rate in [(0.0, 0.0), (0.7, 3.0), (np.pi, -1.5)]:
        q, qd = pfaff.models.ring_state(64, 0.5, theta=theta, theta_dot=rate)
        qdd, lam = model.accelerations(0.0, q, qd)
        assert abs(qdd[1] - 2.0) < 1e-9
        assert np.allclose(qdd[1:], 2.0, atol=1e-9)
        assert abs(qdd[0] - 1.0) < 1e-9
        assert abs(lam[0] + 1.0) < 1e-9


@pytest.mark.parametrize("n", [4, 7])
def test_ring_on_incline(n: int) -> None:
    """Hoop on an incline: a = g sin α / 2 and friction M g sin α / 2 up the slope."""
    vals = {"M": 2.0, "r": 0.3, "g": 9.81, "alpha": 0.4}
    model = pfaff.models.rolling_ring(n, incline=True).equations().compile(vals)
    q, qd = pfaff.models.ring_state(n, 0.3, theta=1.1, theta_dot=2.0)
    qdd, lam = model.accelerations(0.0, q, qd)
    a = 9.81 * np.sin(0.4) / 2
    assert qdd[0] == pytest.approx(a, rel=1e-12)
    assert lam[0] == pytest.approx(-2.0 * 9.81 * np.sin(0.4) / 2, rel=1e-12)


def test_reduced_equation_symbolic() -> None:
    """Reduction of the explicit ring to θ1 gives 2 M r² θ̈ = F r, like the one-coordinate model."""
    ring = pfaff.models.rolling_ring(5, force=True)
    th1 = ring.coordinates[1]
    red = ring.reduce([th1])
    eq = red.lagrange_equations[0]
    assert sp.simplify(eq.lhs - 2 * M * r**2 * th1.diff(t, 2)) == 0
    assert sp.simplify(eq.rhs - F * r) == 0
    mini = pfaff.models.rolling_ring_minimal(force=True).equations()
    assert sp.simplify(mini.mass_matrix[0, 0] - red.mass_matrix[0, 0]) == 0
    assert sp.simplify(mini.forcing[0] - red.forcing[0]) == 0
    # T on the manifold is I θ̇² with I = M r².
    assert sp.simplify(red.kinetic_energy - M * r**2 * th1.diff(t) ** 2) == 0


@pytest.mark.parametrize("n", [3, pytest.param(8, marks=pytest.mark.slow)])
def test_reduced_and_multiplier_forms_agree(n: int) -> None:
    """Same θ̈ from the KKT solve and from the reduced equations, incline and push included."""
    ring = pfaff.models.rolling_ring(n, force=True, incline=True)
    vals = {"M": 1.3, "r": 0.4, "F": -0.8, "g": 9.81, "alpha": 0.2}
    full = ring.equations().compile(vals)
    red = ring.reduce([ring.coordinates[1]]).compile(vals)
    rng = np.random.default_rng(1)
    for _ in range(3):
        theta, rate = rng.uniform(-3, 3, 2)
        q, qd = pfaff.models.ring_state(n, 0.4, theta=theta, theta_dot=rate)
        qdd, _ = full.accelerations(0.0, q, qd)
        qdd_red, lam_red = red.accelerations(0.0, [theta], [rate])
        assert lam_red.shape == (0,)
        assert qdd_red[0] == pytest.approx(qdd[1], rel=1e-12)
        expected = (-0.8 + 1.3 * 9.81 * np.sin(0.2)) / (2 * 1.3 * 0.4)
        assert qdd_red[0] == pytest.approx(expected, rel=1e-12)


def test_back_substitution_matches_kkt() -> None:
    """Peeling Aᵀλ = Mq̈ - (Q - h) from λ_N down reproduces the KKT multipliers."""
    n = 40
    model = pfaff.models.rolling_ring(n, force=True).equations().compile({"M": 1, "r": 0.5, "F": 3})
    q, qd = pfaff.models.ring_state(n, 0.5, theta=0.4, theta_dot=1.7)
    qdd, lam = model.accelerations(0.0, q, qd)
    A = model.constraint_matrix(0.0, q)
    res = model.mass_matrix(0.0, q) @ qdd - model.forcing(0.0, q, qd)
    lam_bs, order = multipliers_by_back_substitution(A, res)
    assert order[0] == n - 1 and order[-1] == 0  # λ_N first, λ_1 last
    np.testing.assert_allclose(lam_bs, lam, atol=1e-12)
    # Closed form of the seed's recursion: λ_k = Σ_{j>=k} m (r² θ̈ + r ẍ cos θ_j), k >= 2.
    m = 1.0 / n
    terms = m * (0.5**2 * qdd[1:] + 0.5 * qdd[0] * np.cos(q[1:])) + 0  # h_θ = 0 for the ring
    np.testing.assert_allclose(lam[1:], np.cumsum(terms[::-1])[::-1][1:], atol=1e-12)


def test_templates_keep_symbolic_work_constant() -> None:
    """The ring's N particles and N-1 spacing constraints are each derived once."""
    for n in (4, 100):
        eom = pfaff.models.rolling_ring(n, force=True).equations()
        assert len(eom.blocks) == 4  # particles, no-slip, spacing, push
        sizes = sorted(b.coords.shape[0] for b in eom.blocks)
        assert sizes == [1, 1, n - 1, n]


def test_explicit_and_symbolic_matrices_consistent() -> None:
    """M from the particles equals Σ m JᵀJ written out by hand for N = 3."""
    eom = pfaff.models.rolling_ring(3).equations()
    _x, *th = eom.coordinates
    m = M / 3
    expected = sp.zeros(4, 4)
    expected[0, 0] = M
    for k in range(3):
        expected[0, k + 1] = expected[k + 1, 0] = m * r * sp.cos(th[k])
        expected[k + 1, k + 1] = m * r**2
    assert sp.simplify(eom.mass_matrix - expected) == sp.zeros(4, 4)
    A = sp.Matrix([[1, -r, 0, 0], [0, -1, 1, 0], [0, 0, -1, 1]])
    assert eom.constraint_matrix == A
    assert eom.constraint_bias == sp.zeros(3, 1)
