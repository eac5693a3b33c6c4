"""Forward sensitivities (pfaff.sensitivities) against converged central differences of tight runs.

The double pendulum with joint dampers in its angles and in Cartesian coordinates (two rods):
∂q(5 s)/∂(m1, l2, c) and ∂q(5 s)/∂q0 against fourth-order central differences (steps 1e-3 and
2e-3 relative, which must agree to 2e-7: the reference is converged) of runs at rtol 1e-12, to 1e-6
relative to the column's size; the Cartesian start recompleted from the same angles for every
perturbed parameter; the two forms' sensitivities of the angles agree.
"""

from __future__ import annotations

import numpy as np
import pytest
from central_differences import close, converged, stencil

import pfaff
from pfaff.models import damped_double_pendulum
from pfaff.models import double_pendulum_cartesian_state as cartesian_state

VALUES = {"m1": 1.0, "m2": 1.5, "l1": 1.0, "l2": 0.8, "g": 9.81, "c": 0.3}
ANGLES, RATES = [0.8, -0.4], [0.0, 0.5]
TIGHT = {"rtol": 1e-12, "atol": 1e-14, "t_eval": [0.0, 5.0]}
PARAMS = ["m1", "l2", "c"]


@pytest.fixture(scope="module")
def angles_model():
    return damped_double_pendulum().equations().compile(VALUES)


@pytest.fixture(scope="module")
def cartesian_model():
    return damped_double_pendulum(cartesian=True).equations().compile(VALUES)


def end_q(model, q0, qd0, **values) -> np.ndarray:
    run = pfaff.simulate(model.with_parameters(values), q0, qd0, (0, 5), **TIGHT)
    assert run.status == "success"
    return run.q[-1]


def cartesian_start(p):
    return cartesian_state(ANGLES, RATES, p)


@pytest.fixture(scope="module")
def angles_run(angles_model):
    return pfaff.sensitivities(
        angles_model, ANGLES, RATES, (0, 5), parameters=PARAMS, initial=True, **TIGHT
    )


@pytest.fixture(scope="module")
def cartesian_run(cartesian_model):
    return pfaff.sensitivities(
        cartesian_model,
        lambda p: cartesian_start(p)[0],
        lambda p: cartesian_start(p)[1],
        (0, 5),
        parameters=PARAMS,
        **TIGHT,
    )


def test_labels_and_shapes(angles_run):
    assert angles_run.sensitivity.shape == (2, 4, 7)
    assert angles_run.sensitivity_labels == [
        *PARAMS, "q0.theta1", "q0.theta2", "qd0.theta1", "qd0.theta2"
    ]  # fmt: skip
    assert angles_run.multiplier_sensitivity.shape == (2, 0, 7)
    assert np.allclose(angles_run.sensitivity[0, :, 3:], np.eye(4))  # ∂(q, q̇)(0)/∂(q0, q̇0)


@pytest.mark.parametrize(
    "j, name",
    [pytest.param(0, "m1", marks=pytest.mark.slow), pytest.param(1, "l2", marks=pytest.mark.slow),
     (2, "c")],
)  # fmt: skip
def test_angles_form_parameters(angles_model, angles_run, j, name):
    ref = converged(lambda v: end_q(angles_model, ANGLES, RATES, **{name: v}), VALUES[name])
    assert close(angles_run.sensitivity[-1, :2, j], ref)


@pytest.mark.slow
@pytest.mark.parametrize("i", [0, 1])
def test_angles_form_initial_angles(angles_model, angles_run, i):
    def q_end(v: float) -> np.ndarray:
        q0 = list(ANGLES)
        q0[i] = v
        return end_q(angles_model, q0, RATES)

    assert close(angles_run.sensitivity[-1, :2, 3 + i], converged(q_end, ANGLES[i]))


@pytest.mark.slow
@pytest.mark.parametrize("j, name", list(enumerate(PARAMS)))
def test_cartesian_form_parameters(cartesian_model, cartesian_run, j, name):
    def q_end(v: float) -> np.ndarray:
        q0, qd0 = cartesian_start({**VALUES, name: v})  # recompleted from the angles
        return end_q(cartesian_model, q0, qd0, **{name: v})

    assert close(cartesian_run.sensitivity[-1, :4, j], converged(q_end, VALUES[name]))


def angle_jacobian(q: np.ndarray) -> np.ndarray:
    """∂(θ1, θ2)/∂(x1, y1, x2, y2), θ the angles from the downward vertical."""
    d = q[2:] - q[:2]
    r1, r2 = q[:2] @ q[:2], d @ d
    J = np.zeros((2, 4))
    J[0, :2] = [-q[1] / r1, q[0] / r1]
    J[1, :2] = [d[1] / r2, -d[0] / r2]
    J[1, 2:] = [-d[1] / r2, d[0] / r2]
    return J


@pytest.mark.slow
def test_forms_agree_on_the_angles(angles_run, cartesian_run):
    q = cartesian_run.q[-1]
    theta = [np.arctan2(q[0], -q[1]), np.arctan2(q[2] - q[0], q[1] - q[3])]
    assert np.allclose(theta, angles_run.q[-1], atol=1e-9)
    from_cartesian = angle_jacobian(q) @ cartesian_run.sensitivity[-1, :4, :]
    assert close(from_cartesian, angles_run.sensitivity[-1, :2, :3])


@pytest.mark.slow
def test_cartesian_initial_values_by_consistent_state(cartesian_model):
    """∂q(5 s)/∂x1(0) with x1, x2 held and y1, y2 recompleted by consistent_state (implicit
    function theorem) against central differences of runs from recompleted states."""
    q0, qd0 = cartesian_start(VALUES)
    run = pfaff.sensitivities(
        cartesian_model, q0, qd0, (0, 5), initial=True, independent=["x1", "x2"], **TIGHT
    )
    assert run.sensitivity_labels[0] == "q0.x1"

    def q_end(v: float) -> np.ndarray:
        q = q0.copy()
        q[0] = v
        qs, qds = pfaff.consistent_state(cartesian_model, q, qd0, ["x1", "x2"])
        return end_q(cartesian_model, qs, qds)

    assert close(run.sensitivity[-1, :4, 0], converged(q_end, q0[0]))
    assert np.abs(run.sensitivity[:, :, 1]).max() == 0.0  # y1(0) is not free


@pytest.mark.slow
def test_multiplier_sensitivity(cartesian_model, cartesian_run):
    """∂λ(5 s)/∂c against central differences of the multipliers of tight runs."""

    def lam_end(v: float) -> np.ndarray:
        q0, qd0 = cartesian_start({**VALUES, "c": v})
        model = cartesian_model.with_parameters({"c": v})
        return pfaff.simulate(model, q0, qd0, (0, 5), **TIGHT).multipliers[-1]

    ref = stencil(lam_end, VALUES["c"], 1e-3)
    assert close(cartesian_run.multiplier_sensitivity[-1, :, 2], ref, 1e-5)


@pytest.mark.slow
def test_constraints_hold_to_first_order(cartesian_run):
    """f_q S_q + f_p = 0 for the rods: ∂(x1² + y1² − l1²)/∂l2 = 2 q·S = 0 at every time."""
    q, S = cartesian_run.q, cartesian_run.sensitivity
    rod1 = 2 * (q[:, 0] * S[:, 0, 1] + q[:, 1] * S[:, 1, 1])
    d = q[:, 2:] - q[:, :2]
    rod2 = 2 * np.einsum("ki,ki->k", d, S[:, 2:4, 1] - S[:, :2, 1]) - 2 * VALUES["l2"]
    assert np.abs(rod1).max() < 1e-10 and np.abs(rod2).max() < 1e-10


def chaplygin_sleigh():
    """The Chaplygin sleigh: a knife edge at (x, y) heading φ, its mass centre a ahead, no side
    slip −sin φ ẋ + cos φ ẏ = 0 (a velocity constraint only)."""
    import sympy as sp

    x, y, phi = pfaff.coordinates("x y phi")
    m, inertia, a = sp.symbols("m I a")
    s = pfaff.System([x, y, phi])
    s.add_particle(m, [x + a * sp.cos(phi), y + a * sp.sin(phi)])
    s.add_kinetic_energy(inertia * phi.diff() ** 2 / 2)
    s.add_velocity_constraint(-sp.sin(phi) * x.diff() + sp.cos(phi) * y.diff(), name="edge")
    return s


def test_nonholonomic_sleigh_by_its_offset():
    values = {"m": 2.0, "I": 0.3, "a": 0.4}
    model = chaplygin_sleigh().equations().compile(values)
    q0, qd0 = [0.0, 0.0, 0.3], [np.cos(0.3), np.sin(0.3), 1.5]  # on the constraint for any a
    opts = {"rtol": 1e-12, "atol": 1e-14, "t_eval": [0.0, 2.0]}
    run = pfaff.sensitivities(model, q0, qd0, (0, 2), parameters=["a", "I"], **opts)
    for j, name in enumerate(["a", "I"]):

        def end(v: float, name: str = name) -> np.ndarray:
            other = model.with_parameters({name: v})
            traj = pfaff.simulate(other, q0, qd0, (0, 2), **opts)
            return np.concatenate((traj.q[-1], traj.qd[-1]))

        assert close(run.sensitivity[-1, :, j], converged(end, values[name]))
    # the velocity constraint to first order: ∂(−sin φ ẋ + cos φ ẏ)/∂p = 0
    q, qd, S = run.q[-1], run.qd[-1], run.sensitivity[-1]
    dV = (
        -np.cos(q[2]) * qd[0] * S[2] - np.sin(q[2]) * qd[1] * S[2]
        - np.sin(q[2]) * S[3] + np.cos(q[2]) * S[4]
    )  # fmt: skip
    assert np.abs(dV).max() < 1e-10
