"""Families: the template form equals the explicit model, symbolically and numerically."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.derive.compile_family import compile_structured
from pfaff.numeric.projection import Projector

VALS = {"M": 1.3, "r": 0.4, "F": -0.8, "g": 9.81, "alpha": 0.2}
k = sp.Symbol("k", integer=True)


def _pair(n: int, **kw):
    explicit = pfaff.models.rolling_ring(n, family=False, **kw)
    family = pfaff.models.rolling_ring(n, family=True, **kw)
    return explicit.equations(), family.equations()


@pytest.mark.parametrize("n", [2, 3, 6])
def test_family_ring_equations_identical(n: int) -> None:
    a, b = _pair(n, force=True, incline=True)
    assert a.coordinates == b.coordinates
    assert a.mass_matrix == b.mass_matrix
    assert a.forcing == b.forcing
    assert a.constraint_matrix == b.constraint_matrix
    assert a.constraint_bias == b.constraint_bias
    assert a.acceleration_constraints == b.acceleration_constraints
    assert a.lagrange_equations == b.lagrange_equations
    assert list(a.constraint_names) == list(b.constraint_names)
    assert a.kinetic_energy == b.kinetic_energy


def test_family_ring_derives_templates_once() -> None:
    eom = pfaff.models.rolling_ring(100_000, force=True).equations()
    assert eom.family and eom.n == 100_001 and eom.m == 100_000
    assert sorted(b.n_inst for b in eom.blocks) == [1, 1, 99_999, 100_000]
    with pytest.raises(pfaff.PfaffError, match="too large"):
        _ = eom.mass_matrix


@pytest.mark.parametrize("solver", ["triangular", "sparse"])
@pytest.mark.parametrize("n", [3, 17])
def test_family_numbers_match_explicit(n: int, solver: str) -> None:
    a, b = _pair(n, force=True, incline=True)
    ma, mb = a.compile(VALS), compile_structured(b, VALS, solver=solver)
    assert mb.solver == solver
    rng = np.random.default_rng(n)
    q, qd = pfaff.models.ring_state(n, 0.4, theta=0.3, theta_dot=1.7)
    q, qd = q + rng.normal(0, 0.01, q.shape), qd + rng.normal(0, 0.1, q.shape)  # off-manifold
    for _ in range(2):  # the second solve reuses the sparse ordering
        qa, la = ma.accelerations(0.0, q, qd)
        qb, lb = mb.accelerations(0.0, q, qd)
        np.testing.assert_allclose(qb, qa, atol=1e-12)
        np.testing.assert_allclose(lb, la, atol=1e-12)
    np.testing.assert_allclose(mb.forcing(0, q, qd), ma.forcing(0, q, qd), atol=1e-13)
    np.testing.assert_allclose(mb.mass_matrix(0, q).toarray(), ma.mass_matrix(0, q), atol=1e-14)
    np.testing.assert_allclose(mb.constraint_matrix(0, q).toarray(), ma.constraint_matrix(0, q))
    for x, y in zip(
        mb.constraint_residual(0, q, qd), ma.constraint_residual(0, q, qd), strict=True
    ):
        np.testing.assert_allclose(x, y, atol=1e-14)
    np.testing.assert_allclose(mb.energy(0, q, qd), ma.energy(0, q, qd), rtol=1e-13)
    for alpha, beta in [(0.0, 0.0), (2.0, 3.0)]:
        sa, sb = ma.solve(0.0, q, qd, alpha, beta), mb.solve(0.0, q, qd, alpha, beta)
        np.testing.assert_allclose(sb[0], sa[0], atol=1e-12)
        np.testing.assert_allclose(sb[1], sa[1], atol=1e-12)


@pytest.mark.parametrize("n", [4, 1000])
def test_family_ring_closed_forms(n: int) -> None:
    """θ̈ = F/(2Mr), ẍ = F/(2M), λ_1 = -F/2; on an incline ẍ = g sin α / 2."""
    model = (
        pfaff.models.rolling_ring(n, force=True, family=True)
        .equations()
        .compile({"M": 2.0, "r": 0.5, "F": 3.0})
    )
    q, qd = pfaff.models.ring_state(n, 0.5, theta=2.0, theta_dot=-4.0)
    qdd, lam = model.accelerations(0.0, q, qd)
    np.testing.assert_allclose(qdd[1:], 3.0 / (2 * 2.0 * 0.5), rtol=1e-12)
    assert qdd[0] == pytest.approx(3.0 / 4.0, rel=1e-12)
    assert lam[0] == pytest.approx(-1.5, rel=1e-12)
    # the seed's step backwards: λ_k = Σ_{j>=k} m (r² θ̈ + r ẍ cos θ_j)
    m = 2.0 / n
    terms = m * (0.25 * qdd[1:] + 0.5 * qdd[0] * np.cos(q[1:]))
    np.testing.assert_allclose(lam[1:], np.cumsum(terms[::-1])[::-1][1:], atol=1e-12)
    vals = {"M": 2.0, "r": 0.3, "g": 9.81, "alpha": 0.4}
    inc = pfaff.models.rolling_ring(n, incline=True, family=True).equations().compile(vals)
    qdd, lam = inc.accelerations(0.0, *pfaff.models.ring_state(n, 0.3, theta=1.1, theta_dot=2.0))
    assert qdd[0] == pytest.approx(9.81 * np.sin(0.4) / 2, rel=1e-12)


def test_project_onto_the_ring() -> None:
    n = 50
    model = pfaff.models.rolling_ring(n, family=True).equations().compile({"M": 1, "r": 0.5})
    q, qd = pfaff.models.ring_state(n, 0.5, theta=0.3, theta_dot=1.0)
    rng = np.random.default_rng(3)
    project = Projector(model)
    q1, qd1, changed = project(0.0, q + rng.normal(0, 1e-3, q.shape), qd + 0.01)
    f, g = model.constraint_residual(0.0, q1, qd1)
    assert np.max(np.abs(f)) < 1e-12 and np.max(np.abs(g)) < 1e-12 and changed
    assert project.stats["projection_iterations"] == 1  # the ring's constraints are linear in q


def chain_family(n: int):
    """A planar chain of n unit particles in Cartesian families, pinned at the origin."""
    s = pfaff.System()
    x, y = s.add_family("x", n), s.add_family("y", n)
    s.add_particle(1, [x[k], y[k]], over=k)
    s.add_potential_energy(9.81 * y[k], over=k)
    s.add_holonomic_constraint(x[0] ** 2 + y[0] ** 2 - 1, name="pin")
    s.add_holonomic_constraint(
        (x[k + 1] - x[k]) ** 2 + (y[k + 1] - y[k]) ** 2 - 1, "link", over=(k, 0, n - 2)
    )
    return s.equations().compile({})


def test_chain_family_uses_sparse_solver() -> None:
    """A planar chain of particles in Cartesian families: A_L is not square, SuperLU fallback."""
    n = 6
    model = chain_family(n)
    assert model.solver == "sparse"
    q = np.concatenate([np.arange(1, n + 1.0), np.zeros(n)])  # straight, horizontal, at rest
    qdd, _ = model.accelerations(0.0, q, np.zeros(2 * n))
    assert np.all(np.abs(qdd[:n]) < 1e-9)  # at rest the horizontal chain starts to fall: ẍ = 0
    A = model.constraint_matrix(0.0, q).toarray()
    np.testing.assert_allclose(A @ qdd, 0, atol=1e-9)


def test_family_errors() -> None:
    s = pfaff.System(pfaff.coordinates("x"))
    th = s.add_family("theta", 5, first=1)
    with pytest.raises(pfaff.ModelError, match=r"theta6, out of range"):
        s.add_holonomic_constraint(th[k + 1] - th[k], over=k)
    with pytest.raises(pfaff.ModelError, match="out of range"):
        th[0]
    with pytest.raises(pfaff.ModelError, match="pass `over=k`"):
        s.add_particle(1, [th[k], 0])
    phi = s.add_family("phi", 4)
    with pytest.raises(pfaff.ModelError, match="mismatched family lengths"):
        s.add_particle(1, [th[k], phi[k]], over=k)
    with pytest.raises(pfaff.ModelError, match="affine"):
        th[k**2]
    with pytest.raises(pfaff.ModelError, match="clashes"):
        s.add_family("theta", 3)
    with pytest.raises(pfaff.ModelTypeError, match="integer"):
        s.add_family("psi", 2.5)
    with pytest.raises(pfaff.ModelError, match="outside a family reference"):
        s.add_particle(k, [th[k], 0], over=k)


@pytest.mark.slow
def test_memory_estimate_refuses_before_allocating() -> None:
    ring = pfaff.models.rolling_ring(2**31 - 2, force=True)
    with pytest.raises(pfaff.ModelError, match="GiB"):
        ring.equations()


def test_evaluate_states_matches_explicit_model() -> None:
    """What a trajectory reports (q̈, λ, f, g, T, V, T0, T2) at k states, family vs explicit."""
    n, vals = 6, {"M": 1.3, "r": 0.4, "F": -0.8, "g": 9.81, "alpha": 0.2}
    a, b = _pair(n, force=True, incline=True)
    ma, mb = a.compile(vals), b.compile(vals)
    assert ma.solver == "range-space" and mb.solver == "triangular"
    rng = np.random.default_rng(7)
    ts = np.array([0.0, 0.5, 1.0])
    Q = np.stack([pfaff.models.ring_state(n, 0.4, theta=th)[0] for th in (0.1, 1.0, 2.0)])
    QD = rng.normal(0, 1.0, Q.shape)  # velocities off the manifold: g is not zero
    ea, eb = ma.evaluate_states(ts, Q, QD), mb.evaluate_states(ts, Q, QD)
    for key in ("qdd", "multipliers", "f", "g", "T", "V", "T0", "T2"):
        np.testing.assert_allclose(eb[key], ea[key], rtol=1e-11, atol=1e-12, err_msg=key)
    np.testing.assert_allclose(eb["T2"], eb["T"], rtol=1e-12)  # T is quadratic in q̇ here


def test_project_counts_only_real_corrections() -> None:
    n = 40
    model = pfaff.models.rolling_ring(n, family=True).equations().compile({"M": 1, "r": 0.5})
    q, qd = pfaff.models.ring_state(n, 0.5, theta=0.3, theta_dot=1.0)
    project = Projector(model)
    q1, qd1, changed = project(0.0, q, qd)  # on the manifold: nothing to do
    assert not changed and project.stats["projections"] == 0
    np.testing.assert_array_equal(q1, q)
    np.testing.assert_array_equal(qd1, qd)
    q2, qd2, changed = project(0.0, q, qd + 0.01)  # the velocities alone are off
    _, g = model.constraint_residual(0.0, q2, qd2)
    assert changed and project.stats["projection_iterations"] == 1 and np.max(np.abs(g)) < 1e-12
    np.testing.assert_array_equal(q2, q)


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_simulate_family_ring_closed_form() -> None:
    """x(t) = F t²/(4M) and λ_1 = -F/2 along a projected run with shared-trig kernels."""
    n = 4096
    model = pfaff.models.rolling_ring(n, force=2.0).equations().compile({"M": 1.0, "r": 0.5})
    assert model.dyn[0].kernel.angles
    q0, qd0 = pfaff.models.ring_state(n, 0.5, theta=np.pi)
    traj = pfaff.simulate(model, q0, qd0, (0.0, 0.2), max_step=0.02, t_eval=[0.0, 0.1, 0.2])
    assert traj.status == "success" and traj.stats["steps"] >= 10
    np.testing.assert_allclose(traj.q[:, 0], q0[0] + 2.0 * traj.t**2 / 4, atol=1e-9)
    np.testing.assert_allclose(traj.qdd[:, 1:], 2.0, rtol=1e-9)
    np.testing.assert_allclose(traj.multipliers[:, 0], -1.0, rtol=1e-9)
    assert np.abs(traj.constraint_residual).max() <= 1e-9
    np.testing.assert_allclose(
        traj.energy - traj.energy[0], 2.0 * (traj.q[:, 0] - q0[0]), atol=1e-9
    )


def test_simulate_chain_family_projects_onto_nonlinear_constraints() -> None:
    """The SuperLU path in a projected run: Newton steps on |link| = 1, energy kept."""
    n = 6
    model = chain_family(n)
    q = np.concatenate([np.arange(1, n + 1.0), np.zeros(n)])
    traj = pfaff.simulate(model, q, np.zeros(2 * n), (0, 0.5), t_eval=[0, 0.25, 0.5])
    assert model.solver == "sparse" and traj.status == "success"
    assert traj.stats["projections"] > 0
    assert np.abs(traj.constraint_residual).max() < 1e-10
    np.testing.assert_allclose(traj.energy, traj.energy[0], atol=1e-8)
    assert traj.q[-1, 2 * n - 1] < -1.0  # the free end has fallen
