"""Overconstrained systems (issue 22): the seed's ring closed by all N spacing rows, run by every
method and as a family; a four-bar started exactly at a fold keeps its branch-following; the
reports (CLI, JSON); what the symbolic tools refuse, by name."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from test_simulate_fourbar import GRAVITY_TORQUE, INERTIA, four_bar
from test_simulate_fourbar import P as FOURBAR

import pfaff
import systems
from methods import ALL_METHODS

M, R, F = 1.0, 0.5, 2.0
VALUES = {"M": M, "r": R, "F": F}


def closed_ring(n: int, family: bool) -> pfaff.NumericModel:
    with pytest.warns(pfaff.RedundancyWarning, match="depend on one another"):
        eom = pfaff.models.rolling_ring(n, force=True, closed=True, family=family).equations()
    assert eom.redundant_sets == [[f"spacing {k}" for k in range(1, n + 1)]]
    return eom.compile(VALUES)


def check_ring_run(traj: pfaff.Trajectory, n: int) -> None:
    """θ̈ = F/(2Mr), ẍ = F/(2M), λ_1 = −F/2; the spacing multipliers orthogonal to the hoop
    stress (all ones over the spacing rows): the minimum-norm ones; one redundant row."""
    assert traj.status == "success", traj.message
    np.testing.assert_allclose(traj.qdd[:, 1:], F / (2 * M * R), rtol=1e-9)
    np.testing.assert_allclose(traj.qdd[:, 0], F / (2 * M), rtol=1e-9)
    np.testing.assert_allclose(traj.multipliers[:, 0], -F / 2, rtol=1e-9)
    hoop = traj.multipliers[:, 1:].sum(axis=1)
    np.testing.assert_allclose(hoop, 0.0, atol=1e-9 * max(1.0, np.abs(traj.multipliers).max()))
    assert (traj.redundant_rows == 1).all()
    assert np.abs(traj.constraint_residual).max() < 1e-8  # (Baumgarte's drift is reported)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_closed_ring_every_method(method: str) -> None:
    n = 6
    model = closed_ring(n, family=False)
    q, qd = pfaff.models.ring_state(n, R, theta=0.3, theta_dot=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        traj = pfaff.simulate(model, q, qd, (0.0, 1.0), method=method, t_eval=[0.0, 0.5, 1.0])
    check_ring_run(traj, n)
    np.testing.assert_allclose(traj.q[-1, 0], q[0] + qd[0] + F / (4 * M), rtol=1e-9)


@pytest.mark.parametrize("n", [6, 1024, pytest.param(2**16, marks=pytest.mark.slow)])
def test_closed_ring_family(n: int) -> None:
    """The family solver drops the closing row (known from the structure) and reports it."""
    model = closed_ring(n, family=True)
    assert model.solver == "triangular"
    q, qd = pfaff.models.ring_state(n, R, theta=0.3, theta_dot=1.0)
    names, basis = model.redundancy(0.0, q, qd)
    ones = np.r_[0.0, np.ones(n)] / math.sqrt(n)  # the hoop stress, as a subspace
    assert basis.shape == (n + 1, 1) and abs(abs(basis[:, 0] @ ones) - 1.0) < 1e-9
    assert names[-1] == f"spacing {n}"
    traj = pfaff.simulate(model, q, qd, (0.0, 0.05), t_eval=[0.0, 0.05], max_step=0.01)
    check_ring_run(traj, n)


def test_the_explicit_and_family_rings_agree() -> None:
    n = 6
    q, qd = pfaff.models.ring_state(n, R, theta=0.3, theta_dot=1.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        a = closed_ring(n, family=False).accelerations(0.0, q, qd)
        b = closed_ring(n, family=True).accelerations(0.0, q, qd)
    np.testing.assert_allclose(a[0], b[0], rtol=1e-13)
    np.testing.assert_allclose(a[1], b[1], rtol=1e-12, atol=1e-13)


def test_a_start_exactly_at_a_fold_is_not_redundancy() -> None:
    """θ = π: the parallelogram is flat and A loses rank there only. The rank loss does not
    persist at nearby states, so the run keeps the floored branch-following (no row dropped)
    and follows the one-angle branch equation through the fold."""
    model = four_bar().equations().compile(FOURBAR)
    th, w = math.pi, 6.0
    run = model.for_run()
    run.check_determined(0.0, [th, 0.0, th], [w, 0.0, w])
    assert run._run_state["rows"] is None  # an isolated rank loss, not a redundancy
    te = np.linspace(0.0, 0.05, 6)
    traj = pfaff.simulate(model, [th, 0.0, th], [w, 0.0, w], (0.0, 0.05), t_eval=te, rtol=1e-10)
    assert traj.status == "success", traj.message
    acc = -GRAVITY_TORQUE * np.cos(traj.q[:, 0]) / INERTIA
    np.testing.assert_allclose(traj.qdd[:, 0], acc, atol=1e-6)
    np.testing.assert_allclose(traj.q[:, 1], 0.0, atol=1e-8)  # on the parallelogram branch


def test_symbolic_tools_name_the_dependent_set() -> None:
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x - y, name="a")
    s.add_holonomic_constraint(2 * x - 2 * y, name="b")
    with pytest.warns(pfaff.RedundancyWarning):
        eom = s.equations()
    with pytest.raises(pfaff.ConstraintError, match="`a`, `b` depend on one another"):
        eom.solve()
    with (
        pytest.warns(pfaff.RedundancyWarning),
        pytest.raises(pfaff.ConstraintError, match="`a`, `b` depend on one another"),
    ):
        s.reduce([x])
    model = eom.compile({})
    q, qd = pfaff.consistent_state(model, [0.3, 0.0], [0.1, 0.0], independent=["x"])
    np.testing.assert_allclose(q, [0.3, 0.3], rtol=1e-12)
    np.testing.assert_allclose(qd, [0.1, 0.1], rtol=1e-12)


MODEL_FILE = """
[model]
name = "a particle on a line, written twice"
coordinates = ["x", "y"]
parameters = { m = 1.0, g = 9.81 }
kinetic = "m*(dot(x)**2 + dot(y)**2)/2"
potential = "m*g*y"

[[constraints]]
name = "a"
holonomic = "x - y"

[[constraints]]
name = "b"
holonomic = "2*x - 2*y"

[initial]
q = { x = 0.0, y = 0.0 }

[simulate]
t_end = 1.0
"""


def test_the_cli_reports_the_redundancy(tmp_path, capsys) -> None:
    from pfaff.cli import main

    path = tmp_path / "twice.toml"
    path.write_text(MODEL_FILE)
    with warnings.catch_warnings():
        warnings.simplefilter("error", pfaff.RedundancyWarning)  # reported, not warned
        assert main(["equations", str(path), "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["redundant_sets"] == [["a", "b"]]
        assert main(["run", str(path), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["redundant_rows"] == 1 and rep["redundant_sets"] == [["a", "b"]]
    g = 9.81  # along the line the mass is 2, the pull m g: x(1) = -g/4
    assert rep["q_final"] == pytest.approx([-g / 4, -g / 4], rel=1e-9)
    assert main(["run", str(path)]) == 0
    text = capsys.readouterr().out
    assert "Redundant constraints" in text and "a, b" in text


def test_a_run_with_inputs_reports_the_minimum_norm_multipliers() -> None:
    """Inputs report states in one batched pass, except where the run's rows are redundant:
    there λ is the minimum-norm one, as without inputs. Along x = y under the push u the rows
    a = x − y, b = 2x − 2y carry λ_a + 2λ_b = −u/2, so λ = (−u/10, −u/5)."""
    s = systems.driven_particle("a", "b")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        model = s.equations().compile({})
        traj = pfaff.simulate(model, [0, 0], [0, 0], (0, 1), inputs={"u": 4.0}, t_eval=[0.5, 1.0])
    np.testing.assert_allclose(traj.multipliers, [[-0.4, -0.8]] * 2, rtol=1e-12)
    assert (traj.redundant_rows == 1).all()
