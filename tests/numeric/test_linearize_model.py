"""NumericModel.linearize: the compiled model's linearization against the symbolic one and the
hand-derived cart-pole; states named by strings; bad states refused."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff

VALUES = {"m0": 2.0, "m1": 0.5, "g": 9.81, "l0": 0.8, "F": 0.0}


@pytest.fixture(scope="module")
def cartpole():
    eom = pfaff.models.n_link_pendulum_on_cart(1).equations()
    return eom, eom.compile(VALUES)


def test_cartpole_hand_derived(cartpole) -> None:
    _, model = cartpole
    lin = model.linearize(0.0, [0.0, 0.0], [0.0, 0.0], ["q0", "q1"], inputs=["F"])
    m0, m1, g, l0 = (VALUES[k] for k in ("m0", "m1", "g", "l0"))
    A = [[0, 0, 1, 0], [0, 0, 0, 1], [0, m1 * g / m0, 0, 0], [0, (m0 + m1) * g / (m0 * l0), 0, 0]]
    np.testing.assert_allclose(lin.A, A, atol=1e-13)
    np.testing.assert_allclose(lin.B[:, 0], [0, 0, 1 / m0, 1 / (m0 * l0)], atol=1e-13)
    assert [str(s) for s in lin.states] == [
        "q0(t)", "q1(t)", "Derivative(q0(t), t)", "Derivative(q1(t), t)"
    ]  # fmt: skip
    assert lin.inputs == [sp.Symbol("F")]


def test_agrees_with_symbolic_path() -> None:
    """A Cartesian pendulum (multiplier form) swinging through the bottom: a steady motion of
    nothing, so refused; at rest it is accepted and both paths give the same matrices."""
    eom = pfaff.models.cartesian_pendulum().equations()
    vals = {"m": 1.5, "g": 9.81, "L": 2.0}
    model = eom.compile(vals)
    x, y = eom.coordinates
    lin_n = model.linearize(0.0, [0.0, -2.0], [0.0, 0.0], ["x"])
    lin_s = eom.linearize({x: 0, y: -2, **vals}, [x])
    np.testing.assert_allclose(lin_n.A, lin_s.A, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(lin_n.multipliers[0], lin_s.multipliers[0], atol=1e-15)
    np.testing.assert_allclose(lin_n.lambda0, [-1.5 * 9.81 / 4], rtol=1e-14)
    with pytest.raises(pfaff.StateError, match="not a steady motion"):
        model.linearize(0.0, [0.0, -2.0], [1.0, 0.0], ["x"])


def test_bad_states(cartpole) -> None:
    _, model = cartpole
    with pytest.raises(pfaff.StateError, match="`q`"):
        model.linearize(0.0, [0.0], [0.0, 0.0], ["q0", "q1"])
    with pytest.raises(pfaff.StateError, match="`t`"):
        model.linearize(float("nan"), [0.0, 0.0], [0.0, 0.0], ["q0", "q1"])
    with pytest.raises(pfaff.ModelError, match="names `q0` twice"):
        model.linearize(0.0, [0.0, 0.0], [0.0, 0.0], ["q0", "q0"])
    with pytest.raises(pfaff.ModelError, match="not a coordinate"):
        model.linearize(0.0, [0.0, 0.0], [0.0, 0.0], ["q0", "theta"])
