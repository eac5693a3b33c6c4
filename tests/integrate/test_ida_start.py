"""IDA's first step on a family (pfaff.integrate.ida.first_step) against its hand value on the
pushed ring at rest: q̈ = (F/(2M), F/(2Mr), …) and q⃛ = 0."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
from pfaff.integrate.ida import FIRST_ERROR, first_step
from pfaff.integrate.stepper import StepperOptions


def test_first_step_from_backward_eulers_local_error() -> None:
    """h₀ = √(2 ε / ‖y''‖) with y'' = [q̈, q⃛] weighted by atol + rtol |y| (RMS over q and q̇):
    the ring's accelerations do not change along its first Euler step, so q⃛ = 0."""
    n, M, r, F = 16, 1.3, 0.5, 2.0
    model = pfaff.models.rolling_ring(n, force=True, family=True).equations()
    model = model.compile({"M": M, "r": r, "F": F})
    q, qd = pfaff.models.ring_state(n, radius=r, theta=0.3)
    qdd = np.concatenate([[F / (2 * M)], np.full(n, F / (2 * M * r))])
    opts = StepperOptions(rtol=1e-9, atol=1e-11)
    scale = opts.atol + opts.rtol * np.abs(np.concatenate([q, qd]))
    norm = np.sqrt(np.mean(np.square(np.concatenate([qdd, np.zeros(n + 1)]) / scale)))
    h = first_step(model, 0.0, (q, qd, model.solve(0.0, q, qd)[0]), 1.0, opts)["first_step"]
    assert h == pytest.approx(np.sqrt(2 * FIRST_ERROR / norm), rel=1e-6)
    assert 1e-6 < h < 1e-4  # (IDA's own: 5e-12 here)
    # at most a hundredth of the span
    capped = first_step(model, 0.0, (q, qd, qdd), 1e-5, opts)["first_step"]
    assert capped == pytest.approx(1e-7, rel=1e-12)
