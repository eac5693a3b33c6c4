"""IDA on a family (the sparse GGL Newton matrix of pfaff.numeric.ggl) against the pushed
ring's closed forms, the projection method and IDA's dense path."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff

pytestmark = pytest.mark.slow  # (whole runs: a second each on an idle machine)

M_, R_, F_ = 1.3, 0.5, 2.0


def _ring(n: int):
    ring = pfaff.models.rolling_ring(n, force=True, family=True)
    return ring.equations().compile({"M": M_, "r": R_, "F": F_})


def _run(model, n: int, **kw):
    q, qd = pfaff.models.ring_state(n, radius=R_, theta=0.3, theta_dot=0.8)
    return pfaff.simulate(model, q, qd, (0.0, 1.0), method="ida", t_eval=[0.0, 0.5, 1.0], **kw)


@pytest.mark.parametrize("n", [16, 64])
def test_ida_on_the_ring_follows_the_closed_form(n: int) -> None:
    """θ̈ = F/(2Mr), ẍ = F/(2M), λ_1 = −F/2 (DESIRED: the 2Mr²θ̈ = Fr of the one-coordinate
    ring); IDA's sparse path (its Newton matrices counted) to its tolerance, and the projection
    method at the same times."""
    model = _ring(n)
    traj = _run(model, n)
    assert traj.status == "success" and traj.stats["njev"] > 0
    t = traj.t
    theta = 0.3 + 0.8 * t + 0.5 * F_ / (2 * M_ * R_) * t**2
    np.testing.assert_allclose(traj.q[:, 1], theta, rtol=1e-7)
    np.testing.assert_allclose(traj.q[:, 0], R_ * theta, rtol=1e-7)
    np.testing.assert_allclose(traj.multipliers[:, 0], -F_ / 2, rtol=1e-6)
    ref = pfaff.simulate(model, traj.q[0], traj.qd[0], (0.0, 1.0), method="projection", t_eval=t)
    np.testing.assert_allclose(traj.q, ref.q, rtol=0, atol=1e-7)
    np.testing.assert_allclose(traj.qd, ref.qd, rtol=0, atol=1e-6)


def test_sparse_and_dense_newton_matrices_agree() -> None:
    """The family's sparse path and IDA's dense one (finite-difference columns of the
    assembled blocks, asked for by ida_jacobian) give the same motion to the tolerance."""
    n = 16
    model = _ring(n)
    sparse = _run(model, n)
    dense = _run(model, n, ida_jacobian="fd")
    np.testing.assert_allclose(sparse.q, dense.q, rtol=0, atol=1e-8)
    np.testing.assert_allclose(sparse.multipliers, dense.multipliers, rtol=1e-6, atol=1e-8)


def test_the_closed_ring_takes_the_sparse_path_without_its_dependent_row() -> None:
    """A redundant row (the closed ring's last spacing): the DAE keeps the other rows
    (``model.dae_model``) and takes the sparse Newton matrix; the motion is the open ring's
    closed form, every row's residual (the left-out one's too) stays at rounding, λ_1 = −F/2,
    and the spacing multipliers are the minimum-norm ones, orthogonal to the hoop stress (the
    all-ones vector over the spacing rows). IDA's dense path (whose regularization fixes λ
    along the null space of Aᵀ) gives the same motion."""
    n = 64
    ring = pfaff.models.rolling_ring(n, force=True, family=True, closed=True)
    with pytest.warns(pfaff.RedundancyWarning):
        model = ring.equations().compile({"M": M_, "r": R_, "F": F_})
    assert not model.sparse_dae and model.dae_model.sparse_dae and model.dae_model.m == n
    q, qd = pfaff.models.ring_state(n, radius=R_, theta=0.3, theta_dot=0.8)
    kw = {"method": "ida", "t_eval": [0.0, 0.5, 1.0]}
    traj = pfaff.simulate(model, q, qd, (0.0, 1.0), **kw)
    assert traj.status == "success" and traj.stats["njev"] > 0
    assert np.abs(traj.constraint_residual).max() < 1e-10
    theta = 0.3 + 0.8 * traj.t + 0.5 * F_ / (2 * M_ * R_) * traj.t**2
    np.testing.assert_allclose(traj.q[:, 1], theta, rtol=1e-7)
    np.testing.assert_allclose(traj.multipliers[:, 0], -F_ / 2, rtol=1e-6)
    assert np.abs(traj.multipliers[:, 1:].sum(axis=1)).max() < 1e-8  # no hoop stress in it
    dense = pfaff.simulate(model, q, qd, (0.0, 1.0), ida_jacobian="fd", **kw)
    np.testing.assert_allclose(traj.q, dense.q, rtol=0, atol=1e-8)
