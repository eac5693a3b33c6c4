"""The pace of a run (pfaff.integrate.pace): a long smooth run proceeds whatever its span, a
collapse of the step size is a stall, ``max_steps`` is explicit, and a run recording every step
warns with its memory estimate while one given ``t_eval`` stays bounded."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.integrate.pace import COLLAPSE, WINDOW, Pace

MU_G = 0.3 * 9.81  # Coulomb friction per unit mass


@pytest.fixture(scope="module")
def pendulum() -> pfaff.NumericModel:
    return pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})


@pytest.fixture(scope="module")
def sliding_block() -> pfaff.NumericModel:
    """A unit mass with Coulomb friction −μ m g sign(ẋ) and nothing else."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    s.add_generalized_force(x, -MU_G * sp.sign(x.diff(pfaff.t)))
    return s.equations().compile({})


def test_steady_steps_never_stall_whatever_the_span() -> None:
    """The old rule failed a window of 2000 steps of 0.05 with 1e7 s left (2e8 steps to go);
    the pace is judged against the run's own steps, so 20 000 steady ones (with the jitter of a
    step-size controller) pass, and a collapse by 1e9 of the same history fails, named."""
    rng = np.random.default_rng(1)
    pace = Pace(t1=1e7, max_steps=None, state_bytes=None)
    t = 0.0
    for h in 0.05 * (1 + 0.3 * rng.random(20_000)):
        pace.step(t, t + h)
        t += h
    assert pace.steps == 20_000
    with pytest.raises(Exception, match="step-size collapse") as info:
        for _ in range(WINDOW):
            pace.step(t, t + 5e-11)
            t += 5e-11
    assert type(info.value).__name__ == "_RunFailure"
    # a shrink just short of the threshold is not a collapse
    slow = Pace(t1=1e7, max_steps=None, state_bytes=None)
    slow.step(0.0, 1.0)
    for k in range(3 * WINDOW):
        slow.step(1.0 + k * 20 * COLLAPSE, 1.0 + (k + 1) * 20 * COLLAPSE)


def test_long_pendulum_run_proceeds_past_the_old_stall(pendulum: pfaff.NumericModel) -> None:
    """(0, 1e7) used to stop at t ≈ 103 as "stalled"; now it goes on until ``max_steps``, with
    the energy conserved, and warns with the memory its recorded states would need."""
    with pytest.warns(pfaff.LongRunWarning, match=r"GiB of memory: pass t_eval"):
        tr = pfaff.simulate(pendulum, [1, 0], [0, 0], (0, 1e7), max_steps=2600)
    assert tr.status == "failed" and "max_steps = 2600" in tr.message
    assert tr.stats["steps"] == 2600 and len(tr.t) == 2601
    assert tr.t[-1] > 110  # past where the old rule gave up
    energy = tr.kinetic + tr.potential  # released from horizontal rest at y = 0: E = 0
    assert np.abs(energy).max() < 1e-6 * 9.81


def test_coulomb_block_stalls_at_its_stopping_time(sliding_block: pfaff.NumericModel) -> None:
    """Released at ẋ = v0, the block stops at t* = v0/(μg) after x* = v0²/(2μg); then the
    friction's sign(ẋ) chatters about ẋ = 0, the steps collapse and the run fails there."""
    v0 = 0.3
    tr = pfaff.simulate(sliding_block, [0.0], [v0], (0, 1e6), t_eval=[0.0, 1e6])
    assert tr.status == "failed"
    assert "step-size collapse" in tr.message and "sign()" in tr.message
    t_fail = float(tr.message.split("t = ")[1].split(":")[0])
    assert t_fail == pytest.approx(v0 / MU_G, abs=1e-6)


def test_max_steps_is_checked(pendulum: pfaff.NumericModel) -> None:
    for bad in (0, -3, 2.5, "10", True):
        with pytest.raises(pfaff.OptionError, match="`max_steps` must be a positive integer"):
            pfaff.simulate(pendulum, [1, 0], [0, 0], (0, 1), max_steps=bad)


def test_t_eval_keeps_a_long_run_bounded(pendulum: pfaff.NumericModel) -> None:
    """With ``t_eval`` only its times are kept: no warning, however long the span."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", pfaff.LongRunWarning)
        tr = pfaff.simulate(
            pendulum, [1, 0], [0, 0], (0, 1e7), t_eval=[0.0, 50.0, 1e7], max_steps=1200
        )
    assert "max_steps = 1200" in tr.message
    assert list(tr.t) == [0.0, 50.0]
    # the period of this pendulum released from horizontal: y(50) from an independent run
    ref = pfaff.simulate(pendulum, [1, 0], [0, 0], (0, 50.0), t_eval=[50.0])
    np.testing.assert_allclose(tr.q[1], ref.q[0], atol=1e-6)


def test_steps_below_the_ulps_of_t_stall() -> None:
    """Without any history to compare with, steps of a few ulps of t do not advance time."""
    pace = Pace(t1=2e6, max_steps=None, state_bytes=None)
    t = 1e6  # one ulp is 1.16e-10 here
    with pytest.raises(Exception, match="time no longer advances"):
        for _ in range(WINDOW):
            pace.step(t, t + 1e-7)  # 860 ulps
            t += 1e-7
