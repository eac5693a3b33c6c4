"""IDA's Newton matrices, dense and (families) sparse: a size that cannot finish is refused
before running, with the estimate (pfaff.integrate.feasible)."""

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


def test_a_family_is_refused_by_its_sparse_estimate_and_a_benchmark_size_is_not() -> None:
    """The ring of 2^24 particles (4N + 2 unknowns) needs more memory than the estimate allows
    anywhere below ~180 GiB; 2^16, which benchmarks/ida_ring.py runs, is accepted."""
    n = 2**24
    size = 4 * n + 2
    seconds, nbytes = feasible.sparse_ida_estimate(size)
    assert nbytes == pytest.approx(feasible.SPARSE_BYTES_PER_UNKNOWN * size, rel=1e-12)
    assert seconds == pytest.approx(
        feasible.FACTORIZATIONS * feasible.SPARSE_SECONDS_PER_UNKNOWN * size, rel=1e-12
    )
    with pytest.raises(pfaff.OptionError, match=rf"{n + 1} coordinates .*{size} unknowns.* GiB"):
        feasible.refuse_sparse_ida(size, n + 1)
    feasible.refuse_sparse_ida(4 * 2**16 + 2, 2**16 + 1)


def test_a_family_runs_sparse_and_is_refused_by_time_with_its_estimate(monkeypatch) -> None:
    n = 16
    model = pfaff.models.rolling_ring(n, force=True, family=True).equations()
    model = model.compile({"M": 1, "r": 0.5, "F": 2})
    q0, qd0 = pfaff.models.ring_state(n, 0.5, theta=0.2, theta_dot=1.0)
    size = 4 * n + 2
    seconds = feasible.sparse_ida_estimate(size)[0]
    monkeypatch.setattr(feasible, "LIMIT_SECONDS", seconds / 2)
    each = f"{seconds / feasible.FACTORIZATIONS:.3g} s"
    with pytest.raises(pfaff.OptionError, match=f"{size} unknowns.*about {re.escape(each)} each"):
        pfaff.simulate(model, q0, qd0, (0.0, 1.0), method="ida")
    monkeypatch.setattr(feasible, "LIMIT_SECONDS", seconds * 2)
    traj = pfaff.simulate(model, q0, qd0, (0.0, 0.1), method="ida", t_eval=[0.0, 0.1])
    assert traj.status == "success" and traj.stats["njev"] > 0  # (the sparse path's count)
    assert traj.q[-1, 1] == pytest.approx(0.2 + 0.1 + 0.5 * 2.0 * 0.01, rel=1e-7)  # θ̈ = F/(2Mr)
