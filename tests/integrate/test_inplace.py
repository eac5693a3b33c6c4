"""The in-place DOP853 of long states (pfaff.integrate.inplace) against SciPy's DOP853: the same
method, so the same steps and the same results to rounding."""

import importlib.util

import numpy as np
import pytest
from scipy.integrate import DOP853

import pfaff
from pfaff.integrate import inplace
from pfaff.integrate.inplace import InPlaceDOP853

HAVE_NUMBA = importlib.util.find_spec("numba") is not None


@pytest.fixture(autouse=True, params=["numpy", "compiled"])
def sums(request, monkeypatch):
    """Every test on both paths of the stage sums: NumPy's passes and the compiled loops of
    pfaff.integrate.inplacejit (from any state size; without numba both are NumPy's)."""
    monkeypatch.setattr(inplace, "JIT_MIN", 0 if request.param == "compiled" else 10**12)
    return request.param


def _van_der_pol(t, y):
    return np.array([y[1], 5.0 * (1 - y[0] ** 2) * y[1] - y[0]])


def _into(t, y, out):
    out[:] = _van_der_pol(t, y)


def _run(solver):
    ts, ys = [], []
    while solver.status == "running":
        solver.step()
        ts.append(solver.t)
        ys.append(np.array(solver.y))
    return np.array(ts), np.array(ys)


def test_same_steps_as_scipy_with_rejections():
    """Van der Pol (μ = 5) over its relaxation: rejected steps, and the same number of steps,
    right-hand sides and final state as SciPy's DOP853. (Each step's size comes from an error
    estimate that cancels to ~1e-11 of the stages, whose rounding differs between the two sums:
    the grids agree to 1e-7, not to rounding; one step from the same state does, below.)"""
    kw = dict(rtol=1e-8, atol=1e-10, first_step=0.5)  # a first step far too long: rejected
    a = DOP853(_van_der_pol, 0.0, [2.0, 0.0], 8.0, **kw)
    b = InPlaceDOP853(_van_der_pol, 0.0, [2.0, 0.0], 8.0, into=_into, **kw)
    (ta, ya), (tb, yb) = _run(a), _run(b)
    assert a.nfev > 13 * len(ta)  # some attempts were rejected
    assert len(ta) == len(tb) and a.nfev == b.nfev
    np.testing.assert_allclose(tb, ta, rtol=1e-7)
    np.testing.assert_allclose(yb[-1], ya[-1], rtol=1e-7)


# accepted at once: all to rounding; rejected first, then shorter by the rejected error estimate
@pytest.mark.parametrize(("h", "tol"), [(0.05, 1e-14), (0.6, 1e-10)])
@pytest.mark.parametrize("atol", [1e-10, [1e-10, 3e-9]])
def test_one_step_as_scipy(h, tol, atol, sums):
    """From the same state and step size, one step of each: the same attempts, the same step,
    new state and dense output to rounding (after a rejection, to the rounding of the error
    estimate that shortened it), the same next step size."""
    kw = dict(rtol=1e-8, atol=atol, first_step=h)
    a = DOP853(_van_der_pol, 0.3, [1.5, -0.8], 8.0, **kw)
    b = InPlaceDOP853(_van_der_pol, 0.3, [1.5, -0.8], 8.0, into=_into, **kw)
    assert (b._jit is not None) == (sums == "compiled" and HAVE_NUMBA)
    a.step()
    b.step()
    assert a.nfev == b.nfev
    np.testing.assert_allclose(b.t, a.t, rtol=tol)
    np.testing.assert_allclose(b.y, a.y, rtol=tol, atol=1e-15)
    np.testing.assert_allclose(b.h_abs, a.h_abs, rtol=1e-9)
    tm = np.array([a.t_old, (a.t_old + a.t) / 2, a.t])
    np.testing.assert_allclose(b.dense_output()(tm), a.dense_output()(tm), rtol=tol)
    np.testing.assert_allclose(b.dense_output()(tm[1]), a.dense_output()(tm[1]), rtol=tol)
    dense = b.dense_output()
    b.step()
    with pytest.raises(RuntimeError, match="earlier step"):
        dense(tm[1])


@pytest.fixture(scope="module")
def ring():
    return (
        pfaff.models.rolling_ring(64, force=True, family=True)
        .equations()
        .compile({"M": 1, "r": 0.5, "F": 2})
    )


@pytest.mark.parametrize("first_step", [None, 0.4])
def test_ring_run_as_scipy(ring, monkeypatch, first_step):
    """The pushed family ring through simulate: the in-place path and SciPy's take the same
    steps and give the same trajectory and work integral (during the step vs afterwards) to
    rounding; the work is F Δx, the closed form."""
    q0, qd0 = pfaff.models.ring_state(64, 0.5, theta=np.pi, theta_dot=0.7)
    kw = dict(t_eval=[0.0, 0.13, 0.5], max_step=0.1, first_step=first_step)
    runs = []
    for limit in (0, 10**12):  # in place, then SciPy's
        monkeypatch.setattr(inplace, "INPLACE_MIN", limit)
        runs.append(pfaff.simulate(ring, q0, qd0, (0.0, 0.5), **kw))
    a, b = runs
    assert a.stats["steps"] == b.stats["steps"] and a.stats["nfev"] == b.stats["nfev"]
    np.testing.assert_allclose(a.q, b.q, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(a.qd, b.qd, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(a.nc_work, b.nc_work, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(a.nc_work, 2.0 * (a.q[:, 0] - q0[0]), rtol=1e-10, atol=1e-14)


def test_work_node_by_node(ring, monkeypatch):
    """The work up to reported times inside steps with the dense output asked for one node at
    a time (long states, pfaff.integrate.work.ONE_NODE_FROM) equals the one call for all four
    nodes, and F Δx."""
    from pfaff.integrate import work

    q0, qd0 = pfaff.models.ring_state(64, 0.5, theta=np.pi, theta_dot=0.7)
    kw = dict(t_eval=[0.0, 0.13, 0.31, 0.5], max_step=0.1)
    monkeypatch.setattr(inplace, "INPLACE_MIN", 0)
    a = pfaff.simulate(ring, q0, qd0, (0.0, 0.5), **kw)
    monkeypatch.setattr(work, "ONE_NODE_FROM", 1)
    b = pfaff.simulate(ring, q0, qd0, (0.0, 0.5), **kw)
    np.testing.assert_allclose(b.nc_work, a.nc_work, rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(b.nc_work, 2.0 * (b.q[:, 0] - q0[0]), rtol=1e-10, atol=1e-14)


def test_dense_components_as_the_whole(sums):
    """The interpolant at a few components (what the work integral's nodes read) equals the
    whole dense output there, to rounding."""
    b = InPlaceDOP853(_van_der_pol, 0.3, [1.5, -0.8], 8.0, into=_into, rtol=1e-8, atol=1e-10)
    b.step()
    dense = b.dense_output()
    for t in (b.t_old, 0.3 * b.t_old + 0.7 * b.t, b.t):
        np.testing.assert_allclose(dense.at(t, np.array([1])), dense(t)[1:], rtol=1e-14)
        np.testing.assert_allclose(dense.at(t, np.array([0, 1])), dense(t), rtol=1e-14)


def test_spans_and_threads(ring, monkeypatch, sums):
    """The compiled sums over spans of 16 components: the same run to the last bit on one
    thread and on two (the error norm's sums added span by span in order), and to rounding
    the run of one span."""
    from pfaff.numeric import streams

    if sums != "compiled" or not HAVE_NUMBA:
        pytest.skip("the spans are the compiled path's")
    q0, qd0 = pfaff.models.ring_state(64, 0.5, theta=np.pi, theta_dot=0.7)
    kw = dict(t_eval=[0.0, 0.13, 0.5], max_step=0.1)
    monkeypatch.setattr(inplace, "INPLACE_MIN", 0)
    whole = pfaff.simulate(ring, q0, qd0, (0.0, 0.5), **kw)
    monkeypatch.setattr(inplace, "SPAN", 16)
    runs = []
    for threads in (1, 2):
        monkeypatch.setattr(streams, "THREADS", threads)
        monkeypatch.setattr(streams, "PARALLEL_FROM", 0)
        runs.append(pfaff.simulate(ring, q0, qd0, (0.0, 0.5), **kw))
    one, two = runs
    assert one.stats["steps"] == two.stats["steps"] == whole.stats["steps"]
    for key in ("q", "qd", "nc_work"):
        np.testing.assert_array_equal(getattr(two, key), getattr(one, key))
        np.testing.assert_allclose(getattr(one, key), getattr(whole, key), rtol=1e-13, atol=1e-14)
