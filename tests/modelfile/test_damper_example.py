"""``examples/double_pendulum_damper.toml``: small swings decay at the rates of its linearization.

Each damped mode s = −σ ± iω of the linearization about hanging down is started alone (the
real part of its eigenvector, 0.05 rad at the larger angle) and run through the full nonlinear
equations; the logarithmic decrement of that angle's successive peaks, fitted over the run,
gives the decay rate, against −Re s (the nonlinear terms change it by O(amplitude²)).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pfaff

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "double_pendulum_damper.toml"
AMPLITUDE = 0.05  # rad


@pytest.fixture(scope="module")
def damper() -> tuple[pfaff.ModelFile, np.ndarray, np.ndarray]:
    mf = pfaff.load_model(EXAMPLE)
    eom = mf.system.equations()
    th1, th2 = eom.coordinates
    lin = eom.linearize({th1: 0, th2: 0, **mf.parameters}, [th1, th2])
    w, v = np.linalg.eig(lin.A)
    upper = w.imag > 0  # one of each conjugate pair, the slower decay first
    order = np.argsort(-w[upper].real)
    return mf, w[upper][order], v[:, upper][:, order]


def peak_decay_rate(t: np.ndarray, y: np.ndarray) -> tuple[float, int]:
    """−d ln(peak)/dt fitted over every local maximum of ``y`` (each refined by the parabola
    through its three samples); and the number of peaks."""
    i = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
    a, b, c = y[i - 1], y[i], y[i + 1]
    d = (a - c) / (2 * (a - 2 * b + c))  # offset of the vertex, in samples
    peaks, times = b - (a - c) * d / 4, t[i] + d * (t[1] - t[0])
    return -float(np.polyfit(times, np.log(peaks), 1)[0]), len(i)


@pytest.mark.parametrize(
    "mode", [pytest.param(0, marks=pytest.mark.slow, id="slow-mode"), pytest.param(1, id="fast")]
)
def test_modal_decay_rates(damper, mode: int) -> None:
    mf, s, v = damper
    s, x = s[mode], v[:, mode]
    j = int(np.argmax(np.abs(x[:2])))
    x = (AMPLITUDE * x / x[j]).real  # the mode alone, 0.05 rad at its larger angle
    sigma, period = -s.real, 2 * np.pi / s.imag
    assert sigma > 0  # the damper damps both modes
    t_end = min(5 / sigma, 40 * period)  # decayed by e^-5, or 40 periods
    ts = np.arange(0.0, t_end, period / 60)
    traj = pfaff.simulate(mf.compile(), x[:2], x[2:], (0.0, ts[-1]), t_eval=ts, rtol=1e-11)
    assert traj.status == "success"
    rate, peaks = peak_decay_rate(traj.t, traj.q[:, j])
    assert peaks >= 10
    assert rate == pytest.approx(sigma, rel=1e-2)


def test_the_file_moves_and_dissipates() -> None:
    """From its own initial state (θ1 = 1 rad, at rest) the pendulum swings, and the energy it
    loses is the damper's work (the balance T + V − E₀ − W_nc stays at the integration error)."""
    mf = pfaff.load_model(EXAMPLE)
    traj = pfaff.simulate(mf.compile(), mf.q0, mf.qd0, (0.0, 3.0), rtol=1e-10)
    assert np.ptp(traj.q[:, 0]) > 1.5  # swings through the bottom to the other side
    assert traj.nc_work[-1] < 0 and np.all(np.diff(traj.nc_work) <= 1e-12)
    assert np.abs(traj.energy_balance).max() < 1e-7 * abs(traj.energy[0])
