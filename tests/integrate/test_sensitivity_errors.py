"""pfaff.sensitivities: what it refuses (named), and redundant constraint rows."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pfaff
from pfaff.errors import ConstraintError, ModelError, OptionError

PEND = {"m": 1.0, "g": 9.81, "L": 1.0}


@pytest.fixture(scope="module")
def cartesian():
    return pfaff.models.cartesian_pendulum().equations().compile(PEND)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"parameters": ["zz"]}, "`parameters`: 'zz' is not a parameter"),
        ({"parameters": ["g", "g"]}, "`parameters` names `g` twice"),
        ({"parameters": "g"}, "`parameters` must be a list"),
        ({"method": "baumgarte"}, "method='projection' only"),
        ({"events": [pfaff.Event(lambda t, q, qd: q[0], "x")]}, "events or impacts"),
        ({"inputs": {"g": 1.0}}, "`inputs` are not supported"),
        ({"initial": True}, "needs `independent`"),
        ({"initial": 1}, "`initial` must be True or False"),
        ({"integrator": "RK45"}, "`integrator`='DOP853' only"),
    ],
)
def test_refused_options(cartesian, kw, match):
    with pytest.raises(OptionError, match=match):
        pfaff.sensitivities(cartesian, [0.6, -0.8], [0.8, 0.6], (0, 1), **kw)


def test_families_refused():
    model = pfaff.models.rolling_ring(3, family=True).equations().compile({"M": 1.0, "r": 1.0})
    q0, qd0 = pfaff.models.ring_state(3, 1.0, 0.0)
    with pytest.raises(ModelError, match="families"):
        pfaff.sensitivities(model, q0, qd0, (0, 1))


def test_model_events_refused():
    s = pfaff.models.pendulum()
    s.add_event(s.coordinates[0], name="bottom")
    model = s.equations().compile(PEND)
    with pytest.raises(OptionError, match=r"saltation matrix.*bottom"):
        pfaff.sensitivities(model, [0.1], [0.0], (0, 1), parameters=["g"])


def test_redundant_rows():
    """The rod written twice: ∂q/∂L as with one rod (the redundant row dropped from the
    variational solve), ∂λ/∂L refused since λ itself is not determined."""
    s = pfaff.models.cartesian_pendulum()
    x, y = s.coordinates
    L = next(p for p in s.equations().parameters if p.name == "L")
    s.add_holonomic_constraint(2 * (x**2 + y**2 - L**2), name="rod again")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        model = s.equations().compile(PEND)
    single = pfaff.models.cartesian_pendulum().equations().compile(PEND)
    start = ([0.6, -0.8], [0.8, 0.6])
    kw = {"parameters": ["L", "g"], "t_eval": [0.0, 1.0, 2.0], "rtol": 1e-11}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        run = pfaff.sensitivities(model, *start, (0, 2), **kw)
    ref = pfaff.sensitivities(single, *start, (0, 2), **kw)
    assert np.allclose(run.sensitivity, ref.sensitivity, rtol=1e-8, atol=1e-9)
    assert ref.multiplier_sensitivity.shape == (3, 1, 2)
    with pytest.raises(ConstraintError, match="redundant"):
        _ = run.multiplier_sensitivity


@pytest.mark.slow
def test_mrp_switch_ends_the_run():
    """A spin about z passes |σ| = 1 at half a turn: the shadow-set switch restarts the
    integrator in other coordinates, which the sensitivities cannot follow: status "failed"."""
    s = pfaff.models.torque_free_body("mrp")
    model = s.equations().compile({"I1": 1.0, "I2": 2.0, "I3": 3.0})
    att = s.bodies[0].attitude
    q0 = att.from_dcm(np.eye(3))
    qd0 = att.rates(q0, [0.0, 0.0, 2.0])
    run = pfaff.sensitivities(model, q0, qd0, (0, 3), parameters=["I3"])
    assert run.status == "failed"
    assert "MRP shadow-set switch" in run.message
    assert run.t[-1] < 3.0
