"""NumericModel.with_parameters: the same compiled model with other values, as a fresh compile."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff

DAMPER = """
[model]
coordinates = ["theta1", "theta2"]
parameters = { m1 = 1.0, m2 = 2.0, l1 = 1.0, l2 = 0.5, g = 9.81, c = 0.1 }
potential = "-(m1 + m2)*g*l1*cos(theta1) - m2*g*l2*cos(theta2)"

[[particles]]
mass = "m1"
position = ["l1*sin(theta1)", "-l1*cos(theta1)"]

[[particles]]
mass = "m2"
position = ["l1*sin(theta1) + l2*sin(theta2)", "-l1*cos(theta1) - l2*cos(theta2)"]

[[generalized_forces]]
coordinate = "theta2"
expr = "-c*(dot(theta2) - dot(theta1))"

[initial]
q = { theta1 = 1.0, theta2 = 0.0 }
"""


@pytest.fixture(scope="module")
def damper(tmp_path_factory):
    p = tmp_path_factory.mktemp("wp") / "damper.toml"
    p.write_text(DAMPER)
    return pfaff.load_model(p)


def test_same_as_a_fresh_compile_at_states():
    eom = pfaff.models.cartesian_pendulum().equations()
    model = eom.compile({"m": 1.0, "g": 9.81, "L": 2.0})
    other = model.with_parameters({"m": 3.0, "L": 1.5})
    fresh = eom.compile({"m": 3.0, "g": 9.81, "L": 1.5})
    assert other.parameters == fresh.parameters and model.parameters["m"] == 1.0
    q, qd = np.array([0.9, -1.2]), np.array([0.8, 0.6])
    for a, b in zip(other.accelerations(0.0, q, qd), fresh.accelerations(0.0, q, qd), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-14)  # machine code or Python
    for a, b in zip(
        other.constraint_residual(0.0, q, qd), fresh.constraint_residual(0.0, q, qd), strict=True
    ):
        np.testing.assert_array_equal(a, b)
    assert other.energy(0.0, q, qd) == pytest.approx(fresh.energy(0.0, q, qd), rel=1e-14)
    np.testing.assert_array_equal(other.mass_matrix(0.0, q), fresh.mass_matrix(0.0, q))
    assert other._fused is model._fused  # the compiled code is shared


def test_applied_forces_and_energy_balance(damper):
    """The damper's power (a template kernel folding c) follows the new value of c."""
    model = damper.compile()
    t_eval = np.linspace(0, 3, 31)
    for c in (0.0, 0.5, 2.0):
        run = pfaff.simulate(model.with_parameters({"c": c}), damper.q0, damper.qd0, (0, 3),
                             t_eval=t_eval)  # fmt: skip
        ref = pfaff.simulate(damper.compile(c=c), damper.q0, damper.qd0, (0, 3), t_eval=t_eval)
        np.testing.assert_allclose(run.q, ref.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(run.nc_work, ref.nc_work, rtol=1e-10, atol=1e-14)
        assert np.abs(run.energy_balance).max() < 1e-7
        assert (run.nc_work[-1] < -1e-3) == (c > 0)  # the damper takes energy out


def test_only_the_templates_using_a_changed_value_are_new(damper):
    model = damper.compile()
    other = model.with_parameters({"c": 1.0})
    shared = [a is b for a, b in zip(model.dyn, other.dyn, strict=True)]
    assert any(shared) and not all(shared)  # the damper's block only
    assert model.with_parameters({"c": 0.1}).dyn == model.dyn  # the same values: nothing new


def test_bad_values():
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    with pytest.raises(pfaff.ParameterError, match="unknown parameter `M`"):
        model.with_parameters({"M": 1.0})
    with pytest.raises(pfaff.ParameterError, match="`L` is nan"):
        model.with_parameters({"L": float("nan")})
    with pytest.raises(pfaff.ParameterError, match="`m` must be a real number"):
        model.with_parameters({"m": "1"})
    with pytest.raises(pfaff.ParameterError, match="`m` must be a real number"):
        model.with_parameters({"m": True})
    with pytest.raises(pfaff.ParameterError, match="`m` must be a real number"):
        model.with_parameters({"m": np.ones(2)})


def test_a_mass_that_is_not_positive_is_refused_by_the_inertia_check():
    """Not re-checked by with_parameters (SymPy, slow): simulate's first-state check refuses it."""
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    with pytest.raises(pfaff.InertiaError, match="not positive definite"):
        pfaff.simulate(model.with_parameters({"m": -1.0}), [0.0, -1.0], [1.0, 0.0], (0, 1))


def test_machine_code_and_geometry_follow():
    model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    model.compile_machine_code()
    other = model.with_parameters({"L": 3.0})
    fresh = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 3.0})
    q, qd = np.array([0.7]), np.array([0.2])
    np.testing.assert_allclose(other.accelerations(0, q, qd)[0], fresh.accelerations(0, q, qd)[0])
    np.testing.assert_allclose(model.accelerations(0, q, qd)[0], -9.81 / 2 * np.sin(q))
    if model.geometry is not None:
        np.testing.assert_allclose(other.geometry.points([0.0]), [[0.0, -3.0]], atol=1e-12)
        np.testing.assert_allclose(model.geometry.points([0.0]), [[0.0, -2.0]], atol=1e-12)


def test_linearize_after_with_parameters() -> None:
    """The compiled linearizer follows the new values: the pendulum's -g/L."""
    model = pfaff.models.pendulum().equations().compile({"m": 1.0, "g": 9.81, "L": 2.0})
    short = model.with_parameters({"L": 0.5})
    A = np.asarray(short.linearize(0.0, [0.0], [0.0], ["theta"]).A, dtype=float)
    np.testing.assert_allclose(A, [[0.0, 1.0], [-9.81 / 0.5, 0.0]], rtol=1e-12)
