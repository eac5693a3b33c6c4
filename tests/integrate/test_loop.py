"""The compiled stepping loop (pfaff.integrate.loop) against the Python path it stands in for.

Each run is made twice, with the loop and with ``PFAFF_LOOP=0`` (today's Python stepper,
:class:`pfaff.integrate.fastrk.FloatDOP853` with the projection after each step): the same
method and step-size rule, so the states agree to rounding, the steps to a few, and the
energy balance and constraint residuals reported are as small. Also: the fallback without
numba, a step handed to the Python path where the constraints part, an Euler-angle singularity,
``max_steps`` and a stall, each ending the run exactly as the Python path ends it.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.integrate import loop
from pfaff.numeric import jit

CHAIN = 8  # links of the chain on a cart


@pytest.fixture(scope="module")
def pendulum() -> pfaff.NumericModel:
    return pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})


@pytest.fixture(scope="module")
def chain() -> pfaff.NumericModel:
    """The 8-link chain on a cart pushed by F = 0.7 (the work integral runs)."""
    eom = pfaff.models.n_link_pendulum_on_cart(CHAIN).equations()
    values = {str(p): 1.0 + 0.05 * i for i, p in enumerate(eom.parameters)}
    return eom.compile(values | {"g": 9.81, "F": 0.7})


@pytest.fixture(scope="module")
def disk() -> pfaff.NumericModel:
    """The rolling disk: two nonholonomic no-slip rows, 3-1-2 Euler angles."""
    return pfaff.models.rolling_disk().equations().compile({"m": 1.3, "r": 0.4, "g": 9.81})


def disk_state(theta: float, psi_d: float, phi_d: float, r: float = 0.4) -> tuple:
    """The disk at lean θ turning at ψ̇ and spinning at φ̇, on its three constraints: the centre
    at height r cos θ moving with ω × (r k), k the lean frame's axis from contact to centre."""
    ct, st = np.cos(theta), np.sin(theta)
    j, k = np.array([0.0, ct, st]), np.array([0.0, -st, ct])  # (yaw ψ = 0)
    w = psi_d * np.array([0.0, 0.0, 1.0]) + phi_d * j
    v = np.cross(w, r * k)
    return np.array([0.0, 0.0, r * ct, 0.0, theta, 0.0]), np.array([*v, psi_d, 0.0, phi_d])


def both(monkeypatch: pytest.MonkeyPatch, model: object, *args: object, **kw: object) -> tuple:
    """The run with the compiled loop, then on the Python path."""
    compiled = pfaff.simulate(model, *args, **kw)
    with monkeypatch.context() as m:
        m.setenv("PFAFF_LOOP", "0")
        python = pfaff.simulate(model, *args, **kw)
    assert compiled.stats["stepping"] == "compiled loop"
    assert python.stats["stepping"] == "python"
    assert python.stats["stepping_reason"] == "PFAFF_LOOP=0"
    return compiled, python


def agree(a: pfaff.Trajectory, b: pfaff.Trajectory, rtol: float = 1e-9, steps: int = 3) -> None:
    """The same states to rounding (relative to each coordinate's range), the same statistics
    within a few steps, the same energy balance and residuals."""
    assert a.status == b.status == "success"
    assert abs(a.stats["steps"] - b.stats["steps"]) <= steps
    assert abs(a.stats["rejected"] - b.stats["rejected"]) <= steps
    if len(a.t) == len(b.t) and np.array_equal(a.t, b.t):  # the same t_eval
        for x, y in ((a.q, b.q), (a.qd, b.qd)):
            scale = np.maximum(np.abs(y).max(axis=0), 1.0)
            assert (np.abs(x - y) / scale).max() < rtol
        np.testing.assert_allclose(a.nc_work, b.nc_work, rtol=rtol, atol=rtol)
    else:  # every step reported: step sizes agree to ~1e-8 (the error norm's rounding)
        np.testing.assert_allclose(a.t, b.t, rtol=1e-6)
        assert a.t[-1] == b.t[-1]
        np.testing.assert_allclose(a.q[-1], b.q[-1], rtol=rtol, atol=rtol)
        np.testing.assert_allclose(a.nc_work[-1], b.nc_work[-1], rtol=rtol, atol=rtol)
    for tr in (a, b):
        assert np.abs(tr.constraint_residual).max(initial=0.0) <= 1e-10
    np.testing.assert_allclose(
        np.abs(a.energy_balance).max(), np.abs(b.energy_balance).max(), rtol=0.5, atol=1e-10
    )


def test_pendulum_at_t_eval(pendulum: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch) -> None:
    """The Cartesian pendulum released from the horizontal, 10 s reported at 41 times: the
    same states, steps, projections; E = 0 kept to 1e-7 by both."""
    te = np.linspace(0.0, 10.0, 41)
    a, b = both(monkeypatch, pendulum, [1.0, 0.0], [0.0, 0.0], (0, 10), t_eval=te)
    agree(a, b)
    assert abs(a.stats["projections"] - b.stats["projections"]) <= 3
    assert np.abs(a.kinetic + a.potential).max() < 1e-7 * 9.81


def test_pendulum_every_step(pendulum: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch) -> None:
    a, b = both(monkeypatch, pendulum, [0.6, -0.8], [0.8, 0.6], (0, 5))
    agree(a, b)
    assert len(a.t) == a.stats["steps"] + 1  # the start and every step


def test_chain_with_work(chain: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch) -> None:
    """The 8-link chain pushed by F: the work integral inside the loop, at the reported times
    (the dense output's quadrature) and over each step (the method's own), agrees, and the
    energy balance T + V − E0 − W closes to the integration error in both."""
    q0 = np.concatenate([[0.0], np.linspace(0.2, 0.6, CHAIN)])
    te = np.linspace(0.0, 1.0, 9)
    a, b = both(monkeypatch, chain, q0, np.zeros(CHAIN + 1), (0, 1), t_eval=te)
    agree(a, b)
    assert abs(a.nc_work[-1]) > 0.01  # the push does work
    assert np.abs(a.energy_balance).max() < 1e-7 * np.abs(a.potential).max()


def test_rolling_disk(disk: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch) -> None:
    """A nonholonomic system with Euler angles: the rolling, turning, spinning disk."""
    q0, qd0 = disk_state(0.2, 0.5, 5.0)
    a, b = both(monkeypatch, disk, q0, qd0, (0, 2), t_eval=np.linspace(0, 2, 5))
    agree(a, b)
    assert np.abs(a.energy_balance).max() < 1e-8


def test_disk_falling_flat_stops_as_before(
    disk: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A disk released leaning, without spin, falls towards θ = π/2, where its 3-1-2 Euler
    angles are singular: the loop hands that step to the Python path, which stops the run."""
    q0, qd0 = disk_state(1.0, 0.0, 0.0)
    a = pfaff.simulate(disk, q0, qd0, (0, 5))
    with monkeypatch.context() as m:
        m.setenv("PFAFF_LOOP", "0")
        b = pfaff.simulate(disk, q0, qd0, (0, 5))
    assert a.status == b.status == "failed" and "singularity" in a.message
    assert a.stats["python_steps"] == 1 and a.stats["steps"] == b.stats["steps"]
    assert a.t[-1] == pytest.approx(b.t[-1], rel=1e-9)


def test_parting_constraints_fail_as_before(monkeypatch: pytest.MonkeyPatch) -> None:
    """A bead on the unit circle whose x is driven as t/2: past t = 2 no state satisfies both
    constraints; the loop leaves that step to the Python path, which fails it, named."""
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x - pfaff.t / 2, name="drive")
    s.add_holonomic_constraint(x**2 + y**2 - 1, name="circle")
    model = s.equations().compile({})
    ts = np.linspace(0, 1.9, 20)
    a = pfaff.simulate(model, [0, -1], [0.5, 0], (0, 3), t_eval=ts)
    with monkeypatch.context() as m:
        m.setenv("PFAFF_LOOP", "0")
        b = pfaff.simulate(model, [0, -1], [0.5, 0], (0, 3), t_eval=ts)
    assert a.status == b.status == "failed" and a.stats["python_steps"] >= 1
    assert "constraints cannot be satisfied" in a.message
    assert "constraints cannot be satisfied" in b.message
    t_a, t_b = (float(tr.message.split("t = ")[1].split(":")[0]) for tr in (a, b))
    assert t_a == pytest.approx(t_b, abs=1e-6)
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)


def test_max_steps_and_stall(pendulum: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch) -> None:
    """``max_steps`` ends the loop's run after exactly that many steps; a block with (nearly)
    Coulomb friction, −μg tanh(10¹² ẋ), stalls (its steps collapse) where it stops, v0/(μg),
    after the same steps on both paths."""
    a = pfaff.simulate(pendulum, [1, 0], [0, 0], (0, 100), max_steps=300, t_eval=[0, 100])
    assert a.stats["stepping"] == "compiled loop" and a.status == "failed"
    assert "max_steps = 300" in a.message and a.stats["steps"] == 300
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    s.add_generalized_force(x, -0.3 * 9.81 * sp.tanh(1e12 * x.diff(pfaff.t)))
    block = s.equations().compile({})
    runs = []
    for flag in ("1", "0"):
        monkeypatch.setenv("PFAFF_LOOP", flag)
        runs.append(pfaff.simulate(block, [0.0], [0.3], (0, 10.0), t_eval=[0.0, 10.0]))
    a, b = runs
    assert a.stats["stepping"] == "compiled loop" and b.stats["stepping"] == "python"
    assert "step-size collapse" in a.message and "step-size collapse" in b.message
    assert a.stats["steps"] == b.stats["steps"]
    t_a, t_b = (float(tr.message.split("t = ")[1].split(":")[0]) for tr in (a, b))
    assert t_a == pytest.approx(0.3 / (0.3 * 9.81), abs=1e-6) and t_a == pytest.approx(t_b)


def test_without_numba(pendulum: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch) -> None:
    """numba missing (its import fails): the Python path, saying why, with the same results."""
    te = np.linspace(0.0, 3.0, 7)
    a = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0, 3), t_eval=te)
    monkeypatch.delitem(jit._MODULES, "loopkernel")  # (loaded once per process: forgotten)
    monkeypatch.delattr(pfaff.integrate, "loopkernel", raising=False)
    monkeypatch.setitem(sys.modules, "pfaff.integrate.loopkernel", None)  # import fails
    b = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0, 3), t_eval=te)
    assert b.stats["stepping"] == "python"
    assert b.stats["stepping_reason"] == "numba is not installed"
    agree(a, b)


def test_where_it_does_not_apply(pendulum: pfaff.NumericModel) -> None:
    """RK45, Baumgarte and user events stay on the Python path."""
    for kw in (
        {"integrator": "RK45"},
        {"method": "baumgarte"},
        {"events": [pfaff.Event(lambda t, q, qd: q[0], "x")]},
    ):
        tr = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0, 0.5), **kw)
        assert tr.stats["stepping"] == "python" and tr.status == "success"


def test_ctrl_c_keeps_what_the_loop_recorded(
    pendulum: pfaff.NumericModel, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C between two calls of the loop: status "interrupted", the states recorded so far
    (every step of the first call) kept, on the constraints."""
    real, calls = loop.CompiledLoop.advance, []

    def advance(self: loop.CompiledLoop, run: object, k: int, work: float) -> object:
        calls.append(k)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(self, run, k, work)

    monkeypatch.setattr(loop.CompiledLoop, "advance", advance)
    tr = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0, 50))
    assert tr.status == "interrupted" and tr.stats["stepping"] == "compiled loop"
    assert len(tr.t) == tr.stats["steps"] + 1 > 2 and tr.t[-1] < 50
    assert np.abs(tr.constraint_residual).max() <= 1e-10


def test_a_shipped_model_steps_in_the_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """A model pickled right after it is compiled (how a sweep ships it to its workers) steps in
    the compiled loop, as the model it was pickled from does, with the same results: the
    pushed chain (the loop's work integral) and the pendulum (its constraint code)."""
    import pickle

    eom = pfaff.models.n_link_pendulum_on_cart(2).equations()
    values = {str(p): 1.0 + 0.05 * i for i, p in enumerate(eom.parameters)}
    cases = [
        (eom.compile(values | {"g": 9.81, "F": 0.7}), [0.0, 0.3, 0.5], [0.0, 0.0, 0.0]),
        (pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2}),
         [2.0, 0.0], [0.0, 0.0]),
    ]  # fmt: skip
    te = np.linspace(0.0, 2.0, 5)
    for model, q0, qd0 in cases:
        shipped = pickle.loads(pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL))
        a, b = both(monkeypatch, shipped, q0, qd0, (0, 2), t_eval=te)
        agree(a, b)
        c = pfaff.simulate(model, q0, qd0, (0, 2), t_eval=te)
        assert c.stats["stepping"] == "compiled loop"
        np.testing.assert_allclose(a.q, c.q, rtol=1e-12, atol=1e-12)
