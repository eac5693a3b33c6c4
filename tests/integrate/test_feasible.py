"""IDA's dense Newton matrix: a size that cannot finish is refused before running, with the
estimate (pfaff.integrate.feasible)."""

from __future__ import annotations

import re

import pytest

import pfaff
from pfaff.integrate import feasible


def test_the_estimate_is_the_measured_constant_times_size_cubed() -> None:
    # the ring of 2048 members: 2n + m + m_h unknowns (n = 2049, m = m_h = 2048)
    size = 2 * 2049 + 2 * 2048
    seconds = feasible.FACTORIZATIONS * feasible.SECONDS_PER_CUBE * size**3
    assert feasible.ida_estimate(size) == pytest.approx(seconds, rel=1e-12)
    with pytest.raises(pfaff.OptionError, match=r"method 'ida' on 2049 coordinates .* h or more"):
        feasible.refuse_dense_ida(size, 2049)
    feasible.refuse_dense_ida(2 * 7 + 2 * 6, 7)  # the six-member ring: nothing to refuse


def test_simulate_refuses_before_running_with_the_estimate(monkeypatch) -> None:
    n = 6
    model = pfaff.models.rolling_ring(n, force=True).equations().compile({"M": 1, "r": 0.5, "F": 2})
    q0, qd0 = pfaff.models.ring_state(n, 0.5, theta=0.2, theta_dot=1.0)
    size = 2 * (n + 1) + 2 * n
    monkeypatch.setattr(feasible, "LIMIT_SECONDS", feasible.ida_estimate(size) / 2)
    estimate = f"{feasible.ida_estimate(size) / feasible.FACTORIZATIONS:.3g} s"
    with pytest.raises(
        pfaff.OptionError, match=f"{size} unknowns.*about {re.escape(estimate)} each"
    ):
        pfaff.simulate(model, q0, qd0, (0.0, 1.0), method="ida")
    monkeypatch.setattr(feasible, "LIMIT_SECONDS", feasible.ida_estimate(size) * 2)
    assert pfaff.simulate(model, q0, qd0, (0.0, 0.1), method="ida").status == "success"
