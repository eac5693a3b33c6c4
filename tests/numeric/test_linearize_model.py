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


def test_no_symbolic_work_after_the_first_call(cartpole, monkeypatch) -> None:
    """The derivatives are generated once: later calls, other states, other parameter values
    (a with_parameters copy shares the factory) and other input values do numbers only."""
    import symengine

    from pfaff.derive import linearize as dl

    _, model = cartpole
    first = model.linearize(0.0, [0.0, 0.0], [0.0, 0.0], ["q0", "q1"], inputs=["F"])
    heavy = model.with_parameters({"m1": 1.5})
    assert heavy.linearizer is model.linearizer

    def refuse(*args, **kwargs):
        raise AssertionError("symbolic work at call time")

    for owner, name in [
        (sp, "diff"), (sp.Expr, "diff"), (sp.Basic, "subs"), (sp.Basic, "xreplace"),
        (sp.Matrix, "jacobian"), (sp, "lambdify"), (sp, "simplify"), (symengine, "diff"),
        (symengine, "Lambdify"), (symengine, "sympify"), (symengine, "cse"),
        (dl, "LinearForms"), (dl, "linear_forms"), (dl, "_generate"),
    ]:  # fmt: skip
        monkeypatch.setattr(owner, name, refuse)
    again = model.linearize(0.0, [0.3, 0.0], [0.0, 0.0], ["q0", "q1"], inputs=["F"])
    np.testing.assert_allclose(again.A, first.A, atol=1e-13)  # q0 is ignorable
    lin = heavy.linearize(0.0, [0.0, 0.0], [0.0, 0.0], ["q0", "q1"], inputs=["F"])
    m0, m1, g = VALUES["m0"], 1.5, VALUES["g"]
    assert lin.A[2, 1] == pytest.approx(m1 * g / m0, rel=1e-13)
    assert lin.inputs == [sp.Symbol("F")]


def test_factory_pickles(cartpole) -> None:
    """The factory pickles (its generated code is made again after unpickling) and gives the
    same matrices; the model's factory is made by the derivation stage, not by the façade."""
    import pickle

    from pfaff.numeric.linearizer import LinearizerFactory

    _, model = cartpole
    args = (0.0, [0.0, 0.0], [0.0, 0.0], ["q0", "q1"])
    lin = model.linearize(*args, inputs=["F"])
    assert isinstance(model.linearizer, LinearizerFactory)
    clone = pickle.loads(pickle.dumps(model))  # the whole model, its factory with it
    assert clone.linearizer is not model.linearizer
    again = clone.linearize(*args, inputs=["F"])
    np.testing.assert_array_equal(again.A, lin.A)
    np.testing.assert_array_equal(again.B, lin.B)
    assert again.states == lin.states and again.inputs == lin.inputs


def _spring_cart():
    """A cart of mass m on a spring of stiffness k (an input): A = [[0, 1], [-k/m, 0]]."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(sp.Symbol("m"), [x, 0])
    k = s.add_input("k")
    push = s.add_input("push")
    s.add_force([-k * x + push, 0], at=[x, 0])
    return s.equations().compile({"m": 2.0})


def test_input_values_per_call() -> None:
    model = _spring_cart()
    assert model.inputs == ["k", "push"]
    lin = model.linearize(0.0, [0.0], [0.0], ["x"], input_values={"k": 4.0})
    np.testing.assert_allclose(lin.A, [[0.0, 1.0], [-2.0, 0.0]], atol=1e-15)
    assert model.parameters["k"] == 0.0  # nothing written into the model
    np.testing.assert_allclose(model.linearize(0.0, [0.0], [0.0], ["x"]).A, [[0, 1], [0, 0]])
    lin = model.linearize(0.0, [0.0], [0.0], ["x"], inputs=["push"], input_values={"k": 8.0})
    np.testing.assert_allclose(lin.B, [[0.0], [0.5]], atol=1e-15)
    np.testing.assert_allclose(lin.A[1, 0], -4.0)
    with pytest.raises(pfaff.StateError, match="accelerate"):  # pushed: not an equilibrium
        model.linearize(0.0, [0.0], [0.0], ["x"], input_values={"push": 1.0})
    lin = model.linearize(0.0, [0.25], [0.0], ["x"], input_values={"push": 1.0, "k": 4.0})
    np.testing.assert_allclose(lin.A, [[0.0, 1.0], [-2.0, 0.0]], atol=1e-15)
    with pytest.raises(pfaff.OptionError, match="`m` is not an input"):
        model.linearize(0.0, [0.0], [0.0], ["x"], input_values={"m": 1.0})
    with pytest.raises(pfaff.OptionError, match="input_values"):
        model.linearize(0.0, [0.0], [0.0], ["x"], input_values={"k": "4"})
