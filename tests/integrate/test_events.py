"""User events: pfaff.Event in simulate(events=...), System.add_event compiled with the model.

The reference: a pendulum released from rest at θ₀ crosses θ = 0 downwards once per period
T = 4 √(L/g) K(m), m = sin²(θ₀/2) (K the complete elliptic integral of the first kind).
"""

import pickle

import numpy as np
import pytest
import sympy as sp
from scipy.special import ellipk

import pfaff
from pfaff import ModelError, OptionError

L, G, TH0 = 1.0, 9.81, 1.0
PARAMS = {"m": 1.0, "g": G, "L": L}
PERIOD = 4 * np.sqrt(L / G) * ellipk(np.sin(TH0 / 2) ** 2)


@pytest.fixture(scope="module")
def angle():
    return pfaff.models.pendulum().equations().compile(PARAMS)


@pytest.fixture(scope="module")
def cartesian():
    return pfaff.models.cartesian_pendulum().equations().compile(PARAMS)


def _start(model):
    if model.n == 1:
        return [TH0], [0.0]
    return [L * np.sin(TH0), -L * np.cos(TH0)], [0.0, 0.0]


def _down(model):
    """θ, or x (= L sin θ), falling through 0: once per period, at T/4 + kT."""
    return pfaff.Event(lambda t, q, qd: q[0], name="down", direction=-1)


def _period_error(traj, count=4):
    ts = np.array([e.t for e in traj.events])
    assert len(ts) == count
    assert {e.name for e in traj.events} == {"down"} and {e.kind for e in traj.events} == {"event"}
    periods = np.diff(ts)
    first = ts[0] - PERIOD / 4
    return max(np.abs(periods / PERIOD - 1).max(), abs(first) / PERIOD)


@pytest.mark.parametrize("which", ["angle", "cartesian"])
def test_period_projection(which, request):
    model = request.getfixturevalue(which)
    q0, qd0 = _start(model)
    traj = pfaff.simulate(
        model, q0, qd0, (0, 3.9 * PERIOD), events=[_down(model)], rtol=1e-12, atol=1e-14
    )
    assert traj.status == "success"
    assert _period_error(traj) < 1e-10
    for e in traj.events:  # each root is a reported state
        i = int(np.flatnonzero(traj.t == e.t)[0])
        np.testing.assert_array_equal(traj.q[i], e.q)
        assert abs(e.q[0]) < 1e-9


@pytest.mark.parametrize(
    ("method", "rtol", "atol", "bound"),
    [
        ("baumgarte", 1e-11, 1e-13, 1e-9),
        pytest.param("ida", 1e-8, 1e-10, 1e-6, marks=pytest.mark.slow),
    ],
)
@pytest.mark.parametrize("which", ["angle", "cartesian"])
def test_period_other_methods(which, method, rtol, atol, bound, request):
    model = request.getfixturevalue(which)
    q0, qd0 = _start(model)
    traj = pfaff.simulate(
        model, q0, qd0, (0, 3.9 * PERIOD), events=[_down(model)], method=method, rtol=rtol,
        atol=atol,
    )  # fmt: skip
    assert traj.status == "success"
    assert _period_error(traj) < bound


def test_direction(angle):
    q0, qd0 = _start(angle)
    kw = dict(rtol=1e-10, atol=1e-12)
    both = pfaff.simulate(angle, q0, qd0, (0, 2.1 * PERIOD), events=[pfaff.Event(_g)], **kw)
    up = pfaff.Event(_g, name="up", direction=1)
    down = pfaff.Event(_g, name="down", direction=-1)
    split = pfaff.simulate(angle, q0, qd0, (0, 2.1 * PERIOD), events=[up, down], **kw)
    assert [e.name for e in both.events] == ["event1"] * 4
    assert [e.name for e in split.events] == ["down", "up", "down", "up"]
    np.testing.assert_allclose([e.t for e in split.events], [e.t for e in both.events], rtol=1e-9)
    np.testing.assert_allclose(
        [e.t for e in both.events], PERIOD * np.array([0.25, 0.75, 1.25, 1.75]), rtol=1e-8
    )


def _g(t, q, qd):
    return q[0]


@pytest.mark.parametrize("t_eval", [None, np.linspace(0, 3 * PERIOD, 31)])
def test_terminal(cartesian, t_eval):
    q0, qd0 = _start(cartesian)
    stop = pfaff.Event(_g, name="second pass", direction=-1, terminal=2)
    traj = pfaff.simulate(
        cartesian, q0, qd0, (0, 3 * PERIOD), events=[stop], t_eval=t_eval, rtol=1e-12, atol=1e-14
    )
    assert traj.status == "success"
    assert "second pass" in traj.message
    assert abs(traj.t[-1] - 1.25 * PERIOD) < 1e-10 * PERIOD
    assert traj.t[-1] == traj.events[-1].t and len(traj.events) == 2
    np.testing.assert_array_equal(traj.q[-1], traj.events[-1].q)
    assert abs(traj.q[-1, 0]) < 1e-9
    assert np.all(np.diff(traj.t) > 0)
    if t_eval is not None:
        assert set(t_eval[t_eval < traj.t[-1]]) <= set(traj.t)
    first = pfaff.simulate(
        cartesian, q0, qd0, (0, 3 * PERIOD), events=[pfaff.Event(_g, terminal=True)]
    )
    assert abs(first.t[-1] - 0.25 * PERIOD) < 1e-8 and "`event1`" in first.message


def test_declared_on_system():
    s = pfaff.models.pendulum()
    theta = s.coordinates[0]
    s.add_event(theta, name="down", direction=-1)
    s.add_event(theta.diff(pfaff.t) * sp.Symbol("L"), name="turn", direction=1, terminal=2)
    model = s.equations().compile(PARAMS)
    assert [e.name for e in model.events] == ["down", "turn"]
    q0, qd0 = _start(model)
    kw = dict(rtol=1e-12, atol=1e-14)
    traj = pfaff.simulate(model, q0, qd0, (0, 3 * PERIOD), **kw)
    plain = pfaff.models.pendulum().equations().compile(PARAMS)
    ref = pfaff.simulate(
        plain, q0, qd0, (0, 3 * PERIOD), events=[_down(plain)], **kw
    )  # the callable form
    downs = [e.t for e in traj.events if e.name == "down"]
    np.testing.assert_allclose(downs, [e.t for e in ref.events][: len(downs)], rtol=1e-13)
    # θ̇ rises through 0 at the left turning point T/2, and the second time at 3T/2: stop
    assert "`turn`" in traj.message and abs(traj.t[-1] - 1.5 * PERIOD) < 1e-10
    # pickled, and with other parameter values
    again = pickle.loads(pickle.dumps(model))
    traj2 = pfaff.simulate(again, q0, qd0, (0, 3 * PERIOD), **kw)
    assert [e.t for e in traj2.events] == [e.t for e in traj.events]
    long = model.with_parameters({"L": 4.0})
    traj3 = pfaff.simulate(long, q0, qd0, (0, 6 * PERIOD), **kw)
    assert abs(traj3.events[0].t - PERIOD / 2) < 1e-9  # T ∝ √L: the first down at T(4)/4


def test_events_in_files(cartesian, tmp_path):
    xr = pytest.importorskip("xarray")
    q0, qd0 = _start(cartesian)
    traj = pfaff.simulate(cartesian, q0, qd0, (0, PERIOD), events=[_down(cartesian)])
    ds = xr.load_dataset(traj.to_netcdf(tmp_path / "run.nc"))
    assert [str(n) for n in ds["event_name"].values] == ["down"]
    np.testing.assert_allclose(ds["event_time"].values, [traj.events[0].t])
    none = pfaff.simulate(cartesian, q0, qd0, (0, 0.1))
    assert xr.load_dataset(none.to_netcdf(tmp_path / "none.nc")).attrs["events"] == 0


def test_json_summary(cartesian):
    from pfaff.cli.simdemo import _summary

    q0, qd0 = _start(cartesian)
    traj = pfaff.simulate(cartesian, q0, qd0, (0, PERIOD), events=[_down(cartesian)])
    (rec,) = _summary(traj, 0.0)["events"]
    assert rec == {"name": "down", "t": traj.events[0].t, "kind": "event"}


def test_bad_input(cartesian):
    with pytest.raises(OptionError, match="`g` of an Event must be callable"):
        pfaff.Event(0.5)
    with pytest.raises(OptionError, match="`direction` must be -1"):
        pfaff.Event(_g, direction=2)
    with pytest.raises(OptionError, match="`terminal` must be"):
        pfaff.Event(_g, terminal=-1)
    with pytest.raises(OptionError, match="`events` must be a list"):
        pfaff.simulate(cartesian, *_start(cartesian), (0, 1), events=pfaff.Event(_g))
    with pytest.raises(OptionError, match=r"`events\[0\]` must be a pfaff.Event"):
        pfaff.simulate(cartesian, *_start(cartesian), (0, 1), events=[_g])
    s = pfaff.models.cartesian_pendulum()
    x, _ = s.coordinates
    with pytest.raises(ModelError, match="`condition` names `k`, which is not a parameter"):
        s.add_event(x - sp.Symbol("k"))
    with pytest.raises(ModelError, match="not a coordinate"):
        s.add_event(sp.Function("z")(pfaff.t))
    with pytest.raises(OptionError, match="event `e`: `direction`"):
        s.add_event(x, name="e", direction="up")
    s.add_event(x, name="e")
    with pytest.raises(ModelError, match="already an event `e`"):
        s.add_event(x, name="e")
    nan = pfaff.Event(lambda t, q, qd: np.nan if t > 0.1 else 1.0, name="bad")
    traj = pfaff.simulate(cartesian, *_start(cartesian), (0, 1), events=[nan])
    assert traj.status == "failed" and "event `bad` is nan" in traj.message


def test_families_refuse_events():
    ring = pfaff.models.rolling_ring(4, force=True, family=True)
    ring.add_event(ring.coordinates[0], name="x")
    with pytest.raises(ModelError, match=r"events .* not supported by models with families"):
        ring.equations().compile({"M": 1, "r": 0.5, "F": 2})
