"""pfaff.fit: identification of the damped pendulum m l² θ̈ + c θ̇ + m g l sin θ = 0.

Synthetic data from a tight run at the true values: noise-free data give the truth back (with
initial values fitted too, and through an observed expression that depends on a fitted
parameter); with 1 % Gaussian noise (20 fixed seeds) the estimates of (c, l) fall within 3
reported standard errors of the truth in at least 18 runs, and the mean reported standard error
is within 30 % of the estimates' spread over the seeds.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.errors import OptionError

TRUTH = {"m": 1.0, "l": 0.8, "g": 9.81, "c": 0.05}
SEEDS = list(range(1000, 1020))


@pytest.fixture(scope="module")
def model():
    return pfaff.models.damped_pendulum().equations().compile(TRUTH)


def clean_run(model, t, q0=0.6, qd0=0.0):
    return pfaff.simulate(model, [q0], [qd0], (t[0], t[-1]), t_eval=t, rtol=1e-12, atol=1e-14)


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_noise_free_with_initial_values(model):
    t = np.linspace(0, 3, 61)
    run = clean_run(model, t, 0.6, 0.3)
    guess = {"c": 0.1, "l": 1.0, "q0.theta": 0.5, "qd0.theta": 0.0}
    res = pfaff.fit(
        model, t, np.column_stack((run.q, run.qd)), guess, ["theta", "theta_dot"], [0.5], [0.0],
        rtol=1e-11,
    )  # fmt: skip
    assert res.status == "success"
    expected = {"c": 0.05, "l": 0.8, "q0.theta": 0.6, "qd0.theta": 0.3}
    for key, value in expected.items():
        assert res.estimates[key] == pytest.approx(value, rel=1e-6, abs=1e-8)
    assert np.abs(res.residuals).max() < 1e-8
    assert res.residuals.shape == (61, 2)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_observed_expression_of_a_fitted_parameter(model):
    """The bob's height −l cos θ depends on l directly: its Jacobian needs ∂y/∂l."""
    t = np.linspace(0, 3, 61)
    run = clean_run(model, t)
    theta = model.linearizer.coordinates[0]
    height = -sp.Symbol("l") * sp.cos(theta)
    data = -TRUTH["l"] * np.cos(run.q[:, 0])
    res = pfaff.fit(model, t, data, {"c": 0.1, "l": 1.0}, [height], [0.6], [0.0], rtol=1e-11)
    assert res.estimates["l"] == pytest.approx(0.8, rel=1e-6)
    assert res.estimates["c"] == pytest.approx(0.05, rel=1e-6)


@pytest.mark.slow
def test_identification_with_noise(model):
    t = np.linspace(0, 5, 101)
    clean = clean_run(model, t).q
    sigma = 0.01 * np.abs(clean).max()
    est, se = [], []
    for seed in SEEDS:
        data = clean + sigma * np.random.default_rng(seed).standard_normal(clean.shape)
        res = pfaff.fit(model, t, data, {"c": 0.1, "l": 1.0}, ["theta"], [0.6], [0.0])
        assert res.status == "success"
        est.append([res.estimates["c"], res.estimates["l"]])
        se.append([res.standard_errors["c"], res.standard_errors["l"]])
    est, se = np.array(est), np.array(se)
    inside = np.all(np.abs(est - [TRUTH["c"], TRUTH["l"]]) <= 3 * se, axis=1)
    assert inside.sum() >= 18
    ratio = se.mean(axis=0) / est.std(axis=0, ddof=1)
    assert np.all(np.abs(ratio - 1) <= 0.3), ratio


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"parameters": {"zz": 1.0}}, "'zz' is neither a parameter"),
        ({"parameters": {}}, "non-empty dict"),
        ({"parameters": {"c": "0.1"}}, r"`parameters\['c'\]` must be a real number"),
        ({"observe": ["phi"]}, "'phi' is neither a coordinate"),
        ({"observe": "theta"}, "`observe` must be a non-empty list"),
        ({"measured": np.zeros((5, 2))}, r"must have shape \(len\(t\), len\(observe\)\)"),
        ({"measured": np.full(11, np.nan)}, "NaN"),
        ({"t": np.zeros(11)}, "strictly increasing"),
        ({"weights": [-1.0]}, "non-negative"),
        ({"bounds": {"c": (0.2, 1.0)}}, "contain the guess"),
        ({"bounds": {"g": (0, 1)}}, "not a fitted value"),
        ({"t_eval": [0.0]}, "`t_eval` is set by `t`"),
    ],
)
def test_refused(model, kw, match):
    args = {
        "t": np.linspace(0, 1, 11), "measured": np.zeros(11), "parameters": {"c": 0.1},
        "observe": ["theta"], "q0": [0.1], "qd0": [0.0],
    }  # fmt: skip
    args |= kw
    with pytest.raises(OptionError, match=match):
        pfaff.fit(model, **args)


def test_plot_writes_a_figure(model, tmp_path):
    t = np.linspace(0, 1, 11)
    res = pfaff.fit(model, t, clean_run(model, t).q, {"c": 0.1}, ["theta"], [0.6], [0.0])
    res.plot(tmp_path / "fit.png")
    assert (tmp_path / "fit.png").stat().st_size > 1000
    assert set(res.to_dict()) >= {"estimates", "standard_errors", "status", "message"}
    assert repr(res).startswith("<pfaff.FitResult success: c = 0.05 ±")


def test_observed_expression_refusals(model):
    theta = model.linearizer.coordinates[0]
    t = np.linspace(0, 1, 11)
    for bad, match in ((sp.Symbol("k") * theta, "uses k"), (sp.Function("u")(pfaff.t), "uses")):
        with pytest.raises(pfaff.ModelError, match=match):
            pfaff.fit(model, t, np.zeros(11), {"c": 0.1}, [bad], [0.1], [0.0])


def test_parameter_with_assumptions_in_an_expression(model):
    """A parameter symbol written with assumptions (l positive) is the model's parameter l."""
    t = np.linspace(0, 2, 41)
    run = clean_run(model, t)
    theta = model.linearizer.coordinates[0]
    x = sp.Symbol("l", positive=True) * sp.sin(theta)
    data = TRUTH["l"] * np.sin(run.q[:, 0])
    res = pfaff.fit(model, t, data, {"l": 1.0}, [x], [0.6], [0.0], rtol=1e-11)
    assert res.estimates["l"] == pytest.approx(0.8, rel=1e-6)


def test_constrained_model_with_a_moving_start():
    """The Cartesian pendulum's rod length from x(t), y(t): the start moves with L (fixed angle),
    given as functions of the parameters; noise-free data give L back."""
    cart = pfaff.models.cartesian_pendulum().equations().compile({"m": 1.0, "g": 9.81, "L": 1.0})
    angle = 0.7

    def q0(p):
        return [p["L"] * np.sin(angle), -p["L"] * np.cos(angle)]

    truth = cart.with_parameters({"L": 1.3})
    t = np.linspace(0, 2, 41)
    run = pfaff.simulate(truth, q0({"L": 1.3}), [0, 0], (0, 2), t_eval=t, rtol=1e-12, atol=1e-14)
    res = pfaff.fit(
        cart, t, run.q, {"L": 1.0}, ["x", "y"], q0, lambda p: [0.0, 0.0],
        bounds={"L": (0.5, 2.0)}, rtol=1e-11,
    )  # fmt: skip
    assert res.status == "success"
    assert res.estimates["L"] == pytest.approx(1.3, rel=1e-7)
