"""pfaff.fit against opty on opty's identification example, the Vyasarayani pendulum.

The data (``tests/data/vyasarayani_pendulum.csv``, made once by ``tests/data/make_vyasarayani.py``
with seed 20110411): ÿ₁ = −p sin y₁, p = 10, y₁(0) = π/6, ẏ₁(0) = 0, 5000 samples on [0, 50] s,
noise σ = 0.05 on the angle (the fitted channel) and 0.1 on the rate. In pfaff it is the damped
pendulum with m = l = 1, c = 0, so p = g.

The reference is opty's estimate on that file, computed in the session that committed it
(opty 1.5.0, cyipopt 1.7.0, IPOPT 3.11.9; ``benchmarks/fit.py`` computes it again when opty is
installed): opty's direct collocation (midpoint rule, 5000 nodes, the measured angle and rate
as the guess of the trajectories, p guessed 50) minimising Σ (y₁ − y₁,measured)² gave
p = 9.998575673543222 with y₁(0) = 0.5222907, y₂(0) = −0.0091267.

pfaff fits the same three unknowns (g and the initial angle and rate) by single shooting with exact
sensitivities. A single shot from a guess far from 10 ends in one of the example's many local
minima (the paper's point), so the guess is carried through windows of growing length (0.5, 2, 10
and 50 s), each fit starting from the last estimates.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pfaff

DATA = Path(__file__).parents[1] / "data" / "vyasarayani_pendulum.csv"
OPTY_P = 9.998575673543222  # opty 1.5.0 on DATA (see the module docstring)
OPTY_START = (0.5222907, -0.0091267)
WINDOWS = (0.5, 2.0, 10.0, 50.0)


def fit_in_windows(model, t, angle, guess: float):
    """pfaff.fit of (g, θ(0), θ̇(0)) on the data up to each window's end, the last one on all."""
    est = {"g": guess, "q0.theta": float(angle[0]), "qd0.theta": 0.0}
    for end in WINDOWS:
        k = t <= end + 1e-9
        res = pfaff.fit(
            model.with_parameters({"g": est["g"]}), t[k], angle[k], est, ["theta"],
            [angle[0]], [0.0], bounds={"g": (1e-3, None)}, rtol=1e-8, atol=1e-12,
        )  # fmt: skip
        est = res.estimates
    return res


@pytest.mark.slow
def test_estimate_agrees_with_opty():
    """pfaff's p within 1e-3 relative of opty's, from a guess five times too large.

    The two differ by the midpoint rule's frequency lag: its discrete oscillation of
    ÿ = −ω² y turns by 2 atan(ωh/2) ≈ ωh(1 − ω²h²/12) a step, so to match the measured
    frequency opty must raise p by about ω²h²/6 relative (ω² ≈ p, h = 50/4999 s): 1.67e-4. The
    pendulum's amplitude (0.52 rad) lowers the effective ω² by a few per cent, so the gap is
    checked to lie between 0.75 and 1.0 of p h²/6.
    """
    t, angle, _ = np.loadtxt(DATA, delimiter=",", skiprows=1).T
    model = (
        pfaff.models.damped_pendulum()
        .equations()
        .compile({"m": 1.0, "l": 1.0, "g": 50.0, "c": 0.0})
    )
    res = fit_in_windows(model, t, angle, 50.0)
    assert res.status == "success"
    p = res.estimates["g"]
    assert p == pytest.approx(OPTY_P, rel=1e-3)
    h = (t[-1] - t[0]) / (len(t) - 1)
    lag = OPTY_P / p - 1
    assert 0.75 * p * h**2 / 6 < lag < p * h**2 / 6, lag
    assert res.estimates["q0.theta"] == pytest.approx(OPTY_START[0], abs=1e-4)
    assert res.estimates["qd0.theta"] == pytest.approx(OPTY_START[1], abs=1e-4)
    # the truth within 3 reported standard errors, the residual RMS the noise's 0.05
    assert abs(p - 10.0) < 3 * res.standard_errors["g"]
    assert np.sqrt(np.mean(res.residuals**2)) == pytest.approx(0.05, rel=0.05)
