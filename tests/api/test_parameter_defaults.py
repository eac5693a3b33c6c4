"""Parameter defaults (System.set_parameter_defaults): compile() fills what it is not given."""

import math

import pytest

import pfaff
from pfaff.core.errors import ModelError


def test_default_fills_a_missing_value_and_a_given_one_wins():
    s = pfaff.models.pendulum()
    s.set_parameter_defaults({"g": 9.81, "L": 2.0})
    eom = s.equations()
    by_default = eom.compile({"m": 1})
    overridden = eom.compile({"m": 1, "L": 0.5})
    # θ̈ = −(g/L) sin θ, the pendulum's closed form
    assert by_default.accelerations(0.0, [0.3], [0.0])[0][0] == pytest.approx(
        -9.81 / 2.0 * math.sin(0.3), rel=1e-14
    )
    assert overridden.accelerations(0.0, [0.3], [0.0])[0][0] == pytest.approx(
        -9.81 / 0.5 * math.sin(0.3), rel=1e-14
    )


def test_bouncing_ball_restitution_is_a_parameter_with_its_default():
    ball = pfaff.models.bouncing_ball(0.8)
    eom = ball.equations()
    q0, qd0 = pfaff.models.bouncing_ball_state(1.0)
    for given, e in (({}, 0.8), ({"e": 0.5}, 0.5)):
        model = eom.compile({"m": 1.0, "g": 9.81, **given})
        traj = pfaff.simulate(model, q0, qd0, (0.0, 0.6), rtol=1e-12, atol=1e-14)
        hit = next(r for r in traj.events if r.kind == "impact")
        # Newton's law: the rebound is −e times the impact speed √(2 g h)
        assert hit.qd[1] == pytest.approx(e * math.sqrt(2 * 9.81), rel=1e-9)


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"nope": 1.0}, "not a parameter"),
        ({"g": "9.81"}, "real number"),
        ({"g": float("nan")}, "finite"),
        ([("g", 1.0)], "dict"),
    ],
)
def test_bad_defaults_are_refused(values, match):
    s = pfaff.models.pendulum()
    with pytest.raises(ModelError, match=match):
        s.set_parameter_defaults(values)
    assert s.parameter_defaults == {}


def test_bouncing_ball_restitution_out_of_range():
    with pytest.raises(ModelError, match=r"\[0, 1\]"):
        pfaff.models.bouncing_ball(1.5)
