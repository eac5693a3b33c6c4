"""Every KKT solver of both model kinds against closed forms: a new solver joins ``SOLVERS`` and
gets the whole suite.

The system is the seed's rolling ring of N particles pushed by a force F at its centre, which
both kinds compile (``family=True`` gives the family model): ẍ = F/(2M), θ̈ = F/(2Mr), the no-slip
friction λ_1 = −F/2 and T = M ẋ² (half translation, half rotation); the spacing multipliers, which
depend on where the particles are, by the dynamic rows M q̈ − (Q − h) = Aᵀλ.
"""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
from pfaff.numeric.projection import Projector
from pfaff.numeric.protocol import DynamicsModel

SOLVERS = (
    ("general", "range-space"),
    ("general", "lu"),
    ("general", "sparse"),
    ("family", "triangular"),
    ("family", "sparse"),
)
IDS = [f"{kind}-{solver}" for kind, solver in SOLVERS]
N, M, R, F = 7, 1.5, 0.4, 2.0
VALUES = {"M": M, "r": R, "F": F}


@pytest.fixture(scope="module", params=SOLVERS, ids=IDS)
def model(request) -> DynamicsModel:
    kind, solver = request.param
    system = pfaff.models.rolling_ring(N, force=True, family=kind == "family")
    compiled = system.equations().compile(VALUES, solver=solver)
    assert compiled.solver == solver
    assert isinstance(compiled, DynamicsModel)
    return compiled


def _state(theta: float = 0.7, theta_dot: float = 1.3) -> tuple[np.ndarray, np.ndarray]:
    return pfaff.models.ring_state(N, R, theta=theta, theta_dot=theta_dot)


def _dense(a) -> np.ndarray:
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a)


def test_accelerations_and_multipliers(model: DynamicsModel) -> None:
    qdd, lam = model.accelerations(0.0, *_state())
    assert qdd[0] == pytest.approx(F / (2 * M), rel=1e-12)
    np.testing.assert_allclose(qdd[1:], F / (2 * M * R), rtol=1e-12)
    assert lam[0] == pytest.approx(-F / 2, rel=1e-12)
    assert model.stats["kkt_solves"] >= 1


def test_energy(model: DynamicsModel) -> None:
    T, V = model.energy(0.0, *_state(theta_dot=1.3))
    assert T == pytest.approx(M * (R * 1.3) ** 2, rel=1e-13) and V == 0.0


def test_baumgarte_rows_off_the_manifold(model: DynamicsModel) -> None:
    """Off the manifold the constraint rows ask A q̈ + Ȧq̇ + ḃ = −2α g − β² f, and the dynamic
    rows M q̈ − (Q − h) = Aᵀλ: both checked with the model's own M, A and residuals."""
    rng = np.random.default_rng(11)
    q, qd = _state()
    q, qd = q + rng.normal(0, 1e-3, q.shape), qd + rng.normal(0, 1e-2, q.shape)
    alpha, beta = 3.0, 5.0
    qdd, lam = model.solve(0.0, q, qd, alpha, beta)
    f, g = model.residual(0.0, q, qd)
    acc = model.acceleration_residual(0.0, q, qd, qdd)  # A q̈ + Ȧq̇ + ḃ
    np.testing.assert_allclose(acc, -2 * alpha * g - beta**2 * f, atol=1e-11)
    Mq = _dense(model.mass_matrix(0.0, q)) @ qdd - model.forcing(0.0, q, qd)
    np.testing.assert_allclose(Mq, _dense(model.constraint_matrix(0.0, q)).T @ lam, atol=1e-11)


def test_ode_function_matches_solve(model: DynamicsModel) -> None:
    q, qd = _state()
    start = (0.0, q, qd)
    for alpha, beta in ((0.0, 0.0), (2.0, 3.0)):
        fun = model.ode_function(alpha, beta, start=start)
        y = fun(0.0, np.concatenate([q, qd]))
        np.testing.assert_array_equal(y[: model.n], qd)
        np.testing.assert_allclose(
            y[model.n :], model.solve(0.0, q, qd, alpha, beta)[0], atol=1e-12
        )


def test_projection_is_mass_orthogonal(model: DynamicsModel) -> None:
    """A velocity kicked along a constraint impulse M⁻¹Aᵀμ comes back exactly; a perturbed
    position returns onto the manifold."""
    q, qd = _state()
    Mm, A = _dense(model.mass_matrix(0.0, q)), _dense(model.constraint_matrix(0.0, q))
    kick = np.linalg.solve(Mm, A.T @ np.linspace(-1.0, 1.0, model.m))
    project = Projector(model)
    q1, qd1, changed = project(0.0, q, qd + kick)
    assert changed
    np.testing.assert_array_equal(q1, q)
    np.testing.assert_allclose(qd1, qd, atol=1e-12)
    rng = np.random.default_rng(5)
    q2, qd2, _ = project(0.0, q + rng.normal(0, 1e-3, q.shape), qd)
    f, g = model.constraint_residual(0.0, q2, qd2)
    assert np.abs(f).max() < 1e-12 and np.abs(g).max() < 1e-12


def test_projection_thresholds_from_the_row_norms(model: DynamicsModel) -> None:
    """The projection's per-row thresholds are tol·clip(|A_i|/max|A_j|, 1e-4, 1) of the
    assembled A's rows, at a first state and again at another (the ring's A is constant: a
    family model keeps them for the run)."""
    q, qd = _state()
    A = _dense(model.constraint_matrix(0.0, q))
    norms = np.linalg.norm(A, axis=1)
    want = 1e-10 * np.clip(norms / norms.max(), 1e-4, 1.0)
    run = model.for_run()
    for theta in (0.7, 2.1):
        q, qd = _state(theta=theta)
        np.testing.assert_allclose(run.linearize_constraints(0.0, q, qd, 1e-10).thr, want)


def test_model_project_is_the_projection(model) -> None:
    """``model.project`` at one state: the same algorithm and result as the integrators' Projector."""
    rng = np.random.default_rng(9)
    q, qd = _state()
    q0, qd0 = q + rng.normal(0, 1e-3, q.shape), qd + rng.normal(0, 1e-2, q.shape)
    q1, qd1, steps = model.project(0.0, q0, qd0)
    q2, qd2, changed = Projector(model)(0.0, q0, qd0)
    assert steps >= 1 and changed
    np.testing.assert_array_equal(q1, q2)
    np.testing.assert_array_equal(qd1, qd2)
    f, g = model.constraint_residual(0.0, q1, qd1)
    assert np.abs(f).max() < 1e-12 and np.abs(g).max() < 1e-12
    assert model.project(0.0, q1, qd1)[2] == 0  # on the manifold: nothing to do
    with pytest.raises(pfaff.OptionError, match="`tol`"):
        model.project(0.0, q1, qd1, tol="1e-9")


def test_simulation_closed_form(model: DynamicsModel) -> None:
    """x(t) = x0 + ẋ0 t + F t²/(4M) and λ_1 = −F/2 along a projected run."""
    q0, qd0 = _state(theta=0.0, theta_dot=0.5)
    ts = np.linspace(0.0, 1.0, 5)
    traj = pfaff.simulate(model, q0, qd0, (0.0, 1.0), t_eval=ts)
    assert traj.success, traj.message
    np.testing.assert_allclose(traj.q[:, 0], R * 0.5 * ts + F * ts**2 / (4 * M), atol=1e-9)
    np.testing.assert_allclose(traj.multipliers[:, 0], -F / 2, rtol=1e-10)
    assert np.abs(traj.constraint_residual).max() < 1e-10


def test_redundant_constraints_every_general_solver() -> None:
    """Two multiples of one constraint: reported, the motion exact, λ minimum-norm.

    The particle slides down the line x = y under gravity: q̈ = (−g/2, −g/2), the constraint
    force Aᵀλ = M q̈ − F = (−g/2, g/2) = (λ_a + 2λ_b)(1, −1); the minimum-norm λ is along (1, 2):
    λ_a = −g/10, λ_b = −g/5. The null space of Aᵀ is (2, −1)/√5."""
    x, y = pfaff.coordinates("x y")
    g = 9.81
    for solver in ("range-space", "lu", "sparse"):
        s = pfaff.System([x, y])
        s.add_particle(1.0, [x, y])
        s.add_potential_energy(g * y)
        s.add_holonomic_constraint(x - y, name="a")
        s.add_holonomic_constraint(2 * x - 2 * y, name="b")
        with pytest.warns(pfaff.RedundancyWarning, match="`a`, `b` depend on one another"):
            eom = s.equations()
        assert eom.redundant_sets == [["a", "b"]]
        model = eom.compile({}, solver=solver)
        with pytest.warns(pfaff.RedundancyWarning):
            qdd, lam = model.accelerations(0.0, [0.3, 0.3], [0.1, 0.1])
        np.testing.assert_allclose(qdd, [-g / 2, -g / 2], rtol=1e-12)
        np.testing.assert_allclose(lam, [-g / 10, -g / 5], rtol=1e-12)
        names, basis = model.redundancy(0.0, [0.3, 0.3], [0.1, 0.1])
        assert names == ["a", "b"] and basis.shape == (2, 1)
        np.testing.assert_allclose(np.abs(basis[:, 0]), [2 / 5**0.5, 1 / 5**0.5], rtol=1e-12)


def test_contradicting_constraints_are_refused_naming_both() -> None:
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1.0, [x, y])
    s.add_holonomic_constraint(x - 1, name="one")
    s.add_holonomic_constraint(x - 2, name="two")
    with pytest.raises(pfaff.ConstraintError, match="`one`, `two` cannot hold together"):
        s.equations()


def test_unknown_solver_is_refused() -> None:
    eom = pfaff.models.rolling_ring(3, force=True).equations()
    with pytest.raises(pfaff.OptionError, match=r"`solver`.*range-space, lu, sparse"):
        eom.compile(VALUES, solver="triangular")
    fam = pfaff.models.rolling_ring(3, force=True, family=True).equations()
    with pytest.raises(pfaff.OptionError, match=r"`solver`.*triangular, sparse"):
        fam.compile(VALUES, solver="lu")
